"""The one-way data flow of DESIGN.md: nothing imports upward."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "bvsr_cad"
LAYER = {"units": 0, "worker": 0, "parameters": 1, "models": 2, "parts": 3, "assembly": 4, "analysis": 5,
         "exporters": 6, "checks": 6, "pipeline": 7, "sim": 7, "cli": 8}


def _layer(module: str) -> int:
    return LAYER[module.split(".")[0]]


def test_nothing_imports_upward():
    bad = []
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).with_suffix("")
        parts = rel.parts
        if parts[-1] == "__init__" and len(parts) == 1:
            continue
        here = ".".join(parts)
        me = _layer(here)
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = list(parts[:-1])[: len(parts) - node.level]
                    mod = ".".join(base + ([node.module] if node.module else []))
                    targets = [mod] if mod else [n.name for n in node.names]
                elif node.module and node.module.startswith("bvsr_cad."):
                    targets = [node.module.removeprefix("bvsr_cad.")]
            elif isinstance(node, ast.Import):
                targets = [a.name.removeprefix("bvsr_cad.") for a in node.names if a.name.startswith("bvsr_cad.")]
            for t in targets:
                if t and t.split(".")[0] in LAYER and _layer(t) > me:
                    bad.append(f"{here} imports {t}")
    assert not bad, bad


def test_checks_never_build_geometry():
    for path in (PKG / "checks").rglob("*.py"):
        text = path.read_text()
        assert "build123d" not in text and "..parts" not in text and "..assembly" not in text, path.name

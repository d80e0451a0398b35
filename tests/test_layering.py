"""The one-way data flow of DESIGN.md: nothing imports upward."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "bvsr_cad"
LAYER = {"_deferred": 0, "units": 0, "colors": 0, "worker": 0, "parameters": 1, "models": 2, "parts": 3, "assembly": 4, "analysis": 5,
         "exporters": 6, "checks": 6, "cache": 6, "publish": 7, "pipeline": 7, "analyses_process": 7, "sim": 7, "sim_gpu": 7, "api": 7, "sweep": 7, "watch": 8, "cli": 8}


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


#: Calls that write a file (or a picture) to disk.
WRITERS = ("write_text", "write_bytes", "savefig", "screenshot", "export_stl", "export_step", "Write", "mkdir", "copyfile",
           "rename", "unlink", "rmtree", "mkstemp", "mkdtemp")


def test_nothing_below_the_exporters_writes_a_file():
    """DESIGN.md: compute first, write last; the layers below exporters/ hand on objects in memory."""
    bad = []
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).with_suffix("")
        if rel.parts == ("__init__",) or _layer(".".join(rel.parts)) >= LAYER["exporters"]:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
                mode = [a.value for a in node.args[1:2] if isinstance(a, ast.Constant)] + \
                       [k.value.value for k in node.keywords if k.arg == "mode" and isinstance(k.value, ast.Constant)]
                if name in WRITERS or (name == "open" and any(set(str(m)) & set("wax") for m in mode)):
                    bad.append(f"{rel}:{node.lineno} {name}")
    assert not bad, bad

"""The one-way data flow of docs/architecture.md: every module sits in exactly one layer and
nothing imports upward."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "bvsr_cad"

#: Every top-level module and package of bvsr_cad in exactly one layer, lowest first
#: (docs/architecture.md's import direction). A module imports its own package freely and another
#: package only from a lower layer: two packages of one layer (the writers and the checks) never
#: import each other, so no layer hides an import. ``__version__`` is the package root's one value
#: read below it (its ``__init__`` imports nothing at import). ``errors`` holds the base classes of
#: the errors, below everything, so that every layer's errors can subclass them.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("error bases", ("errors",)),
    (
        "foundations",
        ("units", "colors", "folders", "extras", "defaults", "memo", "process", "__version__"),
    ),
    ("parameters", ("parameters",)),
    ("models", ("models",)),
    ("parts", ("parts",)),
    ("assembly", ("assembly",)),
    ("analysis", ("analysis",)),
    ("writers and checks", ("exporters", "checks")),
    ("simulation", ("simulation",)),
    ("pipeline", ("pipeline",)),
    ("studies", ("studies",)),
    ("Python API", ("api",)),
    ("command line", ("cli",)),
    ("python -m bvsr_cad", ("__main__",)),
)
LAYER = {name: rank for rank, (_layer, names) in enumerate(LAYERS) for name in names}


def _top(module: str) -> str:
    return module.split(".")[0]


def _imports(path: Path) -> list[str]:
    """The bvsr_cad modules ``path`` imports (anywhere in it: inside a function too), as dotted
    names under the package."""
    parts = path.relative_to(PKG).with_suffix("").parts
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(parts[:-1])[: len(parts) - node.level]
                if node.module:
                    out.append(".".join(base + [node.module]))
                else:  # from . import x: each name is a module or a value of the package
                    out += [".".join(base + [n.name]) for n in node.names]
            elif node.module and node.module.startswith("bvsr_cad."):
                out.append(node.module.removeprefix("bvsr_cad."))
            elif node.module == "bvsr_cad":
                out += [n.name for n in node.names]
        elif isinstance(node, ast.Import):
            out += [
                a.name.removeprefix("bvsr_cad.")
                for a in node.names
                if a.name.startswith("bvsr_cad.")
            ]
    return out


def _modules() -> list[Path]:
    return [
        p
        for p in sorted(PKG.rglob("*.py"))
        if "__pycache__" not in p.parts and p.relative_to(PKG) != Path("__init__.py")
    ]


def upward_imports() -> list[str]:
    bad = []
    for path in _modules():
        here = ".".join(path.relative_to(PKG).with_suffix("").parts)
        for target in _imports(path):
            there = _top(target)
            if there == _top(here) or not there:
                continue
            if there not in LAYER:
                bad.append(f"{here} imports {target}, which no layer holds")
            elif LAYER[there] >= LAYER[_top(here)]:
                bad.append(
                    f"{here} imports {target}: {LAYERS[LAYER[there]][0]} is not below "
                    f"{LAYERS[LAYER[_top(here)]][0]}"
                )
    return bad


def test_every_module_sits_in_exactly_one_layer():
    names = [name for _layer, members in LAYERS for name in members]
    assert len(names) == len(set(names)), "a name in two layers"
    tops = {p.relative_to(PKG).parts[0].removesuffix(".py") for p in _modules()}
    tops |= {p.name for p in PKG.iterdir() if p.is_dir() and p.name != "__pycache__"}
    assert tops - set(names) == set(), (
        "modules in no layer: put each in LAYERS (and docs/architecture.md's table)"
    )
    assert set(names) - tops - {"__version__"} == set(), "layers name modules that are gone"


def test_nothing_imports_upward():
    bad = upward_imports()
    assert not bad, bad


def test_checks_never_build_geometry():
    for path in (PKG / "checks").rglob("*.py"):
        text = path.read_text()
        assert "build123d" not in text and "..parts" not in text and "..assembly" not in text, (
            path.name
        )


#: Calls that write a file (or a picture) to disk.
WRITERS = (
    "write_text",
    "write_bytes",
    "savefig",
    "screenshot",
    "export_stl",
    "export_step",
    "Write",
    "mkdir",
    "copyfile",
    "rename",
    "unlink",
    "rmtree",
    "mkstemp",
    "mkdtemp",
)


def test_nothing_below_the_exporters_writes_a_file():
    """docs/architecture.md: compute first, write last; the layers below exporters/ hand on objects
    in memory."""
    bad = []
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).with_suffix("")
        if rel.parts == ("__init__",) or LAYER[rel.parts[0]] >= LAYER["exporters"]:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
                mode = [a.value for a in node.args[1:2] if isinstance(a, ast.Constant)] + [
                    k.value.value
                    for k in node.keywords
                    if k.arg == "mode" and isinstance(k.value, ast.Constant)
                ]
                if name in WRITERS or (
                    name == "open" and any(set(str(m)) & set("wax") for m in mode)
                ):
                    bad.append(f"{rel}:{node.lineno} {name}")
    assert not bad, bad


def _process_settings(tree: ast.AST) -> list[tuple[int, str]]:
    """Where a module sets something of its process: an environment variable, the garbage
    collector, the allocator, the import system, OCCT's thread pool."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if isinstance(t, ast.Subscript) and ast.unparse(t.value) == "os.environ":
                    found.append((node.lineno, ast.unparse(t)))
        elif isinstance(node, ast.Call):
            call = ast.unparse(node.func)
            if call in (
                "os.environ.setdefault",
                "os.environ.update",
                "os.putenv",
                "gc.disable",
                "gc.freeze",
                "gc.set_threshold",
                "sys.meta_path.insert",
                "sys.meta_path.append",
            ) or call.endswith(("mallopt", "DefaultPool_s")):
                found.append((node.lineno, call))
    return found


def test_process_settings_live_in_one_module():
    """bvsr_cad/process/ alone sets a process's environment, collector, allocator, import system or
    OCCT's threads (docs/architecture.md); the others call it."""
    bad = [
        f"{path.relative_to(PKG)}:{line} {what}"
        for path in _modules()
        if path.relative_to(PKG).parts[0] != "process"
        for line, what in _process_settings(ast.parse(path.read_text()))
    ]
    assert not bad, bad
    found = {
        what
        for path in (PKG / "process").glob("*.py")
        for _line, what in _process_settings(ast.parse(path.read_text()))
    }
    # the scan sees each kind of setting the package makes (a scan that saw nothing would pass)
    assert {"gc.disable", "gc.freeze", "sys.meta_path.insert"} <= found, found
    for kind in ("os.environ", "OSD_ThreadPool.DefaultPool_s", "mallopt"):
        assert any(kind in w for w in found), (kind, found)


def test_writers_and_checks_import_no_process_setting():
    """A writer or a check receives products and writes or judges them: it neither tunes the
    process nor imports what does."""
    bad = [
        f"{path.relative_to(PKG)} imports {target}"
        for path in _modules()
        if path.relative_to(PKG).parts[0] in ("exporters", "checks")
        for target in _imports(path)
        if _top(target) == "process"
    ]
    assert not bad, bad


def test_writers_and_checks_keep_no_memo_of_their_own():
    """A writer's or a check's slow step goes through the memo it is handed (bvsr_cad.memo.Memo,
    docs/architecture.md's table of memos): none decorates a function with a cache of its own."""
    bad = []
    for path in _modules():
        if path.relative_to(PKG).parts[0] not in ("exporters", "checks"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                for dec in node.decorator_list:
                    name = ast.unparse(dec.func if isinstance(dec, ast.Call) else dec)
                    if name.rsplit(".", 1)[-1] in ("lru_cache", "cache", "remembered"):
                        bad.append(f"{path.relative_to(PKG)}:{node.lineno} @{name}")
    assert not bad, bad

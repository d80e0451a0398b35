"""MkDocs hook: the pages' generated tables, made at docs build time from the code and its data.

A page asks for a table with a marker line, ``<!-- generated: NAME -->``, which this hook replaces:

- ``parameters``: every key of the parameter schema (``bvsr_cad/parameters/data/schema.toml``
  through the dataclasses of ``bvsr_cad.parameters.tables``) with its unit, default, allowed values
  and the cached build stages (so the outputs) that read it;
- ``export-files``, ``manifest-keys``: every file of an export and every key of its manifest;
- ``paper-checks``, ``paper-table``: the paper's figures against the model's (the export's
  ``paper:`` checks and its ``analysis/measurements.json``).

The export is the one named by ``$BVSR_DOCS_EXPORT``, else the committed summary of the default
build, ``docs/data/export_summary.json`` (``python docs/hooks/generate.py EXPORT`` writes it;
``tests/test_docs.py`` compares its structure with a fresh build).

Nothing in these tables is typed by hand, so they cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import typing
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parents[1]
MARKER = re.compile(r"^<!-- generated: ([a-z-]+) -->$", re.MULTILINE)

#: A key's unit, read from the end of its name (the project's names carry their unit); the longest
#: suffix that matches wins.
UNIT_SUFFIXES = {
    "_mm": "mm",
    "_mm2": "mm²",
    "_m": "m",
    "_deg": "deg",
    "_deg_s": "deg/s",
    "_s": "s",
    "_kg": "kg",
    "_kpa": "kPa (gauge)",
    "_kpa_abs": "kPa (absolute)",
    "_mpa": "MPa",
    "_g_cm3": "g/cm³",
    "_k": "K",
    "_n_per_m": "N/m",
    "_n_per_m_per_kpa": "N/m per kPa",
    "_n_s_per_m": "N s/m",
    "_n_mm2": "N mm²",
    "_l_s_bar": "dm³/(s bar)",
    "_percent": "%",
    "_thread": "mm (metric size)",
    "_mm3": "mm³",
    "_cm3": "cm³",
    "_g": "g",
    "_m2": "m²",
    "_rad": "rad",
    "_seconds": "s",
    "_nm_rad": "N m/rad",
    "_kg_m2": "kg m²",
}
#: Keys without a unit: counts, names, choices, ratios.
UNITLESS = "—"

#: The cached stages of a build, what each produces and which parameters it reads: every table of
#: the parameters but its ``*_IGNORE`` tuple in ``bvsr_cad.pipeline.stages`` (read there, never
#: copied), plus the keys handed to its cache key beside them. A key that no stage reads still moves
#: what every build writes afresh (manifest, robot descriptions, BOM, print jobs, checks, report).
STAGES = (
    ("part files", "PART_FILES_IGNORE", ("vertebra.material",), "`step/`, `stl/`, part previews"),
    (
        "geometry analyses",
        "ANALYSIS_GEOMETRY_IGNORE",
        ("vertebra.material", "analysis.min_clearance_mm"),
        "joint limits, clearance map",
    ),
    (
        "analyses",
        "ANALYSES_IGNORE",
        ("fabrication_package.tube_lead_mm", "fabrication_package.tube_bend_allowance"),
        "`analysis/`, joint limits of `robot/`",
    ),
    ("drawings", "DRAWINGS_IGNORE", ("vertebra.material",), "`drawings/`"),
    ("rigid twin", "TWIN_IGNORE", ("vertebra.material",), "rigid twin pieces, `robot/*_rigid.*`"),
    (
        "robot meshes",
        "ROBOT_GEOMETRY_IGNORE",
        ("vertebra.material", "robot.collision_geometry"),
        "`robot/` meshes and collision shapes",
    ),
)
#: The mold set reads its arguments (``bvsr_cad.assembly.products.mold_set_inputs``): the SOA's
#: table, the flange diameter and the casting allowances.
MOLD_READS = ("soa", "joint.base_diameter_mm", "casting")


def unit_of(name: str) -> str:
    """The unit a key's name carries, or an em dash for a count, a name or a choice."""
    best = max((s for s in UNIT_SUFFIXES if name.endswith(s)), key=len, default=None)
    return UNIT_SUFFIXES[best] if best else UNITLESS


def _number(x: Any) -> str:
    return str(int(x)) if isinstance(x, (int, float)) and float(x).is_integer() else format(x, "g")


def allowed_text(meta: typing.Mapping[str, Any]) -> str:
    """What a key allows, as the loader's error messages say it."""
    if meta.get("choices"):
        return "one of " + ", ".join(f"`{c!r}`" for c in meta["choices"])
    bounds = [
        f"{sym} {_number(meta[k])}"
        for k, sym in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤"))
        if meta.get(k) is not None
    ]
    return " and ".join(bounds) if bounds else "any"


def _reads(stage_ignore: tuple[str, ...], extra: tuple[str, ...], key: str) -> bool:
    table = key.split(".")[0]
    if key in extra or table in extra:
        return True
    return table not in stage_ignore and ".".join(key.split(".")[:2]) not in stage_ignore


def stage_readers(key: str) -> list[str]:
    """The cached stages whose inputs include ``key`` (dotted, as in a parameter file)."""
    pipeline = _pipeline()
    moved = [
        name
        for name, ignore, extra, _outputs in STAGES
        if _reads(getattr(pipeline, ignore), extra, key)
    ]
    table = key.split(".")[0]
    if table in MOLD_READS or ".".join(key.split(".")[:2]) in MOLD_READS:
        moved.append("mold set")
    return moved


def _pipeline() -> Any:
    """The module that declares the stages' ignore lists (the build's stage list)."""
    import importlib

    for name in ("bvsr_cad.pipeline.stages",):
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name not in (name, name.rpartition(".")[0]):
                raise
            continue
        if all(hasattr(module, ignore) for _n, ignore, _e, _o in STAGES):
            return module
    raise RuntimeError(
        "docs/hooks/generate.py: no module declares the stages' ignore lists "
        f"({', '.join(i for _n, i, _e, _o in STAGES)}); update STAGES to the build's stage list"
    )


def _default_file_values() -> dict[str, Any]:
    import tomllib

    data = tomllib.loads((DOCS.parent / "params" / "bvsr.toml").read_text(encoding="utf-8"))

    def flat(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in d.items():
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
        return out

    return flat(data)


def parameter_rows() -> list[dict[str, str]]:
    """One row per schema key, in the order of the dataclasses (``materials.<key>``: any material
    name)."""
    from bvsr_cad.parameters.tables import _SCHEMA, TailSpec

    shipped = _default_file_values()
    rows: list[dict[str, str]] = []

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            key, typ = f"{prefix}{f.name}", hints[f.name]
            if dataclasses.is_dataclass(typ):
                walk(typ, key + ".")
                continue
            if typing.get_origin(typ) is dict:  # the material table: one entry per material name
                walk(typing.get_args(typ)[1], key + ".<name>.")
                continue
            if f.metadata.get("keys"):  # named numbers, each with its own rule
                for name, rule in _SCHEMA[f.metadata["keys"]].items():
                    rows.append(row(f"{key}.{name}", name, rule, None))
                continue
            rows.append(row(key, f.name, f.metadata, f.default))

    def row(key: str, name: str, meta: typing.Mapping[str, Any], default: Any) -> dict[str, str]:
        if default is dataclasses.MISSING or default is None:
            in_file = shipped.get(key.replace("<name>.", "PA12_MJF."))
            default_text = (
                f"required (`bvsr.toml`: `{in_file!r}`)" if in_file is not None else "required"
            )
        else:
            default_text = f"`{default!r}`" if default != "" else "empty"
        allowed = allowed_text(meta)
        if meta.get("depends_on"):  # the keys whose values narrow the range further (schema.toml)
            allowed += "; narrowed by " + ", ".join(f"`{k}`" for k in meta["depends_on"])
        return {
            "key": key,
            "unit": unit_of(name),
            "default": default_text,
            "allowed": allowed,
            "doc": meta.get("doc", ""),
            "moves": ", ".join(stage_readers(key)) or "none",
        }

    walk(TailSpec, "")
    return rows


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def parameters_markdown() -> str:
    """The parameter reference: one table per parameter-file table."""
    out: list[str] = []
    current = None
    for r in parameter_rows():
        table = r["key"].split(".")[0] if "." in r["key"] else "(top level)"
        if table != current:
            current = table
            heading = table if table == "(top level)" else f"[{table}]"
            out += [
                "",
                f"### {heading}",
                "",
                "| key | unit | default | allowed | what it is | cached stages it moves |",
                "|---|---|---|---|---|---|",
            ]
        out.append(
            "| "
            + " | ".join(
                _cell(c)
                for c in (
                    f"`{r['key']}`",
                    r["unit"],
                    r["default"],
                    r["allowed"],
                    r["doc"],
                    r["moves"],
                )
            )
            + " |"
        )
    return "\n".join(out) + "\n"


def _fmt(x: Any) -> str:
    if x is None or (isinstance(x, float) and x != x):  # None or NaN: nothing predicted
        return "—"
    if isinstance(x, float):
        return format(x, ".4g")
    return str(x)


def paper_table_markdown(data: dict[str, Any] | None = None) -> str:
    """The paper's figures beside the model's, row by row, from an export's
    ``measurements.json``."""
    data = data if data is not None else _summary()["measurements"]
    out = [
        "| row | quantity | role | unit | paper | model, tables' values | model, fitted | error, "
        "fitted | source |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["rows"]:
        unit = "" if r.get("unit") in (None, "1") else r["unit"]
        rel = r.get("rel_calibrated")
        cells = (
            r["row"],
            r["label"],
            r["role"],
            unit,
            _fmt(r["reported"]),
            _fmt(r.get("uncalibrated")),
            _fmt(r.get("calibrated")),
            "—" if rel is None or rel != rel else f"{rel:+.0%}",
            r.get("source", ""),
        )
        out.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    summary = {
        k: v
        for k, v in data.items()
        if k not in ("rows", "note", "data_file") and not isinstance(v, (dict, list))
    }
    out += ["", "| over the rows | value |", "|---|---|"]
    out += [f"| `{k}` | {_cell(_fmt(v))} |" for k, v in summary.items()]
    out += [
        "",
        "Fitted values: "
        + ", ".join(f"`{k}` = {_fmt(v)}" for k, v in data.get("fitted", {}).items()),
        "",
        f"Build note: {data.get('note', '')}",
    ]
    return "\n".join(out) + "\n"


EXPORT_SUMMARY = DOCS / "data" / "export_summary.json"
#: The manifest's tables whose keys are names the build chose (a file, a joint, a pressure line, an
#: MJCF model, a BOM total), by path, and the placeholder their keys read as in the reference. Every
#: other key is printed as it is written.
NAME_KEYED = {
    "robot.chains": "<file>",
    "robot.joint_limits": "<joint>",
    "robot.supply_lag_s": "<line>",
    "robot.mjcf_actuators": "<model>",
    "bom.totals": "<total>",
}
#: Numbers in the manifest whose name carries no unit, by their generalised path (see
#: :func:`manifest_keys`).
MANIFEST_UNITS = {
    "parts[].print_transform": "4 x 4 transform, mm",
    "parts[].tail_transform": "4 x 4 transform, mm",
    "molds.parts[].print_transform": "4 x 4 transform, mm",
    "assembly.instances[].transform": "4 x 4 transform, mm",
    "checks[].value": "`checks[].unit`",
    "checks[].limit": "`checks[].unit`",
    "molds.scale": "ratio (1 + shrinkage)",
    "molds.parts[].pull_direction": "unit vector",
    "molds.parts[].parting_planes[].point": "mm",
    "molds.parts[].parting_planes[].normal": "unit vector",
    "rigid_tail.mass_g_solid": "g",
    "bom.totals.<total>.quantity": "`bom.totals.<total>.unit`",
    "robot.chains.<file>.bend_limit.max_overshoot": "fraction of theta_max",
    "robot.joint_limits.<joint>.lower": "rad (m for `*_chord`)",
    "robot.joint_limits.<joint>.upper": "rad (m for `*_chord`)",
    "robot.joint_limits.<joint>.velocity": "rad/s (m/s for `*_chord`)",
    "robot.joint_limits.<joint>.effort": "N m (N for `*_chord`)",
    "viewer.bytes": "bytes",
    "viewer.scenes[].bytes": "bytes",
    "scenes.files[].bytes": "bytes",
    "volatile.stages[].seconds": "s",
}
#: Leaf names that count things.
COUNTS = {
    "segments",
    "joints",
    "panels",
    "count",
    "quantity",
    "total_parts",
    "rows",
    "printed_parts",
    "cast_parts",
    "fasteners",
    "valves",
    "holes",
    "objects",
    "triangles",
    "meshes",
    "faces",
    "joint",
    "segment",
    "nodes",
    "bodies",
    "actuators",
    "<model>",
}


def _generalise(table: str, key: str) -> str:
    """A key of a name-keyed table becomes its placeholder (:data:`NAME_KEYED`); a key that cannot
    be a field's name (a path, words with spaces) becomes ``<name>``; every other key stays as
    written."""
    if table in NAME_KEYED:
        return NAME_KEYED[table]
    return "<name>" if "/" in key or " " in key else key


def _kind(v: Any) -> str:
    if isinstance(v, bool):
        return "bool"
    if isinstance(v, (int, float)):
        return "number"
    return "null" if v is None else "text"


def manifest_keys(manifest: dict[str, Any]) -> dict[str, dict[str, str]]:
    """Every key path of a manifest (a list's items as ``[]``, a name-keyed table's keys as its
    placeholder), with its JSON type (``a or b`` where values differ, ``list of ...`` for a list of
    numbers or names), its unit and the default build's value where it is one number."""
    kinds: dict[str, set[str]] = {}
    example: dict[str, Any] = {}

    def note(path: str, kind: str, value: Any) -> None:
        kinds.setdefault(path, set()).add(kind)
        if path not in example or example[path] is None:
            example[path] = value

    def walk(v: Any, path: str) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                g = _generalise(path, k)
                walk(x, f"{path}.{g}" if path else g)
            if not v:
                note(path, "object", None)
        elif isinstance(v, list):
            if v and not any(isinstance(x, (dict, list)) for x in v):  # numbers or names
                inner = " or ".join(sorted({_kind(x) for x in v}))
                note(path, f"list of {inner}", v[0])
                return
            for x in v:
                walk(x, path + "[]")
            if not v:
                note(path, "list", None)
        else:
            note(path, _kind(v), v)

    walk(manifest, "")
    out = {}
    for path in sorted(kinds):
        if kinds[path] == {"list"} and any(k.startswith(path + "[]") for k in kinds):
            continue  # a list empty here and filled elsewhere: its items' keys describe it
        kind = _either(kinds[path])
        number = "number" in kind
        value = example[path]
        volatile = path.startswith("volatile.")  # differs from build to build: no example
        out[path] = {
            "type": kind,
            "unit": manifest_unit(path) if number else "",
            "example": _fmt(value)
            if number and isinstance(value, (int, float)) and not volatile
            else "",
        }
    return out


def _either(kinds: set[str]) -> str:
    """``a, b or c``, single values first, lists last."""
    ordered = sorted(kinds, key=lambda k: (k.startswith("list"), k))
    return (
        " or ".join(ordered) if len(ordered) < 3 else ", ".join(ordered[:-1]) + " or " + ordered[-1]
    )


def manifest_unit(path: str) -> str:
    """The unit of a number in the manifest: from the table above, else its name or its table's
    name."""
    bare = re.sub(r"(\[\])+$", "", path)
    if bare in MANIFEST_UNITS:
        return MANIFEST_UNITS[bare]
    for part in reversed(bare.replace("[]", "").split(".")):
        if unit_of(part) != UNITLESS:
            return unit_of(part)
    return "count" if bare.replace("[]", "").rsplit(".", 1)[-1] in COUNTS else "?"


def export_files(export: Path) -> dict[str, list[str]]:
    """The export's files by folder (the tail's own name replaced by ``<name>``)."""
    name = json.loads((export / "manifest.json").read_text(encoding="utf-8"))["name"]
    folders: dict[str, list[str]] = {}
    for f in sorted(p for p in export.rglob("*") if p.is_file()):
        rel = f.relative_to(export).as_posix().replace(f"{name}_description", "<name>_description")
        folder, _, file = rel.rpartition("/")
        file = re.sub(rf"^{re.escape(name)}(?=[_.])", "<name>", file)
        folders.setdefault(folder or ".", []).append(file)
    return folders


def export_summary(export: Path) -> dict[str, Any]:
    """What the docs read from one export: its files, its manifest's keys, the paper checks, the
    measurements."""
    manifest = json.loads((export / "manifest.json").read_text(encoding="utf-8"))
    return {
        "params_sha256": manifest["params_sha256"],
        "files": export_files(export),
        "manifest_keys": manifest_keys(manifest),
        "paper_checks": [c for c in manifest["checks"] if c["name"].startswith("paper:")],
        "measurements": json.loads(
            (export / "analysis" / "measurements.json").read_text(encoding="utf-8")
        ),
    }


def _summary() -> dict[str, Any]:
    """The export the pages describe: ``$BVSR_DOCS_EXPORT`` (an export folder, read as it is) if
    set, else the committed summary of the default build."""
    export = os.environ.get("BVSR_DOCS_EXPORT")
    if export:
        return json.loads(json.dumps(export_summary(Path(export))))
    return json.loads(EXPORT_SUMMARY.read_text(encoding="utf-8"))


def export_files_markdown() -> str:
    """Every file of the default export, by folder."""
    out = ["| folder | files |", "|---|---|"]
    for folder, files in _summary()["files"].items():
        out.append(f"| `{folder}/` | " + ", ".join(f"`{_cell(f)}`" for f in files) + " |")
    return "\n".join(out) + "\n"


def manifest_markdown() -> str:
    """Every key of ``manifest.json`` with its type, unit and the default build's value."""
    out = ["| key | type | unit | default build |", "|---|---|---|---|"]
    for key, k in _summary()["manifest_keys"].items():
        out.append(f"| `{_cell(key)}` | {k['type']} | {_cell(k['unit'])} | {_cell(k['example'])} |")
    return "\n".join(out) + "\n"


def paper_checks_markdown() -> str:
    """The paper's figures the build computes beside the build's, with each difference's reason."""
    out = [
        "| figure | paper | model | unit | where in the paper | difference and reason |",
        "|---|---|---|---|---|---|",
    ]
    for c in _summary()["paper_checks"]:
        out.append(
            "| "
            + " | ".join(
                _cell(x)
                for x in (
                    f"`{c['name'].removeprefix('paper:')}`",
                    _fmt(c["limit"]),
                    _fmt(c["value"]),
                    c["unit"],
                    c["where"],
                    c["note"],
                )
            )
            + " |"
        )
    return "\n".join(out) + "\n"


#: The guide that shows each command in use (a command not named here gets no link).
CLI_GUIDES = {
    "build": "../guides/designer.md",
    "watch": "../guides/designer.md",
    "show": "../guides/designer.md",
    "init": "../guides/designer.md",
    "check": "checks.md",
    "simulate": "../guides/simulation.md",
    "mount": "../guides/simulation.md",
    "calibrate": "../guides/lab.md",
    "workspace": "../models.md",
    "clearance": "../models.md#clearance-and-joint-limits",
    "sweep": "../guides/studies.md",
}


def cli_commands() -> list[tuple[str, Any]]:
    """Every subcommand of ``bvsr`` with its parser, in the parser's order (read from
    ``bvsr_cad.cli.make_parser``, the parser the command runs)."""
    import argparse

    from bvsr_cad.cli import make_parser

    top = make_parser()
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    return list(sub.choices.items())


def cli_arguments(parser: Any) -> list[dict[str, str]]:
    """One row per argument of a parser: its name or flags, what it takes, its default, its help."""
    import argparse

    rows = []
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        names = ", ".join(a.option_strings) or (a.metavar or a.dest)
        if a.choices:
            takes = "one of " + ", ".join(f"`{c}`" for c in a.choices)
        elif a.nargs == 0:
            takes = "flag"
        else:
            takes = _takes(a.type) + (" (optional)" if a.nargs == "?" else "")
        default = a.default
        shown = (
            ""
            if default is None or default is False or default == argparse.SUPPRESS
            else f"`{default}`"
        )
        rows.append(
            {
                "argument": names,
                "takes": takes,
                "default": shown,
                "required": "yes" if a.required else "",
                "help": (a.help or "") % {"default": default} if a.help else "",
            }
        )
    return rows


def _takes(parse: Any) -> str:
    """What an argument's type accepts: ``int``, ``float`` or one of
    ``bvsr_cad.cli.parser._number``'s checked numbers (its bound read from the closure), else
    text."""
    import inspect

    names = {int: "integer", float: "number"}
    if parse in names:
        return names[parse]
    if callable(parse) and getattr(parse, "__closure__", None):
        bound = inspect.getclosurevars(parse).nonlocals
        if {"kind", "minimum", "inclusive"} <= bound.keys():
            sym = "≥" if bound["inclusive"] else ">"
            return f"{names[bound['kind']]} {sym} {_number(bound['minimum'])}"
    return "text"


def cli_markdown() -> str:
    """The command reference: every ``bvsr`` command with its usage and every argument, generated
    from the parser so that none can go missing."""
    import argparse

    out: list[str] = []
    for name, parser in cli_commands():
        parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=100)
        usage = parser.format_usage().removeprefix("usage: ").strip()
        what = _escape(parser.description or _help_of(name))
        if name in CLI_GUIDES:
            what += f" ([in use]({CLI_GUIDES[name]}))"
        out += ["", f"### `bvsr {name}`", "", what, "", "```text", usage, "```", ""]
        out += ["| argument | takes | default | what it does |", "|---|---|---|---|"]
        for r in cli_arguments(parser):
            code = _escape(r["argument"]).replace("\\|", "&#124;")  # a | would split the cell
            arg = f"<code>{code}</code>" + (" (required)" if r["required"] else "")
            cells = (arg, r["takes"], r["default"], _escape(r["help"]))
            out.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(out) + "\n"


def _escape(text: str) -> str:
    """Help text in a Markdown cell: ``<name>`` kept as text, not read as an HTML tag."""
    return _cell(text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))


def _help_of(name: str) -> str:
    """A subcommand's one-line help, as ``bvsr --help`` lists it."""
    import argparse

    from bvsr_cad.cli import make_parser

    top = make_parser()
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    return next(c.help for c in sub._choices_actions if c.dest == name)


GENERATORS = {
    "parameters": parameters_markdown,
    "paper-table": lambda: paper_table_markdown(),
    "export-files": export_files_markdown,
    "manifest-keys": manifest_markdown,
    "paper-checks": paper_checks_markdown,
    "cli": cli_markdown,
}


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """MkDocs event: replace each marker with its generated table (an unknown marker fails the
    build)."""

    def replace(m: re.Match[str]) -> str:
        if m.group(1) not in GENERATORS:
            raise ValueError(
                f"{page.file.src_path}: unknown generated table {m.group(1)!r}; known: "
                f"{sorted(GENERATORS)}"
            )
        return GENERATORS[m.group(1)]()

    return MARKER.sub(replace, markdown)


if (
    __name__ == "__main__"
):  # refresh the committed summary from an export: python docs/hooks/generate.py EXPORT
    import sys

    EXPORT_SUMMARY.write_text(
        json.dumps(export_summary(Path(sys.argv[1])), indent=1, sort_keys=True) + "\n",
        encoding="utf-8",
    )

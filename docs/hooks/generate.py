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
#: the parameters but its ``*_IGNORE`` tuple in ``bvsr_cad.build.pipeline`` (read there, never
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

    for name in ("bvsr_cad.build.pipeline",):
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
    "bom.totals.<name>.quantity": "`bom.totals.<name>.unit`",
    "robot.chains.<name>.bend_limit.max_overshoot": "fraction of theta_max",
    "robot.joint_limits.<name>.lower": "rad (m for `*_chord`)",
    "robot.joint_limits.<name>.upper": "rad (m for `*_chord`)",
    "robot.joint_limits.<name>.velocity": "rad/s (m/s for `*_chord`)",
    "robot.joint_limits.<name>.effort": "N m (N for `*_chord`)",
    "viewer.bytes": "bytes",
    "viewer.scenes[].bytes": "bytes",
    "scenes.files[].bytes": "bytes",
    "robot.supply_lag_s.<name>": "s",
    "volatile.stages[].seconds": "s",
    "volatile.cpu_seconds.<name>": "s",
    "mass_g.<name>": "g",
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
    "bvsr",
    "bvsr_segments",
    "bvsr_exact",
    "<name>",
}


def _generalise(key: str, tail_name: str) -> str:
    """A manifest key that is a name (a joint, a file, a line, a tail) becomes ``<name>``."""
    data_like = (
        any(c.isdigit() for c in key.removesuffix("_m2").removesuffix("_mm2").removesuffix("_mm3"))
        or "/" in key
        or " " in key
        or key.startswith(tail_name)
    )
    return "<name>" if data_like else key


def manifest_keys(manifest: dict[str, Any]) -> dict[str, dict[str, str]]:
    """Every key path of a manifest (lists as ``[]``, name-keyed tables as ``<name>``), with its
    JSON type, its unit and the default build's value where it is one number or short text."""
    tail = manifest.get("name", "")
    out: dict[str, dict[str, str]] = {}

    def walk(v: Any, path: str, leaf: str) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                g = _generalise(k, tail)
                walk(x, f"{path}.{g}" if path else g, g)
            if not v:
                out.setdefault(path, {"type": "object", "unit": "", "example": "{}"})
            return
        if isinstance(v, list):
            if v and all(
                not isinstance(x, (dict, list)) for x in v
            ):  # a vector of numbers or names
                walk(v[0], path, leaf)
                out[path]["type"] = "list of " + out[path]["type"]
                return
            for x in v:
                walk(x, path + "[]", leaf)
            if not v:
                out.setdefault(path + "[]", {"type": "list", "unit": "", "example": "[]"})
            return
        if path in out:
            return
        kind = (
            "number"
            if isinstance(v, (int, float)) and not isinstance(v, bool)
            else ("bool" if isinstance(v, bool) else "null" if v is None else "text")
        )
        volatile = path.startswith("volatile.")  # differs from build to build: no example
        out[path] = {
            "type": kind,
            "unit": manifest_unit(path, leaf) if kind == "number" else "",
            "example": _fmt(v) if kind == "number" and not volatile else "",
        }

    walk(manifest, "", "")
    return dict(sorted(out.items()))


def manifest_unit(path: str, leaf: str) -> str:
    """The unit of a number in the manifest: from the table above, else its name or its table's
    name."""
    bare = re.sub(r"(\[\])+$", "", path)
    if bare in MANIFEST_UNITS:
        return MANIFEST_UNITS[bare]
    for part in reversed(bare.replace("[]", "").split(".")):
        if unit_of(part) != UNITLESS:
            return unit_of(part)
    return "count" if leaf.replace("[]", "") in COUNTS else "?"


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
    """The paper's figures of SPEC section 6 beside the build's, with each difference's reason."""
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


GENERATORS = {
    "parameters": parameters_markdown,
    "paper-table": lambda: paper_table_markdown(),
    "export-files": export_files_markdown,
    "manifest-keys": manifest_markdown,
    "paper-checks": paper_checks_markdown,
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

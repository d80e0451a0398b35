"""MkDocs hook: what the user guides show that the code must keep true.

- ``images/parameter_figure.svg``: the paper's Table I and II symbols dimensioned on a joint and an
  SOA of the default tail (``params/bvsr.toml``), drawn by
  :func:`bvsr_cad.exporters.parameter_figure.parameter_figure` at every docs build (a generated file
  of the site, never committed, so it cannot fall behind the geometry);
- ``<!-- guide: measurement-quantities -->``: the lab guide's table of the quantities a
  measurements file may hold (:data:`bvsr_cad.parameters.measurements.QUANTITIES` and
  ``HOW_TO_MEASURE``), each with the fitted values it informs
  (:func:`bvsr_cad.analysis.calibrate.informed_values`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_PARAMS = ROOT / "params" / "bvsr.toml"
FIGURE_URI = "images/parameter_figure.svg"
MARKER = re.compile(r"^<!-- guide: ([a-z-]+) -->$", re.MULTILINE)


def parameter_figure_svg(params: Path = DEFAULT_PARAMS) -> bytes:
    """The designer's figure for the tail of ``params`` (SVG bytes)."""
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.exporters.parameter_figure import parameter_figure
    from bvsr_cad.parameters.load import load_spec

    return parameter_figure(build_assembly(load_spec(params), solids=False))


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def measurement_quantities_markdown(params: Path = DEFAULT_PARAMS) -> str:
    """One row per quantity: unit string, condition keys, what it is, how to measure it, and the
    fitted values a ``fit`` row of it informs (by default; with ``--fit``)."""
    from bvsr_cad.analysis.calibrate import informed_values
    from bvsr_cad.parameters.load import load_spec
    from bvsr_cad.parameters.measurements import HOW_TO_MEASURE, QUANTITIES

    spec = load_spec(params)
    missing = sorted(set(QUANTITIES) - set(HOW_TO_MEASURE))
    if missing:
        raise ValueError(f"bvsr_cad.parameters.measurements.HOW_TO_MEASURE lacks {missing}")
    out = [
        "| quantity: what it is | unit | condition keys | how to measure it "
        "| fitted value it informs |",
        "|---|---|---|---|---|",
    ]
    for name, (unit, conditions, what) in QUANTITIES.items():
        default, on_request = informed_values(spec, name)
        informs = ", ".join(f"`{v}`" for v in default) or "none (a check of the tables' values)"
        if on_request:
            informs += "; with `--fit`: " + ", ".join(f"`{v}`" for v in on_request)
        keys = ", ".join(f"`{k}`" for k in conditions)
        how = re.sub(r"``([^`]+)``", r"`\1`", HOW_TO_MEASURE[name])
        out.append(
            "| "
            + " | ".join(_cell(c) for c in (f"`{name}`: {what}", f"`{unit}`", keys, how, informs))
            + " |"
        )
    return "\n".join(out) + "\n"


GENERATORS = {"measurement-quantities": measurement_quantities_markdown}


def on_files(files: Any, config: Any) -> Any:
    """MkDocs event: add the designer's figure, drawn from the default parameters, to the site."""
    from mkdocs.structure.files import File

    files.append(File.generated(config, FIGURE_URI, content=parameter_figure_svg()))
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """MkDocs event: replace each guide marker with its generated table (an unknown one fails the
    build)."""

    def replace(m: re.Match[str]) -> str:
        if m.group(1) not in GENERATORS:
            raise ValueError(
                f"{page.file.src_path}: unknown guide table {m.group(1)!r}; known: "
                f"{sorted(GENERATORS)}"
            )
        return GENERATORS[m.group(1)]()

    return MARKER.sub(replace, markdown)

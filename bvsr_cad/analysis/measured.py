"""The model against the measurements its calibration was fitted to (the report's section).

A parameter file calibrated by `bvsr calibrate` names its data file
(``calibration.data_file``, relative to the parameter file) and the tail the
data measured (``calibration.measured_tail``). A build predicts the rows
that measured its own tail twice, with the tables' values and with the
fitted ones, exactly as `bvsr calibrate` does (:func:`bvsr_cad.analysis.calibrate.compare_rows`):

- a row whose conditions name a segment count (``segments=3``) measured a
  tail with that many segments: the build of such a tail compares it,
  whether it is the measured tail or one that takes its fitted values
  (BVSR_L takes BVSR's and compares the BVSR_L workspace row);
- a row that names none measured the calibration's tail: its build compares it.

`bvsr calibrate` fits and reports over every row. A tail with another rod,
or whose data file is missing or changed, gets a note instead of rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..assembly.assemble import Assembly
from ..parameters.measurements import Measurement, MeasurementError, data_sha256, load_measurements
from ..parameters.tables import TailSpec
from .calibrate import COMPARE_THREADS, compare_rows, rms_relative, uncalibrated
from .predict import Predictor, WorkspaceSim

#: A row "lands" when the calibrated prediction is within this relative error of the reported
#: figure.
LANDS_WITHIN_REL = 0.30


@dataclass(frozen=True)
class MeasuredComparison:
    data_file: str
    note: str  # why there are no rows, or what the rows are
    rows: list[dict] = field(default_factory=list)
    fitted: dict[str, float] = field(default_factory=dict)

    def rms(self, role: str, key: str) -> float:
        return rms_relative(self.rows, role, key)

    def landed(self, role: str = "holdout") -> tuple[int, int]:
        """(rows of ``role`` within :data:`LANDS_WITHIN_REL`, rows of ``role``)."""
        rows = [r for r in self.rows if r["role"] == role]
        return sum(abs(r["rel_calibrated"]) <= LANDS_WITHIN_REL for r in rows), len(rows)

    def to_json(self) -> dict:
        out = {
            "data_file": self.data_file,
            "note": self.note,
            "fitted": self.fitted,
            "rows": self.rows,
            "lands_within_rel": LANDS_WITHIN_REL,
        }
        roles = [role for role in ("fit", "holdout") if any(r["role"] == role for r in self.rows)]
        out |= {
            f"rms_rel_{role}{suffix}": self.rms(role, key)
            for role in roles
            for suffix, key in (("", "rel_calibrated"), ("_uncalibrated", "rel_uncalibrated"))
        }
        if "holdout" in roles:
            out["holdout_landed"] = list(self.landed("holdout"))
        return out


def compare_measurements(
    asm: Assembly,
    params_path: str | Path | None,
    progress: Callable[[str], None] | None = None,
    workspace_sim: WorkspaceSim | None = None,
    theta_max_rad: list[float] | Callable[[], list[float]] | None = None,
    threads: int = COMPARE_THREADS,
) -> MeasuredComparison | None:
    """The comparison for ``asm``'s spec, or None when the file carries no calibration.

    ``workspace_sim``: what predicts the measured tip workspace (:class:`Predictor`); the pipeline
    gives :func:`bvsr_cad.simulation.sim.protocol_radius_mm`. ``theta_max_rad``: the joints' limits
    of ``asm`` where the build has them, or what gives them when first needed (they may still be
    computing). ``threads``: as in :func:`bvsr_cad.analysis.calibrate.compare_rows`."""
    spec = asm.spec
    cal = spec.calibration
    if not cal.fitted:
        return None
    fitted = dict(cal.fitted)
    inherited = bool(cal.measured_tail) and cal.measured_tail != spec.name
    loaded = _calibration_rows(spec, params_path)
    if isinstance(loaded, str):
        return MeasuredComparison(cal.data_file, loaded, fitted=fitted)
    rows, others = rows_of_tail(loaded, spec.segments, inherited)
    if not rows:
        return MeasuredComparison(
            cal.data_file,
            _inherited_note(spec) if inherited else f"no row of {cal.data_file} measured this tail",
            fitted=fitted,
        )
    pred = Predictor(asm, spec, workspace_sim)
    if theta_max_rad is not None:
        pred.known_limits(theta_max_rad)
    table = compare_rows(
        pred.with_spec(uncalibrated(spec)),
        pred,
        rows,
        None if progress is None else (lambda m: progress(f"measurements: {m}")),
        threads,
    )
    return MeasuredComparison(cal.data_file, _rows_note(spec, inherited, others), table, fitted)


def _calibration_rows(spec: TailSpec, params_path: str | Path | None) -> list[Measurement] | str:
    """Every row of the calibration's data file, or why none is compared: a tail with another rod
    than the data measured, no data file, a missing or changed one, an unreadable one."""
    cal = spec.calibration
    rod = (spec.vertebra.material, float(spec.vertebra.diameter_mm))
    if cal.rod_material and (cal.rod_material, float(cal.rod_diameter_mm)) != rod:
        return (
            f"the data measured a tail with a {cal.rod_material} "
            f"{cal.rod_diameter_mm:g} mm rod and this file's rod is {rod[0]} {rod[1]:g} mm: "
            "another tail, so its rows are not compared (the fitted values carry over, the "
            "rod's E I by the ratio of the tables' values)"
        )
    if not cal.data_file or params_path is None:
        return "the calibration names no data file"
    data = Path(params_path).resolve().parent / cal.data_file
    if not data.is_file():
        return f"data file {data} not found (it is resolved relative to the parameter file)"
    if cal.data_sha256 and data_sha256(data) != cal.data_sha256:
        return (
            "the data file changed since the calibration (SHA-256 differs): "
            "run `bvsr calibrate` again"
        )
    try:
        return load_measurements(data)
    except MeasurementError as exc:
        return f"data file unreadable: {exc}"


def _inherited_note(spec: TailSpec) -> str:
    """Where a tail that takes another tail's fitted values finds its rows compared."""
    return (
        f"fitted values inherited from the {spec.calibration.measured_tail} tail's "
        "calibration; its report compares the rows that measured it"
    )


def _rows_note(spec: TailSpec, inherited: bool, others: list[Measurement]) -> str:
    """What the compared rows are, and where the data file's other rows are compared."""
    data_file = spec.calibration.data_file
    what = (
        f"the rows of {data_file} that measured a {spec.segments}-segment tail"
        if inherited
        else f"every row of {data_file} that measured this tail"
    )
    note = f"{what}, predicted with the tables' values and with the fitted ones"
    if inherited:
        note += f"; {_inherited_note(spec)} ({len(others)} rows)"
    elif others:
        counts = sorted({int(m.condition("segments")) for m in others})
        note += (
            f"; {_rows(others)} measured a {' or '.join(map(str, counts))}-segment tail: the build "
            "of such a "
            "tail that takes these fitted values compares them (`bvsr calibrate` fits and reports "
            "over every row)"
        )
    return note


def rows_of_tail(
    rows: list[Measurement], segments: int, inherited: bool
) -> tuple[list[Measurement], list[Measurement]]:
    """(the rows a build of a ``segments``-segment tail compares, the others): a row naming a
    segment count measured a tail with that many segments; one naming none measured the
    calibration's tail, which the build is unless it ``inherited`` the fitted values."""

    def own(m: Measurement) -> bool:
        named = m.condition("segments")
        return int(named) == segments if named is not None else not inherited

    return [m for m in rows if own(m)], [m for m in rows if not own(m)]


def _rows(rows: list[Measurement]) -> str:
    return ("row " if len(rows) == 1 else "rows ") + ", ".join(str(m.row) for m in rows)


__all__ = ["MeasuredComparison", "compare_measurements", "rows_of_tail", "LANDS_WITHIN_REL"]

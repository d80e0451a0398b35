"""`bvsr calibrate`: fit the quantities no table gives to measured figures, check on held-out ones.

The fit uses the ``fit`` rows only: bounded least squares (scipy
``least_squares``, trust-region reflective) on the relative errors
(predicted - reported) / reported, over the logarithms of the fitted
values (all positive, spanning decades). The ``holdout`` rows are predicted
before and after and never enter the fit, so changing them cannot move a
fitted value.

Which quantities are fitted follows from the data and the supply model:
the effective area A and the vertebra's effective E I when the fit rows
hold quasi-static figures, and the supply's speed (the valve's sonic
conductance, or the Eq 13 ramp time with ``pneumatics.model = "ramp"``)
when they hold a dynamic one. The damping c stays at the table's value
unless asked for: one dynamic figure identifies one dynamic parameter.

The 95 % intervals come from the Jacobian at the solution: cov = s^2 (J^T J)^-1
with s^2 = RSS / (m - p) (or RSS / m when m <= p), in log space, so the
interval is value * exp(+/- 1.96 sd).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..errors import BadInput
from ..parameters.measurements import Measurement
from ..parameters.tables import CALIBRATABLE, Calibration, TailSpec
from .predict import Predictor

UNITS = {
    "effective_area_mm2": "mm^2",
    "rod_flexural_rigidity_n_mm2": "N mm^2",
    "damping_n_s_per_m": "N s/m",
    "valve_sonic_conductance_l_s_bar": "dm^3/(s bar)",
    "ramp_time_s": "s",
}
STATIC_QUANTITIES = ("segment_max_angle", "segment_blocked_force", "tip_workspace_radius")
DYNAMIC_QUANTITIES = (
    "segment_peak_velocity",
    "velocity_pressure_exponent",
    "time_pressure_exponent",
    "root_peak_torque",
    "root_peak_force",
    "cart_lift",
    "cart_peak_angle",
    "tip_workspace_radius",
)  # the workspace is recorded in time: both kinds identify it


class CalibrationError(ValueError, BadInput):
    """A calibration that cannot be asked for (an unknown quantity to fit): exit code 2."""


def uncalibrated(spec: TailSpec) -> TailSpec:
    """The spec with its tables' values (any ``[calibration]`` dropped)."""
    return dataclasses.replace(spec, calibration=Calibration())


def table_value(spec: TailSpec, name: str) -> float:
    """The value the tables give a calibratable quantity (the fit's starting point)."""
    from ..models.rod import rod_section

    base = uncalibrated(spec)
    return {
        "effective_area_mm2": base.actuation.effective_area_mm2,
        "rod_flexural_rigidity_n_mm2": rod_section(base).flexural_rigidity_n_mm2,
        "damping_n_s_per_m": base.actuation.damping_n_s_per_m,
        "valve_sonic_conductance_l_s_bar": base.pneumatics.valve_sonic_conductance_l_s_bar,
        "ramp_time_s": base.pneumatics.ramp_time_s,
    }[name]


def default_parameters(spec: TailSpec, rows: list[Measurement]) -> list[str]:
    """What the fit rows can identify (see the module's docstring)."""
    fit = [m.quantity for m in rows if m.role == "fit"]
    names = []
    if any(q in STATIC_QUANTITIES for q in fit):
        names += ["effective_area_mm2"] + (
            ["rod_flexural_rigidity_n_mm2"] if spec.vertebra.has_rod else []
        )
    if any(q in DYNAMIC_QUANTITIES for q in fit):
        names.append(
            "ramp_time_s" if spec.pneumatics.model == "ramp" else "valve_sonic_conductance_l_s_bar"
        )
    return names


def informed_values(spec: TailSpec, quantity: str) -> tuple[list[str], list[str]]:
    """The fitted values a ``fit`` row of ``quantity`` informs: those :func:`default_parameters`
    fits for it, and the damping c, which only ``--fit`` adds, where the row is predicted in time.

    Args:
        spec: the tail (its rod and supply model choose among the defaults).
        quantity: a name of :data:`bvsr_cad.parameters.measurements.QUANTITIES`.

    Returns:
        (fitted by default, fitted only when named in ``--fit``).
    """
    row = Measurement(0, "", quantity, (), 1.0, "", "fit", "")
    on_request = ["damping_n_s_per_m"] if quantity in DYNAMIC_QUANTITIES else []
    return default_parameters(spec, [row]), on_request


def with_values(spec: TailSpec, values: dict[str, float]) -> TailSpec:
    base = uncalibrated(spec)
    return dataclasses.replace(
        base, calibration=dataclasses.replace(base.calibration, fitted=dict(values))
    )


def _bounds(name: str) -> tuple[float, float]:
    rule = CALIBRATABLE[name]
    lo = rule.get("gt", rule.get("ge", 0.0))
    hi = rule.get("lt", rule.get("le", math.inf))
    return max(float(lo), 1e-12) * (1 + 1e-9), float(hi) * (1 - 1e-9)


@dataclass
class FittedValue:
    value: float
    low: float
    high: float
    unit: str
    start: float


@dataclass
class CalibrationResult:
    fitted: dict[str, FittedValue]
    rows: list[dict]
    rms_rel_fit: float
    rms_rel_holdout: float
    rms_rel_fit_uncalibrated: float
    rms_rel_holdout_uncalibrated: float
    calibrated_spec: TailSpec
    evaluations: int
    message: str

    def as_json(self) -> dict:
        return {
            "fitted": {
                k: {
                    "value": v.value,
                    "low": v.low,
                    "high": v.high,
                    "unit": v.unit,
                    "start": v.start,
                }
                for k, v in self.fitted.items()
            },
            "rows": self.rows,
            "rms_rel_fit": self.rms_rel_fit,
            "rms_rel_holdout": self.rms_rel_holdout,
            "rms_rel_fit_uncalibrated": self.rms_rel_fit_uncalibrated,
            "rms_rel_holdout_uncalibrated": self.rms_rel_holdout_uncalibrated,
            "evaluations": self.evaluations,
            "message": self.message,
        }


def _rms(values: list[float]) -> float:
    v = np.asarray([x for x in values if np.isfinite(x)], float)
    return float(np.sqrt(np.mean(v**2))) if v.size else float("nan")


def _relative(predicted: float, reported: float) -> float:
    return (predicted - reported) / abs(reported)


def calibrate(
    spec: TailSpec,
    rows: list[Measurement],
    parameters: list[str] | None = None,
    predictor: Predictor | None = None,
    progress: Callable[[str], None] | None = None,
) -> CalibrationResult:
    """Fit ``parameters`` (default: :func:`default_parameters`) to the fit rows; predict every row
    before and after."""
    say = progress or (lambda _m: None)
    names = parameters if parameters is not None else default_parameters(spec, rows)
    unknown = [n for n in names if n not in CALIBRATABLE]
    if unknown:
        raise CalibrationError(
            f"--fit {','.join(names)}: cannot fit {', '.join(unknown)}; "
            f"allowed: {', '.join(CALIBRATABLE)}"
        )
    fit_rows = [m for m in rows if m.role == "fit"]
    base = uncalibrated(spec)
    pred = predictor.with_spec(base) if predictor is not None else Predictor.from_spec(base)
    start = {n: table_value(spec, n) for n in names}
    residuals = _FitResiduals(spec, pred, names, fit_rows, say)
    x, sd, message = _fit_logs(residuals, names, start)
    fitted = {
        name: FittedValue(
            math.exp(v), math.exp(v - 1.96 * s), math.exp(v + 1.96 * s), UNITS[name], start[name]
        )
        for name, v, s in zip(names, x, sd)
    }
    calibrated = with_values(spec, {k: v.value for k, v in fitted.items()})
    say("calibrate: every row before and after")
    table = compare_rows(pred.with_spec(base), pred.with_spec(calibrated), rows)

    def rms(role: str, key: str) -> float:
        return rms_relative(table, role, key)

    return CalibrationResult(
        fitted,
        table,
        rms("fit", "rel_calibrated"),
        rms("holdout", "rel_calibrated"),
        rms("fit", "rel_uncalibrated"),
        rms("holdout", "rel_uncalibrated"),
        calibrated,
        residuals.evaluations,
        str(message),
    )


class _FitResiduals:
    """The fit rows' relative misses with the fitted parameters at x = log(value), counting its
    evaluations and reporting each one."""

    def __init__(
        self,
        spec: TailSpec,
        pred: Predictor,
        names: list[str],
        fit_rows: list[Measurement],
        say: Callable[[str], None],
    ):
        self.spec, self.pred, self.names, self.fit_rows, self.say = spec, pred, names, fit_rows, say
        self.evaluations = 0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        values = {n: float(math.exp(v)) for n, v in zip(self.names, x)}
        p = self.pred.with_spec(with_values(self.spec, values))
        out = []
        for m in self.fit_rows:
            try:
                out.append(_relative(p.predict(m), m.value))
            except RuntimeError:
                # a model that does not converge at these values: a large, finite miss
                out.append(10.0)
        r = np.nan_to_num(np.array(out), nan=10.0)
        self.say(
            f"calibrate: evaluation {self.evaluations}: rms {math.sqrt(np.mean(r**2)):.4f} at "
            + ", ".join(f"{n}={v:.4g}" for n, v in values.items())
        )
        return r


def _fit_logs(
    residuals: Callable[[np.ndarray], np.ndarray], names: list[str], start: dict[str, float]
) -> tuple[np.ndarray, np.ndarray, str]:
    """Least squares on x = log(value) within each parameter's bounds, from the tables' values
    ``start``: x, its standard deviations (from the Jacobian, the residuals' variance) and the
    solver's message."""
    from scipy.optimize import least_squares

    if not names:
        return np.array([]), np.array([]), "nothing to fit"
    lo_hi = [_bounds(n) for n in names]
    # The Jacobian steps 1 % in each value.
    x0 = np.array(
        [
            math.log(min(max(start[n], lo * 1.000001), hi * 0.999999))
            for n, (lo, hi) in zip(names, lo_hi)
        ]
    )
    sol = least_squares(
        residuals,
        x0,
        bounds=([math.log(a) for a, _ in lo_hi], [math.log(b) for _, b in lo_hi]),
        x_scale=1.0,
        diff_step=0.01 / np.maximum(1.0, np.abs(x0)),
        xtol=1e-4,
        ftol=1e-6,
        max_nfev=60,
    )
    x, jac, res, message = sol.x, sol.jac, sol.fun, sol.message
    m, n = len(res), len(x)
    s2 = float(res @ res) / (m - n if m > n else max(m, 1))
    try:
        cov = s2 * np.linalg.pinv(jac.T @ jac)
        sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        sd = np.full(n, np.inf)
    return x, sd, message


#: Threads predicting a table's rows, at most: the workspace protocol's rows step in MuJoCo without
#: Python's lock, each in a thread (up to this less one), beside one thread for all the other rows.
COMPARE_THREADS = 8


def compare_rows(
    before: Predictor,
    after: Predictor,
    rows: list[Measurement],
    progress: Callable[[str], None] | None = None,
    threads: int = COMPARE_THREADS,
) -> list[dict]:
    """Every row predicted by ``before`` (uncalibrated) and ``after`` (calibrated), with relative
    errors.

    The predictions run in up to ``threads`` threads, the slowest quantity (the workspace protocol)
    first, the others once its geometry and joint limits are made; each is deterministic, so the
    table is the same for any number of threads."""
    say = progress or (lambda _m: None)

    def predict(pred: Predictor, m: Measurement) -> float:
        if pred is before:
            say(f"row {m.row}: {m.label}")
        return _safe(pred, m)

    jobs = [(pred, m) for m in rows for pred in (before, after)]
    protocol = [i for i, (_pred, m) in enumerate(jobs) if m.quantity == "tip_workspace_radius"]
    # The protocol rows each in a thread of their own (their simulation runs in C, without the
    # interpreter's lock); every other row in one more thread, one after another: their Python takes
    # turns on the lock anyway, and more threads taking turns add only switching (and the taper's
    # unlocked memo filled twice at once: six layouts solved for three), for the same table.
    sims = ThreadPoolExecutor(max(1, min(len(protocol), threads - 1)))
    rest = ThreadPoolExecutor(1) if threads > 1 else sims
    try:
        done = {i: sims.submit(predict, *jobs[i]) for i in protocol}
        # The protocol rows' geometry and joint limits are Python (under the lock) and stand before
        # their simulation: the other rows start once those are made, instead of sharing the lock
        # with them (the table is the same; the simulations start sooner).
        if threads > 1:
            for i in protocol:
                pred, m = jobs[i]
                try:
                    pred.prepare(m)
                except Exception:  # noqa: BLE001 - the row's own job meets it again and reports it
                    pass
        done |= {i: rest.submit(predict, *job) for i, job in enumerate(jobs) if i not in done}
    finally:
        rest.shutdown()
        sims.shutdown()
    table = []
    for n, m in enumerate(rows):
        b, a = done[2 * n].result(), done[2 * n + 1].result()
        table.append(
            {
                "row": m.row,
                "experiment": m.experiment,
                "quantity": m.quantity,
                "label": m.label,
                "role": m.role,
                "unit": m.unit,
                "reported": m.value,
                "uncalibrated": b,
                "calibrated": a,
                "rel_uncalibrated": _relative(b, m.value),
                "rel_calibrated": _relative(a, m.value),
                "source": m.source,
            }
        )
    return table


def rms_relative(table: list[dict], role: str, key: str) -> float:
    """RMS of ``key`` (``rel_uncalibrated`` or ``rel_calibrated``) over the rows of ``role``."""
    return _rms([r[key] for r in table if r["role"] == role])


def _safe(pred: Predictor, m: Measurement) -> float:
    try:
        return pred.predict(m)
    except RuntimeError:
        return float("nan")


__all__ = [
    "calibrate",
    "compare_rows",
    "rms_relative",
    "CalibrationError",
    "CalibrationResult",
    "FittedValue",
    "uncalibrated",
    "default_parameters",
    "informed_values",
    "with_values",
]

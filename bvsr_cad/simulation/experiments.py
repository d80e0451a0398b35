"""What `bvsr simulate` (on no platform and on the cart) and `bvsr calibrate` run, whole: each
experiment, its figures written, its results beside the paper's, as JSON-ready data and as the lines
the command prints (the quadruped's: :func:`bvsr_cad.simulation.quadruped.on_quadruped`).

The command line parses the arguments, loads the input files and prints; the work and the comparison
with the paper live here, next to the simulator they drive (:mod:`.sim`). Nothing is tuned to the
paper: its figures are printed beside the results, with the relative difference.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ..analysis.calibrate import CalibrationResult, calibrate
from ..analysis.predict import Predictor
from ..exporters.calibration_file import write_calibrated_params
from ..parameters import paper
from ..parameters.measurements import Measurement, data_sha256
from ..parameters.tables import TailSpec
from .sim import (
    SimResult,
    cart_comparison,
    impact_table,
    protocol_radius_mm,
    simulate,
    simulate_cart,
    simulate_impact,
)

Progress = Callable[[str], None]


def paper_comparison(res: SimResult, payload_g: float) -> dict[str, dict]:
    """The pulse's peaks beside the figures the paper reports for them (None where it reports none
    at this pressure and payload: the root's peaks are reported at 6 bar only).

    Args:
        res: the :class:`~bvsr_cad.simulation.sim.SimResult` of :func:`~.sim.simulate`.
        payload_g: the tip payload it ran with, g.

    Returns:
        By quantity: ``computed``, ``paper`` (None if not reported) and, for the segment's
        velocity, ``paper_at`` (the conditions the paper measured it under).
    """
    v_ref = paper.SEGMENT_PEAK_VELOCITY_EXTENSION
    peaks = paper.paper_root_peaks(payload_g) if res.pressure_bar == 6 else None
    return {
        "peak_velocity_deg_s": {
            "computed": res.peak_velocity_deg_s,
            "paper": v_ref.value,
            "paper_at": v_ref.measured_on,
        },
        "peak_root_force_n": {
            "computed": res.peak_root_force_n,
            "paper": peaks[0].value if peaks else None,
        },
        "peak_root_torque_nm": {
            "computed": res.peak_root_torque_nm,
            "paper": peaks[1].value if peaks else None,
        },
    }


def pulse(
    spec: TailSpec,
    limits: list[float],
    pressure_bar: float,
    payload_g: float,
    folder: Path,
    supply: str | None = None,
    progress: Progress | None = None,
) -> dict:
    """The paper's pulse (one segment, then the whole tail with its payload), its plot written into
    ``folder``, and its peaks beside the paper's.

    Args:
        spec: the tail.
        limits: each joint's bending limit, rad (:func:`~.sim.joint_limits_rad`).
        pressure_bar: the pulse's gauge pressure, bar.
        payload_g: the tip payload, g.
        folder: where the plot goes (made if missing).
        supply: ``ramp`` or ``valve``; None: the file's ``pneumatics.model``.
        progress: called with a line per stage.

    Returns:
        The peaks, the joint limits, the plot's path, ``paper`` (:func:`paper_comparison`) and the
        supply model used.

    Raises:
        SimulationInputError: a pressure outside the actuators' control range or a negative payload.
    """
    from ..exporters.plots import plot_simulation

    res = simulate(spec, limits, pressure_bar, payload_g, progress=progress, supply=supply)
    png = Path(folder) / f"simulate_{pressure_bar:g}bar_{payload_g:g}g.png"
    supply = supply or spec.pneumatics.model
    how = "Eq 13 ramp" if supply == "ramp" else "ISO 6358 valve supply"
    plot_simulation(res, png, f"{spec.name}: {pressure_bar:g} bar pulse ({how})")
    return {
        "pressure_bar": res.pressure_bar,
        "payload_g": res.payload_g,
        "peak_velocity_deg_s": res.peak_velocity_deg_s,
        "segment_angle_reached_deg": res.angle_reached_deg,
        "peak_root_torque_nm": res.peak_root_torque_nm,
        "peak_root_force_n": res.peak_root_force_n,
        "joint_limits_rad": limits,
        "plot": str(png),
        "paper": paper_comparison(res, payload_g),
        "supply": supply,
    }


def pulse_lines(result: dict) -> list[str]:
    """:func:`pulse`'s result as text: each peak beside the paper's figure and the difference."""
    lines = []
    for key, c in result["paper"].items():
        ref = (
            "not reported at this pressure/payload"
            if c["paper"] is None
            else f"paper {c['paper']:g} ({100 * (c['computed'] - c['paper']) / c['paper']:+.0f} %)"
        )
        lines.append(f"{key}: {c['computed']:.3g}  {ref}")
    reached = result["segment_angle_reached_deg"]
    return [*lines, f"segment reached {reached:.1f} deg; plot: {result['plot']}"]


def cart(
    spec: TailSpec,
    limits: list[float],
    pressure_bar: float,
    folder: Path,
    supply: str | None = None,
    progress: Progress | None = None,
) -> dict:
    """The tail on the paper's hinged cart (extension and waggle), its plot written into ``folder``,
    the cart's motion beside Eq 20-22 and the paper.

    Args:
        spec: the tail.
        limits: each joint's bending limit, rad.
        pressure_bar: the pulses' gauge pressure, bar.
        folder: where the plot goes (made if missing).
        supply: ``ramp`` or ``valve``; None: the file's ``pneumatics.model``.
        progress: called with a line per stage.

    Returns:
        ``pressure_bar``, ``rows`` (:func:`~.sim.cart_comparison`), ``plot`` and ``supply``.
    """
    from ..exporters.plots import plot_cart

    say = progress or (lambda _m: None)
    runs = simulate_cart(spec, limits, pressure_bar, progress=say, supply=supply)
    say("Eq 20-22 on the Eq 6-12 tail model")
    rows = cart_comparison(spec, runs, pressure_bar)
    png = Path(folder) / f"cart_{pressure_bar:g}bar.png"
    plot_cart(runs, png, f"{spec.name} on the hinged cart: {pressure_bar:g} bar pulses")
    return {
        "pressure_bar": pressure_bar,
        "rows": rows,
        "plot": str(png),
        "supply": supply or spec.pneumatics.model,
    }


def cart_lines(result: dict) -> list[str]:
    """:func:`cart`'s result as a table: MuJoCo, Eq 20-22 and the paper, by motion and quantity."""
    lines = [f"{'motion':10} {'quantity':17} {'MuJoCo':>8} {'Eq 20-22':>9} {'paper':>7}"]
    for row in result["rows"]:
        ref = "" if row["paper"] is None else f"{row['paper']:7.3g}"
        quantity = f"{row['quantity']} ({row['unit']})"
        lines.append(
            f"{row['motion']:10} {quantity:17} {row['mujoco']:8.3g} {row['eq20_22']:9.3g} {ref:>7}"
        )
    return [*lines, f"plot: {result['plot']}"]


#: The most a ball may sink into the tail for an impact run to count as resolved, mm.
MAX_PENETRATION_MM = 1.0


def impact(spec: TailSpec, limits: list[float], progress: Progress | None = None) -> list[dict]:
    """The paper's disturbance test: a 500 g and a 650 g ball down the ramp into the soft tail and
    its rigid twin, one row per run (:func:`~.sim.impact_table`)."""

    return impact_table(simulate_impact(spec, limits, progress=progress))


def impact_resolved(rows: list[dict]) -> bool:
    """Every run free of MuJoCo's warnings, no ball sunk deeper than :data:`MAX_PENETRATION_MM`."""
    return all(r["warnings"] == 0 and r["max_penetration_mm"] <= MAX_PENETRATION_MM for r in rows)


def impact_lines(rows: list[dict]) -> list[str]:
    """:func:`impact`'s rows as a table, the paper's tip acceleration beside each."""
    lines = [
        f"{'tail':6} {'ball':22} {'F_root N':>9} {'T_root N m':>10} {'tip acc m/s2':>12} "
        f"{'paper m/s2':>10} {'pen mm':>7} {'warn':>4} {'v m/s':>6} {'v roll':>6}"
    ]
    for r in rows:
        lines.append(
            f"{r['tail']:6} {r['ball']:22} {r['peak_root_force_n']:9.1f} "
            f"{r['peak_root_torque_nm']:10.2f} "
            f"{r['peak_tip_acceleration_m_s2']:12.0f} {r['paper_tip_acceleration_m_s2']:10.0f} "
            f"{r['max_penetration_mm']:7.3f} {r['warnings']:4d} {r['ball_speed_m_s']:6.2f} "
            f"{r['rolling_speed_m_s']:6.2f}"
        )
    return lines


def calibration(
    spec: TailSpec,
    rows: list[Measurement],
    params: str | Path,
    data: str | Path,
    fit: str | None,
    output: str | Path | None,
    progress: Progress | None = None,
) -> tuple[CalibrationResult, Path | None]:
    """The fit of the quantities no table gives to the measurements in ``data``, and with
    ``output`` the calibrated parameter file (``params`` with a ``[calibration]`` table).

    Args:
        spec: the tail ``params`` describes (loaded: a bad file is refused before this module's
            imports).
        rows: the measurements (:func:`~bvsr_cad.parameters.measurements.load_measurements` of
            ``data``, loaded first as well).
        params: the parameter file.
        data: the measurements CSV.
        fit: comma-separated quantities to fit (None: what the fit rows identify).
        output: where the calibrated parameter file goes (None: not written).
        progress: called with a line per stage.

    Returns:
        (the :class:`~bvsr_cad.analysis.calibrate.CalibrationResult`, the file written or None).

    Raises:
        CalibrationError: a quantity that cannot be fitted to these rows.
    """

    say = progress or (lambda _m: None)
    names = [n.strip() for n in fit.split(",") if n.strip()] if fit else None
    say(
        f"{len(rows)} measurements ({sum(m.role == 'fit' for m in rows)} fit, "
        f"{sum(m.role == 'holdout' for m in rows)} holdout); building the geometry"
    )
    res = calibrate(spec, rows, names, Predictor.from_spec(spec, protocol_radius_mm), progress=say)
    if output is None:
        return res, None
    rod = (spec.vertebra.material, spec.vertebra.diameter_mm)
    return res, write_calibrated_params(
        params, output, res, data, data_sha256(data), spec.name, rod
    )


def calibration_lines(res: CalibrationResult) -> list[str]:
    """A :class:`~bvsr_cad.analysis.calibrate.CalibrationResult` as text: each fitted value with
    its interval, each row's error before and after, the RMS errors of fit and holdout rows."""
    lines = ["fitted (95 % interval from the Jacobian; start = the tables' value):"]
    lines += [
        f"  {name} = {v.value:.4g} {v.unit}  [{v.low:.4g} .. {v.high:.4g}]  start {v.start:.4g}"
        for name, v in res.fitted.items()
    ]
    lines.append(
        f"{'row':>4} {'role':8} {'quantity (conditions)':74} {'reported':>10} {'uncalib.':>10} "
        f"{'calib.':>10} {'error':>7}"
    )
    lines += [
        f"{r['row']:>4} {r['role']:8} {r['label'][:74]:74} {r['reported']:>10.4g} "
        f"{r['uncalibrated']:>10.4g} {r['calibrated']:>10.4g} {100 * r['rel_calibrated']:>+6.0f}%"
        for r in res.rows
    ]
    lines.append(
        f"RMS relative error: fit {res.rms_rel_fit_uncalibrated:.3f} -> {res.rms_rel_fit:.3f}, "
        f"holdout {res.rms_rel_holdout_uncalibrated:.3f} -> {res.rms_rel_holdout:.3f}"
    )
    return lines

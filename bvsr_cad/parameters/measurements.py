"""Measurement files for `bvsr calibrate`: one measured figure per CSV row.

Columns (a header row names them; their order is free):

    experiment  where the figure was measured (free text, e.g. "Table III")
    quantity    one of :data:`QUANTITIES` (what the models predict)
    conditions  "key=value; key=value" from the quantity's allowed conditions
    value       a number
    unit        the quantity's unit, spelled as in :data:`QUANTITIES`
    role        fit (the calibration may use it) or holdout (only compared)
    source      where the figure comes from and any condition chosen for it

Every problem is reported with its row number (the header is row 1) and
column, the value found and what is allowed; :class:`MeasurementError`
carries them all, and the command line exits 2 on it.
"""

from __future__ import annotations

import csv
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import BadInput

COLUMNS = ("experiment", "quantity", "conditions", "value", "unit", "role", "source")
ROLES = ("fit", "holdout")
MOTIONS = ("extension", "flexion", "waggle")

#: quantity -> (unit, {condition: kind}, what it is). Kinds: "motion", "number".
QUANTITIES: dict[str, tuple[str, dict[str, str], str]] = {
    "segment_max_angle": (
        "deg",
        {"motion": "motion"},
        "one segment's quasi-static bending angle at the lines' pressure limits",
    ),
    "segment_blocked_force": (
        "N",
        {"motion": "motion"},
        "one segment's quasi-static blocked tip force at the lines' pressure limits",
    ),
    "soa_stiffness": ("N/m", {"pressure_kpa": "number"}, "k of Eq 4 at a gauge pressure"),
    "segment_peak_velocity": (
        "deg/s",
        {"motion": "motion", "pressure_bar": "number"},
        "one segment's peak bending rate before 38 deg, after a pressure pulse",
    ),
    "velocity_pressure_exponent": (
        "1",
        {"motion": "motion", "pressure_min_bar": "number", "pressure_max_bar": "number"},
        "x of V ~ P^x fitted over the pressures 1..6 bar",
    ),
    "time_pressure_exponent": (
        "1",
        {"motion": "motion", "pressure_min_bar": "number", "pressure_max_bar": "number"},
        "x of T ~ P^x, T the time to bend 38 deg",
    ),
    "tip_workspace_radius": (
        "mm",
        {
            "segments": "number",
            "pressurised_max_kpa_abs": "number",
            "depressurised_min_kpa_abs": "number",
        },
        "largest lateral distance of the tip from its rest point under the random protocol",
    ),
    "root_peak_torque": (
        "N m",
        {"pressure_bar": "number", "payload_g": "number", "motion": "motion"},
        "the whole tail's peak torque at the root after a pulse",
    ),
    "root_peak_force": (
        "N",
        {"pressure_bar": "number", "payload_g": "number", "motion": "motion"},
        "the whole tail's peak force at the root after a pulse",
    ),
    "cart_lift": (
        "mm",
        {"pressure_bar": "number", "motion": "motion"},
        "the hinged cart's front-end lift (Eq 20-22)",
    ),
    "cart_peak_angle": (
        "deg",
        {"pressure_bar": "number", "motion": "motion"},
        "the hinged cart's peak angle (Eq 20-22)",
    ),
}


#: quantity -> how a lab measures it, the way the models predict it (the paper's setups where it
#: gives one). The lab guide's table is generated from this and :data:`QUANTITIES`.
HOW_TO_MEASURE: dict[str, str] = {
    "segment_max_angle": (
        "one segment, root panel clamped; hold the lines at their pressure limits for the motion "
        "(``actuation.*``) and read the distal panel's bending angle with an IMU once it settles"
    ),
    "segment_blocked_force": (
        "one segment with its distal panel tied to a force sensor so that it cannot move; the "
        "lines at their pressure limits for the motion; read the settled force"
    ),
    "soa_stiffness": (
        "one SOA on a slider under dead loads; the pressure that keeps it at its original length "
        "against each load gives k at that pressure (the line k = slope P + offset)"
    ),
    "segment_peak_velocity": (
        "one segment, a pressure pulse of ``pressure_bar`` on the lines opposite the bend, the "
        "others open; the peak bending rate (IMU or high-speed video) before 38 deg"
    ),
    "velocity_pressure_exponent": (
        "the peak velocity (above) at several pulse pressures from ``pressure_min_bar`` to "
        "``pressure_max_bar``; the slope of log V against log P"
    ),
    "time_pressure_exponent": (
        "the time to bend 38 deg after the pulse, at several pressures; the slope of log T "
        "against log P"
    ),
    "tip_workspace_radius": (
        "the tail horizontal, every chamber drawing a random pressure between the two absolute "
        "limits each ``actuation.workspace_cycle_s``; motion capture on the tip; the largest "
        "lateral distance from its rest point"
    ),
    "root_peak_torque": (
        "the whole tail on a six-axis force sensor at its root, ``payload_g`` at the tip, a pulse "
        "of ``pressure_bar``; the peak torque"
    ),
    "root_peak_force": "as root_peak_torque; the peak force",
    "cart_lift": (
        "the tail on the hinged cart of ``[cart]``, a pulse of ``pressure_bar``; the largest lift "
        "of the cart's front end"
    ),
    "cart_peak_angle": (
        "the tail on the hinged cart of ``[cart]``, a pulse of ``pressure_bar``; the cart's "
        "largest angle about its hinge"
    ),
}


class MeasurementError(ValueError, BadInput):
    """A bad measurement file; ``problems`` name the row and the column of each."""

    def __init__(self, path: str | Path, problems: list[str]):
        self.path = str(path)
        self.problems = problems
        super().__init__(
            f"{path}: {len(problems)} problem(s) in the measurements:\n"
            + "\n".join(f"  - {p}" for p in problems)
        )


@dataclass(frozen=True)
class Measurement:
    row: int  # 1-based line of the file (the header is row 1)
    experiment: str
    quantity: str
    conditions: tuple[tuple[str, str | float], ...]
    value: float
    unit: str
    role: str
    source: str

    def condition(self, key: str, default=None):
        return dict(self.conditions).get(key, default)

    @property
    def label(self) -> str:
        cond = ", ".join(
            f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.conditions
        )
        return f"{self.quantity} ({cond})" if cond else self.quantity


#: What the models can be asked, per numeric condition: (lowest, highest, whole numbers only).
#: Pressures in bar and kPa are gauge unless named ``_abs``; a pulse is positive; a vacuum stops at
#: -1 atm.
CONDITION_RANGES: dict[str, tuple[float, float, bool]] = {
    "pressure_kpa": (-101.325, 1000.0, False),
    "pressure_bar": (0.01, 10.0, False),
    "pressure_min_bar": (0.01, 10.0, False),
    "pressure_max_bar": (0.01, 10.0, False),
    "payload_g": (0.0, 10000.0, False),
    "segments": (1, 3, True),
    "pressurised_max_kpa_abs": (0.0, 1100.0, False),
    "depressurised_min_kpa_abs": (0.0, 1100.0, False),
}
#: Conditions that bound a range from below and above: the first may not exceed the second.
CONDITION_ORDER = (
    ("pressure_min_bar", "pressure_max_bar"),
    ("depressurised_min_kpa_abs", "pressurised_max_kpa_abs"),
)


def _conditions(text: str, allowed: dict[str, str], where: str, problems: list[str]) -> tuple:
    out = []
    for item in (x.strip() for x in text.split(";")):
        if not item:
            continue
        key, sep, raw = (s.strip() for s in item.partition("="))
        if not sep:
            problems.append(
                f"{where} = {item!r}: expected key=value; allowed keys: "
                f"{', '.join(allowed) or 'none'}"
            )
            continue
        if key not in allowed:
            problems.append(
                f"{where}: unknown condition {key!r}; allowed: {', '.join(allowed) or 'none'}"
            )
            continue
        if allowed[key] == "motion":
            if raw not in MOTIONS:
                problems.append(f"{where}: {key} = {raw!r}; allowed: {', '.join(MOTIONS)}")
                continue
            out.append((key, raw))
        else:
            try:
                value = float(raw)
            except ValueError:
                problems.append(f"{where}: {key} = {raw!r} is not a number")
                continue
            lo, hi, whole = CONDITION_RANGES.get(key, (-math.inf, math.inf, False))
            if not lo <= value <= hi or (whole and not value.is_integer()):
                problems.append(
                    f"{where}: {key} = {raw}; allowed: {'whole numbers ' if whole else ''}"
                    f"{lo:g} to {hi:g}"
                )
                continue
            out.append((key, value))
    given = dict(out)
    for low, high in CONDITION_ORDER:
        if low in given and high in given and given[low] > given[high]:
            problems.append(
                f"{where}: {low} = {given[low]:g} exceeds {high} = {given[high]:g}; allowed: "
                f"{low} <= {high}"
            )
    missing = [k for k in allowed if k not in given]
    if missing and not any(f"{where}:" in p for p in problems):
        problems.append(f"{where}: missing condition(s) {', '.join(missing)}")
    return tuple(out)


def load_measurements(path: str | Path) -> list[Measurement]:
    """Read and validate a measurement CSV.

    Raises:
        MeasurementError: naming the row and the column of every problem.
    """
    from .load import read_input_text

    path = Path(path)
    text = read_input_text(path, MeasurementError)
    rows = list(csv.reader(line for line in text.splitlines() if not line.lstrip().startswith("#")))
    if not rows:
        raise MeasurementError(path, ["empty file: expected a header row " + ",".join(COLUMNS)])
    header = [h.strip() for h in rows[0]]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise MeasurementError(
            path,
            [
                f"row 1 (header): missing column(s) {', '.join(missing)}; "
                f"expected {', '.join(COLUMNS)}"
            ],
        )
    col = {c: header.index(c) for c in COLUMNS}
    problems: list[str] = []
    out: list[Measurement] = []
    for n, raw in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in raw):
            continue
        cells = {c: (raw[i].strip() if i < len(raw) else "") for c, i in col.items()}
        before = len(problems)
        quantity = cells["quantity"]
        if quantity not in QUANTITIES:
            problems.append(
                f"row {n}, column quantity = {quantity!r}: unknown; allowed: "
                f"{', '.join(QUANTITIES)}"
            )
            continue
        unit, allowed, _ = QUANTITIES[quantity]
        if not cells["unit"]:
            problems.append(f"row {n}, column unit: missing; {quantity} is in {unit!r}")
        elif cells["unit"] != unit:
            problems.append(f"row {n}, column unit = {cells['unit']!r}: {quantity} is in {unit!r}")
        try:
            value = float(cells["value"])
            if value != value or value in (float("inf"), float("-inf")):
                raise ValueError
        except ValueError:
            problems.append(f"row {n}, column value = {cells['value']!r}: not a number")
            value = float("nan")
        if value == 0.0:
            problems.append(f"row {n}, column value = 0: relative errors need a non-zero figure")
        if cells["role"] not in ROLES:
            problems.append(
                f"row {n}, column role = {cells['role']!r}: allowed: {', '.join(ROLES)}"
            )
        conditions = _conditions(
            cells["conditions"], allowed, f"row {n}, column conditions", problems
        )
        if len(problems) == before:
            out.append(
                Measurement(
                    n,
                    cells["experiment"],
                    quantity,
                    conditions,
                    value,
                    unit,
                    cells["role"],
                    cells["source"],
                )
            )
    if not problems and not out:
        problems.append("no measurement rows")
    if not problems and not any(m.role == "fit" for m in out):
        problems.append("column role: no row is 'fit'; the calibration needs at least one")
    if problems:
        raise MeasurementError(path, problems)
    return out


def data_sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


__all__ = [
    "Measurement",
    "MeasurementError",
    "load_measurements",
    "data_sha256",
    "QUANTITIES",
    "HOW_TO_MEASURE",
    "COLUMNS",
]

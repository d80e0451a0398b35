"""The calibrated parameter file and the calibration report of `bvsr calibrate`.

The parameter file is the input's text, unchanged but for its
``[calibration]`` tables, which are replaced by the fit's (the data file and
its SHA-256, the fitted values, the fit and holdout RMS). It is written
atomically: a failed or interrupted run leaves the previous file in place.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from ..analysis.calibrate import CalibrationResult

_HEADER = re.compile(r"^\s*\[\[?\s*([A-Za-z0-9_.\-\"' ]+?)\s*\]\]?\s*(#.*)?$")


def strip_calibration(text: str) -> str:
    """The parameter text without its ``[calibration]`` and ``[calibration.*]`` tables."""
    out, skipping = [], False
    for line in text.splitlines():
        m = _HEADER.match(line)
        if m:
            skipping = m.group(1).split(".")[0].strip() == "calibration"
        if not skipping:
            out.append(line)
    while out and not out[-1].strip():
        out.pop()
    return "\n".join(out) + "\n"


def calibration_text(
    result: CalibrationResult,
    data_file: str,
    data_sha256: str,
    measured_tail: str,
    rod: tuple[str, float],
) -> str:
    """``rod``: the measured tail's vertebra (material key, diameter in mm), to which a fitted E I
    belongs."""
    lines = [
        "",
        "# Written by `bvsr calibrate`: the values below replace, in their one home, the values "
        "the",
        "# tables above give (models/actuator, models/rod, models/pneumatics). Delete these tables "
        "to",
        "# return to the uncalibrated model.",
        "[calibration]",
        f'data_file = "{data_file}"',
        f'measured_tail = "{measured_tail}"',
        f'data_sha256 = "{data_sha256}"',
        f'rod_material = "{rod[0]}"',
        f"rod_diameter_mm = {rod[1]:g}",
        f"rms_rel_fit = {result.rms_rel_fit:.6g}",
        f"rms_rel_holdout = {result.rms_rel_holdout:.6g}",
        f"rms_rel_holdout_uncalibrated = {result.rms_rel_holdout_uncalibrated:.6g}",
        "",
        "[calibration.fitted]",
    ]
    for name, v in result.fitted.items():
        lines.append(
            f"{name} = {v.value:.6g}   # {v.unit}; 95 % interval {v.low:.4g} .. {v.high:.4g}; "
            f"table value {v.start:.4g}"
        )
    return "\n".join(lines) + "\n"


def write_calibrated_params(
    source: str | Path,
    out: str | Path,
    result: CalibrationResult,
    data_file: str | Path,
    data_sha256: str,
    measured_tail: str,
    rod: tuple[str, float],
) -> Path:
    """``data_file`` is recorded relative to ``out``'s folder (where the loader resolves it)."""
    out = Path(out)
    rel = Path(os.path.relpath(Path(data_file).resolve(), out.resolve().parent)).as_posix()
    text = strip_calibration(Path(source).read_text(encoding="utf-8")) + calibration_text(
        result, rel, data_sha256, measured_tail, rod
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out


__all__ = ["write_calibrated_params", "strip_calibration", "calibration_text"]

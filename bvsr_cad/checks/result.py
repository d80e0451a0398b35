"""The result every check returns; the CLI and the tests consume the same objects."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class CheckResult:
    """One check's outcome, as the command line, the report, the manifest and the tests read it.

    Attributes:
        name: ``group:where`` or ``group_what`` (``stl_watertight:panel0``, ``paper:tail_mass``).
        passed: True or False for a check; None for an informational comparison, or for a check
            that could not run (then ``value`` is None too: :attr:`skipped`).
        value: what was measured, in ``unit`` (a number, a list, or text).
        limit: what it was compared with, in ``unit``; None or ``"-"`` where there is none.
        unit: the unit of ``value`` and ``limit`` (``""`` for counts and flags).
        where: the file, part or paper section it concerns, relative to the export.
        note: a sentence for a human: why it failed, or what the comparison means.
    """

    name: str
    passed: bool | None
    value: Any
    limit: Any
    unit: str
    where: str
    note: str = ""

    def __post_init__(self) -> None:
        # Checks compute with numpy; the JSON contract wants plain bools and numbers.
        for key in ("passed", "value", "limit"):
            v = getattr(self, key)
            if hasattr(v, "item") and getattr(v, "ndim", 0) == 0:
                object.__setattr__(self, key, v.item())

    def to_json(self) -> dict[str, Any]:
        """The result as plain JSON values (``bvsr check --json`` and the manifest's ``checks``).

        Returns:
            ``{name, passed, value, limit, unit, where, note}``.
        """
        return asdict(self)

    @property
    def skipped(self) -> bool:
        """True for a check that could not run (its tool or extra is missing): no value, no
        verdict."""
        return self.passed is None and self.value is None

    @property
    def group(self) -> str:
        """The check's family, the part of its name before the first ``:`` or ``_`` (``stl``,
        ``print``)."""
        return self.name.split(":", 1)[0].split("_", 1)[0]

    def line(self) -> str:
        """One line: verdict, name, value against limit, where, and the note."""
        if self.skipped:
            return f"SKIP  {self.name} [{self.where}]" + (f"  {self.note}" if self.note else "")
        mark = {True: "PASS", False: "FAIL", None: "INFO"}[self.passed]
        val = f"{self.value:.4g}" if isinstance(self.value, float) else str(self.value)
        text = f"{mark}  {self.name}: {val} {self.unit}".rstrip()
        if self.limit not in (None, "-", ""):
            lim = f"{self.limit:.4g}" if isinstance(self.limit, float) else str(self.limit)
            text += f" (limit {lim} {self.unit})".replace(" )", ")")
        return text + f" [{self.where}]" + (f"  {self.note}" if self.note else "")


def overall(results: list[CheckResult]) -> bool:
    """True when no check failed (informational and skipped checks do not fail a run)."""
    return all(r.passed is not False for r in results)


#: Informational groups printed row by row in the short summary: the comparisons with the paper's
#: figures (mass, length, angles, forces), which a designer reads on every build. Other
#: informational rows are counted.
SHOWN_INFO_GROUPS = ("paper",)


def summary_lines(results: list[CheckResult]) -> list[str]:
    """A passing export at a glance: one line per check group, then every failure in full, the paper
    comparisons, and each reason for skipped checks once (a missing tool is named once, not per
    file)."""
    groups: dict[str, list[CheckResult]] = {}
    for r in results:
        groups.setdefault(r.group, []).append(r)
    width = max((len(g) for g in groups), default=0)
    lines = []
    for name, rows in groups.items():
        passed = sum(r.passed is True for r in rows)
        failed = sum(r.passed is False for r in rows)
        skipped = sum(r.skipped for r in rows)
        info = len(rows) - passed - failed - skipped
        counts = [
            f"{n} {word}"
            for n, word in (
                (passed, "passed"),
                (failed, "failed"),
                (info, "informational"),
                (skipped, "skipped"),
            )
            if n
        ]
        mark = (
            "FAIL"
            if failed
            else ("PASS" if passed else ("SKIP" if skipped == len(rows) else "INFO"))
        )
        lines.append(f"{mark}  {name:<{width}}  {', '.join(counts)}")
    failures = [r.line() for r in results if r.passed is False]
    if failures:
        lines += ["", "failed:"] + failures
    shown = [
        r.line()
        for r in results
        if r.passed is None and not r.skipped and r.group in SHOWN_INFO_GROUPS
    ]
    if shown:
        lines += ["", "compared with the paper:"] + shown
    reasons = list(dict.fromkeys(f"{r.group}: {r.note}" for r in results if r.skipped))
    if reasons:
        lines += ["", "skipped:"] + reasons
    return lines


def tally_line(results: list[CheckResult], verbose: bool = False) -> str:
    """The last line of a run's report: how many checks passed and failed, with the informational
    and skipped ones counted apart (``verbose``: every check was listed above it)."""
    failed = sum(r.passed is False for r in results)
    skipped = sum(r.skipped for r in results)
    info = sum(r.passed is None for r in results) - skipped
    tail = f"{info} informational, {skipped} skipped"
    if failed:
        return f"{len(results) - failed - info - skipped} passed, {failed} failed ({tail})"
    return f"all {len(results) - info - skipped} checks passed ({tail})" + (
        "" if verbose else "; --verbose lists every check"
    )

"""Every check on an export, in one list."""

from __future__ import annotations

import json
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

from ..memo import InMemory, Memo
from .analyses import check_analyses
from .export import Export
from .layout import check_layout
from .mass import check_masses, masses_reads
from .memo import CheckMemo
from .mesh import check_part_mesh, part_mesh_reads
from .molds import check_molds, molds_reads
from .paper import check_paper
from .printability import check_printability
from .result import CheckResult
from .robot import ROBOT_PARTS, check_robot, robot_reads
from .slicer import slice_stls


def _mold_checks(exp: Export, memo: CheckMemo) -> list[CheckResult]:
    """The mold checks of ``exp`` (their verdicts from ``memo``'s cache while their reads are
    unchanged)."""
    return memo("molds", molds_reads(exp), lambda: check_molds(exp))


def _part_mesh(exp: Export, memo: CheckMemo, part: dict[str, Any]) -> list[CheckResult]:
    """One part's mesh checks (its verdicts from ``memo``'s cache while their reads are
    unchanged)."""
    return memo("part_mesh", part_mesh_reads(part), lambda: check_part_mesh(exp, part))


#: Starts the printability checks' second process: ``beside(root, sliced_now, meshes, robot,
#: manifest)`` runs :func:`printability_groups` on the export at ``root`` whose manifest is
#: ``manifest`` in another process and returns its handle
#: (``result_or(here, say, what)``, ``close()``, ``cpu_s``), or None where it could not start. The
#: build hands one to :class:`Checks` (:mod:`bvsr_cad.pipeline.processes.checks_process`); the
#: checks start no process.
StartBeside = Callable[[Path, Collection[str], bool, bool, dict[str, Any]], Any]

#: The manifest sections the printability checks read (besides the files they name).
PRINTABILITY_READS = ("parts", "print_jobs", "fabrication", "assembly", "rigid_tail")


def _printability_reads(exp: Export) -> tuple[list[str], dict[str, Any]]:
    """What the printability checks read: every file the manifest sections of
    :data:`PRINTABILITY_READS` name, and those sections."""
    sections = {k: exp.manifest.get(k) for k in PRINTABILITY_READS}
    names: set[str] = set()

    def walk(v: Any) -> None:
        if isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, str) and v.lower().endswith((".stl", ".3mf", ".step", ".gcode")):
            names.add(v)

    walk(sections)
    return sorted(names), sections


def _state(exp: Export, reads: tuple[list[str], Any]) -> str:
    """A group's reads (file names, manifest values) with each file's size and modification time, in
    one text: the inputs under which a group run early is kept (:func:`_group`)."""
    stats = []
    for rel in reads[0]:
        try:
            st = (exp.root / rel).stat()
            stats.append((st.st_size, st.st_mtime_ns))
        except OSError:
            stats.append(None)
    return json.dumps([reads, stats], sort_keys=True, default=str)


def _quiet(_line: str) -> None:
    pass


def _group(
    early: Memo,
    exp: Export,
    name: str,
    reads: tuple[list[str], Any],
    check: Callable[[], list[CheckResult]],
    say: Callable[[str], None] = _quiet,
) -> list[CheckResult]:
    """Check group ``name`` (its progress line too) through ``early``: the verdicts it holds while
    the group's ``reads`` are as they are now (:func:`_state`, taken before the group reads them),
    else ``check()`` run now, saying ``name``."""

    def now() -> list[CheckResult]:
        say(name)
        return check()

    return early(name, {"reads": _state(exp, reads)}, now)[0]


def _mesh_groups(
    early: Memo, exp: Export, memo: CheckMemo, say: Callable[[str], None] = _quiet
) -> list[CheckResult]:
    """The part meshes' checks, a group per part, then the masses' (on the meshes just read)."""
    results: list[CheckResult] = []
    for part in exp.parts:
        results += _group(
            early,
            exp,
            f"mesh {part['name']}",
            part_mesh_reads(part),
            lambda part=part: _part_mesh(exp, memo, part),
            say,
        )
    return results + _group(
        early, exp, "masses", masses_reads(exp), lambda: check_masses(exp, memo), say
    )


def _print_groups(
    early: Memo,
    exp: Export,
    memo: CheckMemo,
    sliced_now: Collection[str],
    say: Callable[[str], None] = _quiet,
) -> list[CheckResult]:
    """The printability checks, then the mold checks."""
    return _group(
        early,
        exp,
        "printability",
        _printability_reads(exp),
        lambda: check_printability(exp, sliced_now=sliced_now, memo=memo),
        say,
    ) + _group(early, exp, "molds", molds_reads(exp), lambda: _mold_checks(exp, memo), say)


def _robot_groups(
    early: Memo, exp: Export, claim: bool, say: Callable[[str], None] = _quiet
) -> None:
    """The parts of the robot descriptions' checks (none without a robot), a group each, named
    after its progress line; with ``claim`` only those this process takes first
    (:func:`claim_robot_checks`)."""
    if "robot" not in exp.manifest:
        return
    for i, (part, what) in enumerate(ROBOT_PARTS):
        if not claim or claim_robot_checks(exp.root, i):
            _group(early, exp, what, robot_reads(exp), lambda part=part: part(exp), say)


def printability_groups(
    exp: Export,
    sliced_now: Collection[str],
    memo: CheckMemo,
    meshes: bool = False,
    robot: bool = False,
) -> dict[str, tuple[dict[str, str], list[CheckResult]]]:
    """The second process's work: the printability checks and the mold checks of ``exp`` (verdicts
    of unchanged inputs from ``memo``); with ``meshes`` the part meshes' and the masses' checks
    after them; with ``robot`` the robot descriptions' last, the parts the build's own process has
    not taken first (:func:`claim_robot_checks`). Returns, by group (:func:`_group`), the state of
    its reads taken just before it read them and its verdicts (:attr:`bvsr_cad.memo.InMemory.kept`),
    for :class:`Checks` to keep while that state is unchanged."""
    early = InMemory()
    _print_groups(early, exp, memo, set(sliced_now))
    if meshes:
        _mesh_groups(early, exp, memo)
    if robot:
        _robot_groups(early, exp, claim=True)
    return early.kept


#: In the export's folder while a build checks it, one per part of the robot descriptions' checks
#: (:data:`~bvsr_cad.checks.robot.ROBOT_PARTS`): made by whichever of its two processes starts that
#: part first (:func:`claim_robot_checks`); removed by :meth:`Checks.finish`.
ROBOT_CLAIM_FILES = tuple(f".robot-checks-{i + 1}.claim" for i in range(len(ROBOT_PARTS)))


def claim_robot_checks(root: str | Path, part: int) -> bool:
    """Whether this process takes part ``part`` (0-based) of the robot descriptions' checks of the
    export at ``root``: True for the first to ask (its file of :data:`ROBOT_CLAIM_FILES` made,
    atomically), False for any later."""
    import os

    try:
        os.close(
            os.open(Path(root) / ROBOT_CLAIM_FILES[part], os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        )
    except FileExistsError:
        return False
    return True


class _Printability:
    """The second process (started by ``beside``, given the export's path and its manifest): the
    printability checks, the slowest group, and the mold checks; with ``meshes`` the part meshes'
    and the masses' after them; with ``robot`` the robot descriptions' last
    (:func:`printability_groups`). None on one core, or where it could not start."""

    def __init__(
        self,
        exp: Export,
        sliced_now: Collection[str],
        say: Callable[[str], None],
        beside: StartBeside | None,
        meshes: bool = False,
        robot: bool = False,
    ):
        self.say = say
        self.proc = (
            None if beside is None else beside(exp.root, sliced_now, meshes, robot, exp.manifest)
        )
        #: Whether it took the part meshes' and the masses' checks; the robot descriptions'.
        self.meshes, self.robot = self.proc is not None and meshes, self.proc is not None and robot
        self._waited = False
        if self.proc is not None:
            after = [
                what
                for what, asked in (
                    ("the part meshes and the masses", meshes),
                    ("the robot descriptions", robot),
                )
                if asked
            ]
            say(
                "printability and molds: started in a second process"
                + (f" ({' and '.join(after)} after them)" if after else "")
            )

    def keep(self, early: Memo) -> None:
        """Its groups' verdicts recorded in ``early`` under the state of their reads
        (:func:`printability_groups`), waited for once; none where it was lost (then each group runs
        here)."""
        if self.proc is None or self._waited:
            return
        self._waited = True
        for name, (inputs, verdicts) in self.proc.result_or(
            dict, self.say, "printability and molds"
        ).items():
            early(name, inputs, lambda verdicts=verdicts: verdicts)

    def close(self) -> None:
        if self.proc is not None:
            self.proc.close()


class Checks:
    """Every check on an export, in two steps: :meth:`start` runs the groups that read only the CAD
    files (the part meshes here, the printability and mold checks in a second process), so that a
    build can run them before its analyses are in; :meth:`finish` runs the rest on the export as it
    is then and returns every result in one order.

    A group run early (here, at :meth:`start` or :meth:`robot_ahead`, or in the second process) is
    kept in an in-memory memo (:class:`bvsr_cad.memo.InMemory`) under the state of its reads taken
    just before it read them (its manifest values, its files' names, sizes and modification times:
    :func:`_state`). :meth:`finish` asks it for each group with the state as it is then: a group
    whose reads changed since runs again, saying its progress line, so the results are what one run
    on the final export gives.

    ``meshes_beside``: the part meshes' and the masses' checks go to the second process too, after
    its own groups, for a caller with work of its own until :meth:`finish` (a build: its drawings,
    views and robot files; the second process, started later on the print files, would otherwise end
    before the build's process and leave it to work alone). ``robot_beside``: the robot
    descriptions' checks go there too, last, unless :meth:`robot_ahead` takes them here first
    (:func:`claim_robot_checks`): for a build that wrote its robot files before it started the
    checks, they go to whichever process is free first (run here after the build's own stages, they
    took its last seconds on one core while the other processes had ended; run there, the second
    process was the one left alone). :meth:`finish` runs this process's groups before it waits.

    ``manifest`` (here, in :meth:`robot_ahead` and :meth:`finish`): the export's manifest as it is
    then, for a build that writes its file once, at the end (None: read from the folder)."""

    def __init__(
        self,
        root: str | Path,
        progress: Callable[[str], None] | None = None,
        *,
        run_slicer: bool = False,
        beside: StartBeside | None = None,
        store: Memo | None = None,
        meshes_beside: bool = False,
        robot_beside: bool = False,
        manifest: dict[str, Any] | None = None,
    ):
        self.root, self.say, self.store = root, progress or _quiet, store
        self._exp = Export.open(root, manifest)
        self.sliced_now = slice_stls(self._exp, progress=self.say) if run_slicer else {}
        #: The groups run early, by name, under the state of their reads (:func:`_group`).
        self._early = InMemory()
        self._printability = _Printability(
            self._exp, self.sliced_now, self.say, beside, meshes_beside, robot_beside
        )
        #: The CPU seconds of the second process, once :meth:`finish` has its verdicts (else None).
        self.cpu_s: float | None = None

    @classmethod
    def start(cls, root: str | Path, progress: Callable[[str], None] | None = None, **kw) -> Checks:
        """Open the export, start the printability and mold checks (in a second process) and run the
        part meshes' and the masses' here (unless they went there too)."""
        run = cls(root, progress, **kw)
        if not run._printability.meshes:
            try:
                _mesh_groups(run._early, run._exp, CheckMemo(run._exp, run.store), run.say)
            except BaseException:
                run.close()
                raise
        return run

    def robot_ahead(self, manifest: dict[str, Any] | None = None) -> None:
        """The robot descriptions' checks now, on the export as it is (a build that wrote its robot
        files before its analyses were in); :meth:`finish` keeps their results while their reads are
        unchanged. Where they went to the second process too (``robot_beside``), only the parts it
        has not begun (:func:`claim_robot_checks`)."""
        exp = Export.open(self.root, manifest)
        _robot_groups(self._early, exp, self._printability.robot, self.say)

    def finish(self, manifest: dict[str, Any] | None = None) -> list[CheckResult]:
        """Every result, in the order of :func:`run_checks`."""
        say, early, beside = self.say, self._early, self._printability
        exp = Export.open(self.root, manifest)  # as it is now (the manifest may have grown)
        memo = CheckMemo(exp, self.store)
        try:
            # This process's own groups first; each group the second process took is waited for
            # when it is asked.
            say("pentagon layout")
            own = check_layout(exp) + check_paper(exp)
            say("analyses")
            own += check_analyses(exp)
            if beside.robot:
                beside.keep(early)
            own += self._robot(exp)
            if beside.meshes:
                beside.keep(early)
            results = _mesh_groups(early, exp, memo, say) + own
            beside.keep(early)
            results += _print_groups(early, exp, memo, self.sliced_now, say)
            if beside.proc is not None:
                self.cpu_s = beside.proc.cpu_s
        finally:
            self.close()
            for claim in ROBOT_CLAIM_FILES:
                (Path(self.root) / claim).unlink(missing_ok=True)
        return results

    def _robot(self, exp: Export) -> list[CheckResult]:
        """The robot descriptions' checks: each part's verdicts from whichever process ran it, where
        every part ran on the reads as they are now; else all of them run here."""
        now = {"reads": _state(exp, robot_reads(exp))}
        # A part not kept is not run alone (make: None): the whole group runs, as one line.
        kept = [self._early(what, now, lambda: None)[0] for _part, what in ROBOT_PARTS]
        if None not in kept:
            return [r for verdicts in kept for r in verdicts]
        self.say("robot descriptions (URDF, MJCF, MuJoCo, PyBullet)")
        return check_robot(exp)

    def close(self) -> None:
        """Stop the printability process if it still runs (a failed build)."""
        self._printability.close()


def run_checks(
    root: str | Path,
    progress: Callable[[str], None] | None = None,
    *,
    run_slicer: bool = False,
    beside: StartBeside | None = None,
    store: Memo | None = None,
) -> list[CheckResult]:
    """Run every check on the export at ``root``; the results come in the same order either way.

    Args:
        root: the export folder.
        progress: called with one line per step (None: silent).
        run_slicer: slice the printed STLs the slice cache does not hold first.
        beside: starts the printability checks' second process (None: every group runs here); the
            command's :func:`bvsr_cad.pipeline.processes.checks_process.run_checks` gives one on two
            cores or more.
        store: the memo the verdicts are kept through (:class:`bvsr_cad.memo.Memo`, as
            :mod:`bvsr_cad.checks.memo` uses it; None: every check runs).

    Returns:
        Every check's result; the export passes when none has ``passed`` False.

    The checks never start the slicer: the ``slice:*`` results come from the slice cache. With
    ``run_slicer`` (``bvsr check --slice``), every printed STL the cache does not hold is sliced
    first (:func:`~bvsr_cad.checks.slicer.slice_stls`). With ``store`` the groups whose
    files and manifest values are unchanged (the meshes, the molds, the printed STLs, the twin's
    envelope) take their verdicts from it.

    Raises:
        ExportError: the folder is not a readable export.
        SlicerMissingError: ``run_slicer`` and PrusaSlicer is not installed.
    """
    return Checks.start(root, progress, run_slicer=run_slicer, beside=beside, store=store).finish()

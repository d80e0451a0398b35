"""Every check on an export, in one list."""

from __future__ import annotations

import json
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

from ..memo import Memo
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


def _mesh_checks(exp: Export, memo: CheckMemo) -> dict[str, list[CheckResult]]:
    """The part meshes' checks of ``exp``, by part."""
    return {part["name"]: _part_mesh(exp, memo, part) for part in exp.parts}


#: Starts the printability checks' second process: ``beside(root, sliced_now, meshes, robot,
#: manifest)`` runs :func:`printability_groups` on the export at ``root`` whose manifest is
#: ``manifest`` in another process and returns its handle
#: (``result_or(here, say, what)``, ``close()``, ``cpu_s``), or None where it could not start. The
#: build hands one to :class:`Checks` (:mod:`bvsr_cad.pipeline.processes.checks_process`); the
#: checks start no process.
StartBeside = Callable[[Path, Collection[str], bool, bool, dict[str, Any]], Any]


def printability_groups(
    exp: Export,
    sliced_now: Collection[str],
    memo: CheckMemo,
    meshes: bool = False,
    robot: bool = False,
) -> dict[str, Any]:
    """The second process's work: the printability checks and the mold checks of ``exp`` (verdicts
    of unchanged inputs from ``memo``), by group; with ``meshes`` the part meshes' and the masses'
    checks after them (``"part_mesh"``: by part); with ``robot`` the robot descriptions' checks
    last, unless the build's own process took them first (:func:`claim_robot_checks`)."""
    out: dict[str, Any] = {
        "printability": check_printability(exp, sliced_now=set(sliced_now), memo=memo),
        "molds": _mold_checks(exp, memo),
    }
    if meshes:
        out["part_mesh"] = _mesh_checks(exp, memo)
        out["masses"] = check_masses(exp, memo)
    if robot and "robot" in exp.manifest:
        out["robot"] = {
            i: part(exp)
            for i, (part, _what) in enumerate(ROBOT_PARTS)
            if claim_robot_checks(exp.root, i)
        }
    return out


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
    """The printability checks, the slowest group, and the mold checks in a second process (given
    the export's path and its manifest) while the other groups run here; with
    ``meshes`` the part meshes' and the masses' checks too, after them. On one core, or when the
    process fails, they run here."""

    def __init__(
        self,
        exp: Export,
        sliced_now: Collection[str],
        say: Callable[[str], None],
        beside: StartBeside | None,
        memo: CheckMemo | None = None,
        meshes: bool = False,
        robot: bool = False,
    ):
        self.exp, self.sliced_now, self.say = exp, sliced_now, say
        self.memo = memo or CheckMemo(exp)
        self.proc = None
        self._got: dict[str, Any] | None = None
        if beside is not None:
            self.proc = beside(exp.root, sliced_now, meshes, robot, exp.manifest)
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

    def _from_process(self) -> dict[str, Any]:
        """The second process's verdicts by group; empty without one, or when it was lost (then each
        group runs here)."""
        if self.proc is None:
            return {}
        if self._got is None:
            self._got = self.proc.result_or(dict, self.say, "printability and molds")
        return self._got

    def results(self) -> list[CheckResult]:
        got = self._from_process()
        if "printability" in got:
            return got["printability"]
        self.say("printability")
        return check_printability(self.exp, sliced_now=self.sliced_now, memo=self.memo)

    def molds(self) -> list[CheckResult]:
        got = self._from_process()
        if "molds" in got:
            return got["molds"]
        self.say("molds")
        return _mold_checks(self.exp, self.memo)

    def part_meshes(self) -> tuple[dict[str, list[CheckResult]], list[CheckResult]] | None:
        """The part meshes' verdicts by part and the masses' from the second process, or None (not
        asked of it, or it was lost)."""
        got = self._from_process()
        return (got["part_mesh"], got["masses"]) if "part_mesh" in got else None

    def robot(self) -> dict[int, list[CheckResult]] | None:
        """The verdicts of the parts of the robot descriptions' checks the second process took, by
        part, or None (not asked of it, or it was lost)."""
        return self._from_process().get("robot")

    def close(self) -> None:
        if self.proc is not None:
            self.proc.close()


#: The manifest sections the printability checks read (besides the files they name).
PRINTABILITY_READS = ("parts", "print_jobs", "fabrication", "assembly", "rigid_tail")


def _printability_reads(exp: Export) -> str:
    """The manifest sections the printability checks read, and the size and modification time of
    every file those sections name."""
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
    return json.dumps([sections, _state(exp, (sorted(names), None))[1]], sort_keys=True)


def _state(exp: Export, reads: tuple) -> tuple:
    """A group's reads (file names, manifest values) with each file's size and modification time: an
    early verdict stands only while all of them are unchanged."""
    stats = []
    for rel in reads[0]:
        try:
            st = (exp.root / rel).stat()
            stats.append((st.st_size, st.st_mtime_ns))
        except OSError:
            stats.append(None)
    return reads, stats


def _kept(
    early: tuple[tuple, list[CheckResult]] | None,
    exp: Export,
    reads: tuple,
    check: Callable[[], list[CheckResult]],
    say: Callable[[str], None],
    what: str,
) -> list[CheckResult]:
    """A group run early (``(its state then, its results)``): its results while its reads are
    unchanged, else ``check()`` run now on ``exp``."""
    if early is not None and early[0] == _state(exp, reads):
        return early[1]
    say(what)
    return check()


class Checks:
    """Every check on an export, in two steps: :meth:`start` runs the groups that read only the CAD
    files (the part meshes here, the printability and mold checks in a second process), so that a
    build can run them before its analyses are in; :meth:`finish` runs the rest on the export as it
    is then and returns every result in one order. A group started early whose reads changed since
    (its manifest values, its files' names, sizes or modification times; for the printability
    checks, the manifest sections they read) is run again: the results are what one run on the final
    export gives.

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
        self.root, self.say, self.store = root, progress or (lambda _m: None), store
        self.beside, self.meshes_beside, self.robot_beside = beside, meshes_beside, robot_beside
        self.sliced_now: dict = {}
        self._mesh: dict[str, tuple[tuple, list[CheckResult]]] = {}
        self._masses: tuple[tuple, list[CheckResult]] | None = None  # (its reads then, its results)
        # Of groups the second process runs: their reads' state when it started.
        self._mesh_state: dict[str, tuple] = {}
        self._masses_state: tuple | None = None
        self._robot: tuple[tuple, list[CheckResult]] | None = (
            None  # the same, of every part of the robot's
        )
        self._robot_own: dict[
            int, list[CheckResult]
        ] = {}  # the parts :meth:`robot_ahead` ran here, by part
        self._robot_own_state: tuple | None = None  # their reads then
        self._robot_state: tuple | None = (
            None  # the robot's reads when the second process started on them
        )
        self._molds_state: tuple | None = None  # the molds' reads when the early checks started
        self._printability: _Printability | None = None
        self._printability_reads = ""
        #: The CPU seconds of the second process, once :meth:`finish` has its verdicts (else None).
        self.cpu_s: float | None = None
        exp = Export.open(root, manifest)
        if run_slicer:
            self.sliced_now = slice_stls(exp, progress=self.say)
        self._exp = exp

    @classmethod
    def start(cls, root: str | Path, progress: Callable[[str], None] | None = None, **kw) -> Checks:
        """Open the export, start the printability and mold checks (in a second process) and run the
        part meshes' and the masses' here."""
        run = cls(root, progress, **kw)
        exp, say = run._exp, run.say
        memo = CheckMemo(exp, run.store)
        # What the second process is about to read: its verdicts stand only while these are
        # unchanged.
        run._printability_reads = _printability_reads(exp)
        run._molds_state = _state(exp, molds_reads(exp))
        run._printability = _Printability(
            exp, run.sliced_now, say, run.beside, memo, run.meshes_beside, run.robot_beside
        )
        if run.robot_beside and run._printability.proc is not None:
            run._robot_state = _state(exp, robot_reads(exp))
        if run.meshes_beside and run._printability.proc is not None:
            run._mesh_state = {
                part["name"]: _state(exp, part_mesh_reads(part)) for part in exp.parts
            }
            run._masses_state = _state(exp, masses_reads(exp))
            return run
        try:
            for part in exp.parts:
                say(f"mesh {part['name']}")
                reads = part_mesh_reads(part)
                run._mesh[part["name"]] = (_state(exp, reads), _part_mesh(exp, memo, part))
            say("masses")  # on the meshes just read
            run._masses = (_state(exp, masses_reads(exp)), check_masses(exp, memo))
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
        if "robot" not in exp.manifest:
            return
        state = _state(exp, robot_reads(exp))
        for i, (part, what) in enumerate(ROBOT_PARTS):
            if self._robot_state is None or claim_robot_checks(self.root, i):
                self.say(what)
                self._robot_own[i] = part(exp)
        self._robot_own_state = state

    def finish(self, manifest: dict[str, Any] | None = None) -> list[CheckResult]:
        """Every result, in the order of :func:`run_checks`."""
        say = self.say
        exp = Export.open(self.root, manifest)  # as it is now (the manifest may have grown)
        memo = CheckMemo(exp, self.store)
        try:
            # This process's own groups first, then what the second process ran (waited for here).
            say("pentagon layout")
            own = check_layout(exp) + check_paper(exp)
            say("analyses")
            own += check_analyses(exp)
            started = self._printability
            own += self._robot_results(exp)
            results = self._mesh_results(exp, memo) + own
            results += self._printability_results(exp, memo)
            if started is not None and started.proc is not None:
                self.cpu_s = started.proc.cpu_s
        finally:
            self.close()
            for claim in ROBOT_CLAIM_FILES:
                (Path(self.root) / claim).unlink(missing_ok=True)
        return results

    def _robot_results(self, exp: Export) -> list[CheckResult]:
        """The robot's checks: each part from whichever process ran it, all on the files as they
        were when the second process started (else, or where a part is missing, all of them run
        here)."""
        printability = self._printability
        parts, state = dict(self._robot_own), self._robot_own_state
        if self._robot_state is not None and printability is not None:
            beside_robot = printability.robot()  # waits for the second process
            if beside_robot is not None and (not parts or state == self._robot_state):
                parts, state = {**parts, **beside_robot}, self._robot_state
            elif beside_robot is None:
                parts = {}
        if len(parts) == len(ROBOT_PARTS):
            self._robot = (state, [r for i in range(len(ROBOT_PARTS)) for r in parts[i]])
        return _kept(
            self._robot,
            exp,
            robot_reads(exp),
            lambda: check_robot(exp),
            self.say,
            "robot descriptions (URDF, MJCF, MuJoCo, PyBullet)",
        )

    def _mesh_results(self, exp: Export, memo: CheckMemo) -> list[CheckResult]:
        """The part meshes' and the masses' checks: from :meth:`start` or the second process where
        their reads are unchanged, else run here."""
        printability = self._printability
        beside = (
            printability.part_meshes() if self._mesh_state and printability is not None else None
        )
        if beside is not None:
            self._mesh = {
                name: (self._mesh_state[name], r)
                for name, r in beside[0].items()
                if name in self._mesh_state
            }
            self._masses = (self._masses_state, beside[1])
        results: list[CheckResult] = []
        for part in exp.parts:
            results.extend(
                _kept(
                    self._mesh.get(part["name"]),
                    exp,
                    part_mesh_reads(part),
                    lambda part=part: _part_mesh(exp, memo, part),
                    self.say,
                    f"mesh {part['name']}",
                )
            )
        results.extend(
            _kept(
                self._masses,
                exp,
                masses_reads(exp),
                lambda: check_masses(exp, memo),
                self.say,
                "masses",
            )
        )
        return results

    def _printability_results(self, exp: Export, memo: CheckMemo) -> list[CheckResult]:
        """The printability and mold checks: the second process's where it started on the export
        as it is now, else run here."""
        printability = self._printability
        fresh = printability is not None and self._printability_reads == _printability_reads(exp)
        if not fresh:
            if printability is not None:
                printability.close()
            printability = self._printability = _Printability(
                exp, self.sliced_now, self.say, None, memo
            )
        results = printability.results()
        if fresh and self._molds_state == _state(exp, molds_reads(exp)):
            return results + printability.molds()
        # Started on files that changed since: run on the export as it is now.
        self.say("molds")
        return results + _mold_checks(exp, memo)

    def close(self) -> None:
        """Stop the printability process if it still runs (a failed build)."""
        if self._printability is not None:
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

"""The analyses of a build (workspace, clearance, joint limits, calibration): from the cache, or run
from the parameter file in a second process while the build's own process makes and writes the tail
(else, where that process could not start or was lost, here at the end).

Two stages: the geometry analyses (the joint limits and the tip's clearance map, from the tail's
solids) and the rest. With the geometry cached the tail's solids are unchanged: the CAD stages come
from the cache too, and the analyses take both cores while this process waits for them.
"""

from __future__ import annotations

import pickle
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..analysis.limits import per_joint_rad
from ..analysis.run import BESIDE_BUILD_THREADS, BESIDE_IDLE_BUILD_THREADS
from ..parameters.load import params_sha256
from ..process import kernel_threads
from .processes.analyses_process import (
    drop_geometry_ahead,
    keep_rest,
    take_geometry_ahead,
)
from .processes.worker import SecondProcess, result_or
from .runner import Runner, Stage

#: In the geometry analyses' cache entry: :class:`bvsr_cad.analysis.run.GeometryAnalyses`, pickled.
GEOMETRY_FILE = "geometry.pkl"
#: In the analyses' cache entry: their results, pickled.
ANALYSES_FILE = "analyses.pkl"


class Analyses:
    """The analyses of the build ``run`` of ``params``: :meth:`begin` looks them up in the cache and
    starts their second process where they must be run; :meth:`limits_ahead` gives the joint limits
    as soon as they exist, :meth:`results` all of them."""

    def __init__(self, run: Runner, stage: Stage, geometry_stage: Stage, params: Path):
        self.run, self.stage, self.geometry_stage, self.params = run, stage, geometry_stage, params
        self.cached: Path | None = run.hit(stage)
        self.geometry_hit: Path | None = run.hit(geometry_stage) if self.cached is None else None
        self.geometry = None
        self.process: SecondProcess | None = None
        self._kernel_before: int | None = None

    @classmethod
    def begin(
        cls,
        run: Runner,
        stage: Stage,
        geometry_stage: Stage,
        params: Path,
        standby: SecondProcess | None,
    ) -> Analyses:
        """Look the analyses up and, where they must be run, start them in a second process
        (``standby``, started ahead by the command, given the work; else a new one). ``standby`` is
        stopped at once when the analyses are cached: its imports and its head start must not take a
        core from the stages."""
        self = cls(run, stage, geometry_stage, params)
        if self.cached is not None and standby is not None:
            standby.close()
        if self.geometry_hit is not None:
            t = time.perf_counter()
            self.geometry = pickle.loads((self.geometry_hit / GEOMETRY_FILE).read_bytes())
            run.record(geometry_stage, True, time.perf_counter() - t)
        if self.cached is None:
            folder = run.folder
            work = [
                str(params.resolve()),
                params_sha256(params),
                str(self.geometry_hit / GEOMETRY_FILE) if self.geometry_hit is not None else "",
                str(
                    BESIDE_BUILD_THREADS if self.geometry_hit is None else BESIDE_IDLE_BUILD_THREADS
                ),
                str(folder.resolve()),
                run.spec.name,
            ]  # absolute: the process works in another folder
            self.process = (
                standby
                if standby is not None and standby.begin(work, folder)
                else SecondProcess.start(
                    "bvsr_cad.pipeline.processes.analyses_process", work, folder, run.say
                )
            )
            if self.process is not None:
                run.say("analyses: started in a second process")
                # Both cores are busy from here to the end: OCCT's own threads would only contend.
                self._kernel_before = kernel_threads(1)
        return self

    def limits_ahead(self) -> list[float] | None:
        """The joint limits, if the cache or the analyses' process has given them by now (None where
        the analyses are cached: read with them, there is no process to wait for)."""
        if self.cached is not None:
            return None
        ahead = (
            self.geometry
            if self.geometry is not None or self.process is None
            else take_geometry_ahead(self.run.folder)
        )
        return per_joint_rad(ahead.limits) if ahead is not None else None

    def results(self, here: Callable[[Any], Any]) -> tuple[Any, bool]:
        """``(results, drawn)``: from the cache, or the second process's (with their pictures drawn
        there), or ``here(geometry)`` run in this process where it was lost. New results go into the
        cache."""
        run = self.run
        if self.cached is not None:
            t = time.perf_counter()
            results = pickle.loads((self.cached / ANALYSES_FILE).read_bytes())
            run.record(self.stage, True, time.perf_counter() - t)
            return results, False
        results, drawn = result_or(
            self.process, lambda: (here(self.geometry), False), run.say, "analyses"
        )
        if self.geometry is None:
            run.record(self.geometry_stage, False, results.geometry_seconds)

            def keep_geometry(folder: Path) -> None:
                (folder / GEOMETRY_FILE).write_bytes(pickle.dumps(results.geometry))
                keep_rest(run.folder, folder)  # the analyses' process made it: for the next edit

            run.put(self.geometry_stage, keep_geometry)
        run.put(
            self.stage, lambda folder: (folder / ANALYSES_FILE).write_bytes(pickle.dumps(results))
        )
        # Their own time (in the second process, beside the other stages); the wait was shorter.
        run.record(self.stage, False, results.seconds)
        run.log.process("analyses", self.process.cpu_s if self.process is not None else None)
        drop_geometry_ahead(
            run.folder
        )  # not taken (made after the robot's stage, or by a process since lost)
        return results, drawn

    def close(self) -> None:
        """Stop the second process if it still runs (a failed build)."""
        if self.process is not None:
            self.process.close()

    def restore(self) -> None:
        """Give OCCT back the threads it had before the process started."""
        if self._kernel_before is not None:
            kernel_threads(self._kernel_before)
            self._kernel_before = None

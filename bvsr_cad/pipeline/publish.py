"""An export's folder: checked, built beside it, published atomically, or reused whole from the
cache.

A build writes into a temporary folder beside the output (claimed by its process) and moves it into
place only when every file was written, so a failure leaves any earlier export untouched and no
partial one; the next build removes what dead builds left (:func:`clean_leftovers`).

A rebuild of a file the cache holds whole (:func:`reuse_whole`) needs only the parameters, the
cache and the environment the checks depend on: this module imports none of the CAD kernel, the
mesh libraries or the simulator, so that `bvsr build` of an unchanged file answers without their
imports (seconds); :mod:`bvsr_cad.pipeline.stages` builds what it does not find.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from ..checks.environment import environment_state
from ..checks.result import CheckResult
from ..errors import BadInput
from ..exporters.manifest_file import write_manifest
from ..parameters.load import load_spec
from ..parameters.tables import TailSpec
from .cache import ORPHAN_AGE_S, OWNER_FILE, ArtifactCache, claim, copy_tree, owner_alive, stage_key
from .processes.worker import cpu_seconds

Progress = Callable[[str], None]


class OutputError(ValueError, BadInput):
    """The output path cannot take an export (exit code 2)."""


@dataclass
class BuildResult:
    out_dir: Path
    results: list[CheckResult]
    seconds: float
    stages: list[dict] = field(default_factory=list)  # {"stage", "status": reused|built, "seconds"}
    #: CPU seconds by process: ``build`` (this one, since the build opened) and each second process
    #: that gave its result (``analyses``, ``checks``); see :meth:`StageLog.cpu_s`.
    cpu_s: dict[str, float] = field(default_factory=dict)

    @property
    def failed(self) -> list[CheckResult]:
        """The checks that failed (informational and skipped ones do not fail a build)."""
        return [r for r in self.results if r.passed is False]

    def summary(self) -> dict:
        """The build as `bvsr build --json` prints it: the folder, the wall seconds, whether every
        check passed and the names of those that failed, each stage's line and the CPU seconds by
        process."""
        return {
            "out": str(self.out_dir),
            "seconds": round(self.seconds, 2),
            "passed": not self.failed,
            "failed_checks": [r.name for r in self.failed],
            "stages": self.stages,
            "cpu_seconds": self.cpu_s,
        }


@dataclass
class StageLog:
    """Per stage: reused from the cache or built, and the seconds it took (``bvsr build`` prints
    it); and the CPU seconds of the build's processes."""

    say: Progress
    stages: list[dict] = field(default_factory=list)
    cpu0: float = field(
        default_factory=cpu_seconds
    )  # this process's CPU seconds when the build opened
    processes: dict[str, float] = field(default_factory=dict)

    def record(self, stage: str, reused: bool, seconds: float) -> None:
        self.stages.append(
            {
                "stage": stage,
                "status": "reused" if reused else "built",
                "seconds": round(seconds, 3),
            }
        )
        self.say(f"stage {stage}: {'reused' if reused else 'built'} in {seconds:.2f} s")

    def process(self, name: str, cpu_s: float | None) -> None:
        """A second process's CPU seconds (None: it gave no result, its work ran here or was not
        needed)."""
        if cpu_s is not None:
            self.processes[name] = cpu_s

    def cpu_s(self) -> dict[str, float]:
        """CPU seconds so far, by process: ``build``, this one since the build opened (its
        parameters loaded; the pipeline's imports come after) and the second processes recorded,
        each from its own start (its imports included). A CPU-bound build on two cores has their sum
        near twice its seconds."""
        return {
            "build": round(cpu_seconds() - self.cpu0, 2),
            **{k: round(v, 2) for k, v in self.processes.items()},
        }


def volatile(t0: float, log: StageLog) -> dict:
    """The manifest's one place for what changes from build to build of the same file."""
    return {
        "built_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "build_seconds": time.perf_counter() - t0,
        "stages": log.stages,
        "cpu_seconds": log.cpu_s(),
    }


def check_output(out_dir: Path) -> None:
    """Raises :class:`OutputError` when ``out_dir`` is a file or a non-empty folder that is not an
    export."""
    if out_dir.exists():
        if not out_dir.is_dir():
            raise OutputError(f"{out_dir}: exists and is not a folder; choose another -o")
        if any(out_dir.iterdir()) and not (out_dir / "manifest.json").is_file():
            raise OutputError(
                f"{out_dir}: a non-empty folder that is not a bvsr export (no manifest.json); "
                "refusing to replace it; choose another -o"
            )


def clean_leftovers(out_dir: Path) -> list[Path]:
    """Remove what dead builds of ``out_dir`` left beside it: temporary folders whose building
    process is gone (killed with SIGKILL, a power cut) and replaced exports never deleted. A live
    build's folders are kept. Returns what was removed."""
    removed = []
    parent = out_dir.parent
    if not parent.is_dir():
        return removed
    for folder in parent.glob(f".{out_dir.name}.tmp-*"):
        if folder.is_dir() and not owner_alive(folder):
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    for folder in parent.glob(f".{out_dir.name}.old-*"):
        try:
            renamed_s = (
                int(folder.name.rsplit("-", 1)[1]) / 1000.0
            )  # publish names it by the time, in ms
        except ValueError:
            continue
        if folder.is_dir() and time.time() - renamed_s > ORPHAN_AGE_S:
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


def publish(tmp: Path, out_dir: Path) -> None:
    """Move the finished ``tmp`` into place as ``out_dir``, replacing an earlier export (kept on
    failure).

    Args:
        tmp: the build's temporary folder, beside ``out_dir`` (one rename away, on the same file
            system).
        out_dir: the export folder; an earlier export there is replaced only once ``tmp`` is in
            place.
    """
    (tmp / OWNER_FILE).unlink(missing_ok=True)
    old = None
    if out_dir.exists():
        old = out_dir.with_name(f".{out_dir.name}.old-{int(time.time() * 1000)}")
        out_dir.rename(old)
    try:
        tmp.rename(out_dir)
    except BaseException:
        if old is not None:
            old.rename(out_dir)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def temporary_folder(out_dir: Path) -> Path:
    """A new folder beside ``out_dir`` for a build of it, claimed by this process."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.tmp-", dir=out_dir.parent))
    claim(tmp)
    return tmp


def data_path(spec: TailSpec, params: Path) -> Path | None:
    """The calibration's data file (read by the measurement comparison; relative to the parameter
    file's folder), or None when the file names none."""
    return (
        (params.resolve().parent / spec.calibration.data_file).resolve()
        if spec.calibration.data_file
        else None
    )


@dataclass
class OpenedBuild:
    """A build's start: its parameters, its output (checked, dead builds' leftovers removed) and the
    key of the whole export: the parameter file's bytes, the calibration data's and the checks'
    environment."""

    params: Path
    spec: TailSpec
    out: Path
    cache: ArtifactCache | None
    data: bytes
    export_key: str
    log: StageLog
    t0: float


def open_build(
    params: str | Path, out_dir: str | Path | None, say: Progress, use_cache: bool
) -> OpenedBuild:
    """Load ``params`` and prepare ``out_dir`` (default ``exports/<name>``) for a build.

    Args:
        params: the parameter file.
        out_dir: the export folder (None: ``exports/<name>``).
        say: called with one progress line at a time.
        use_cache: use the artifact cache (False: ``--no-cache``).

    Returns:
        The loaded parameters, the output folder, the cache, the calibration data and the export's
        key.

    Raises:
        ParamError: the parameter file is unreadable or describes an impossible tail.
        OutputError: ``out_dir`` cannot be replaced.
    """
    t0 = time.perf_counter()
    params = Path(params)
    spec = load_spec(params)
    out = Path(out_dir) if out_dir is not None else Path("exports") / spec.name
    check_output(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for folder in clean_leftovers(out):
        say(f"removed {folder.name}: left by a build that did not finish")
    cache = ArtifactCache() if use_cache else None
    for folder in cache.clean_leftovers() if cache is not None else []:
        say(
            f"removed the cache's {folder.parent.name}/{folder.name}: an entry a build did not "
            "finish"
        )
    path = data_path(spec, params)
    data = path.read_bytes() if path is not None and path.is_file() else b""
    if path is not None and not path.is_file():
        say(
            f"calibration.data_file = {spec.calibration.data_file!r}: {path} not found (it is "
            "relative to the "
            "parameter file's folder); the export compares no measurements "
            "(analysis/measurements.json says why)"
        )
    key = stage_key(
        "export", params=params.read_bytes(), data=data, environment=environment_state()
    )
    return OpenedBuild(params, spec, out, cache, data, key, StageLog(say), t0)


def reuse_whole(build: OpenedBuild) -> BuildResult | None:
    """Publish the cache's whole export for ``build`` (its manifest's volatile section rewritten).

    Args:
        build: what :func:`open_build` prepared.

    Returns:
        The published build, or None when the cache does not hold this export.
    """
    hit = build.cache.get(build.export_key) if build.cache is not None else None
    if hit is None:
        return None
    tmp = temporary_folder(build.out)
    try:
        t = time.perf_counter()
        copy_tree(hit, tmp)
        manifest = json.loads((tmp / "manifest.json").read_text())
        build.log.record("export", True, time.perf_counter() - t)
        manifest["volatile"] = volatile(build.t0, build.log)
        write_manifest(tmp, manifest)
        publish(tmp, build.out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return BuildResult(
        build.out,
        [CheckResult(**c) for c in manifest["checks"]],
        time.perf_counter() - build.t0,
        build.log.stages,
        manifest["volatile"]["cpu_seconds"],
    )


__all__ = [
    "BuildResult",
    "OpenedBuild",
    "OutputError",
    "StageLog",
    "check_output",
    "clean_leftovers",
    "data_path",
    "open_build",
    "publish",
    "reuse_whole",
    "temporary_folder",
    "volatile",
]

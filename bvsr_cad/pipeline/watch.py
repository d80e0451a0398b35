"""`bvsr watch`: rebuild an export each time its parameter file (or calibration data) is saved.

It watches the folders of the parameter file and of the calibration data file
it names (``calibration.data_file``, read by the build's measurement
comparison) with watchfiles (editors save by writing a new file and renaming
it over the old one), waits until the saves settle (debounce), prints which
keys changed (or that the data changed), rebuilds through the cache (so only
the stages whose inputs changed run again) and says which stages it reused.
When an edit names another data file, that file is watched from then on.
A bad edit prints the error and leaves the last good export in place; the
next save tries again. Ctrl-C stops it; a build in progress is abandoned and
its temporary folder removed, as for `bvsr build`.
"""

from __future__ import annotations

import functools
import threading
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..assembly.assemble import Assembly
from ..parameters.load import ParamError
from ..parts.kernel import GeometryError
from .publish import BuildResult, OutputError
from .stages import build_export

DEBOUNCE_MS = 400
#: How often the watcher also compares the files with what was last built, without an event: a save
#: before its watcher was listening (during the first build, or between the last "watching" line and
#: the watcher's start) sends no event it can see, and was missed until the next save (CI saw one).
CATCH_UP_MS = 500


def changed_keys(old: dict[str, Any], new: dict[str, Any], prefix: str = "") -> list[str]:
    """``table.key: old -> new`` for every value that differs between two parsed parameter files."""
    out = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key), new.get(key)
        name = f"{prefix}{key}"
        if isinstance(a, dict) and isinstance(b, dict):
            out += changed_keys(a, b, name + ".")
        elif a != b:
            out.append(
                f"{name}: {a!r} -> {b!r}"
                if key in old and key in new
                else f"{name}: {'added' if key in new else 'removed'}"
            )
    return out


def _read(path: Path) -> dict[str, Any] | None:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return None


def _data_file(params: Path, data: dict[str, Any] | None) -> Path | None:
    """The calibration data file a parsed parameter file names (relative to its folder, as the build
    reads it), or None."""
    cal = (data or {}).get("calibration")
    name = cal.get("data_file") if isinstance(cal, dict) else None
    return (params.parent / name).resolve() if isinstance(name, str) and name else None


def _bytes(path: Path | None) -> bytes | None:
    try:
        return path.read_bytes() if path is not None else None
    except OSError:
        return None


@dataclass
class _Watched:
    """What the watcher last acted on: the parameter file (``params``) as parsed (``last``), the
    calibration data file it names (``data``) and that file's bytes, and the bytes of both files
    (``seen``, read before a build: a save during it is new)."""

    params: Path
    last: dict[str, Any]
    data: Path | None
    data_bytes: bytes | None
    seen: tuple[bytes | None, bytes | None]

    @classmethod
    def read(cls, params: Path) -> _Watched:
        last = _read(params) or {}
        data = _data_file(params, last)
        data_bytes = _bytes(data)
        return cls(params, last, data, data_bytes, (_bytes(params), data_bytes))

    def files(self) -> set[Path]:
        return {self.params} | ({self.data} if self.data else set())


def watch(
    params: str | Path,
    out_dir: str | Path | None,
    say: Callable[[str], None],
    progress: Callable[[str], None] | None = None,
    stop: threading.Event | None = None,
    debounce_ms: int = DEBOUNCE_MS,
    build: Callable[..., BuildResult] = build_export,
    on_assembly: Callable[[Assembly], None] | None = None,
) -> int:
    """Build once, then after every save; returns 0 when stopped (Ctrl-C or ``stop`` set).
    ``on_assembly``: given each build's assembly as soon as it is built, before the rest of the
    export (``bvsr watch --show``: :func:`bvsr_cad.exporters.ocp_viewer.assembly_sender`)."""
    from watchfiles import watch as watch_files

    params = Path(params).resolve()
    if on_assembly is not None:
        build = functools.partial(build, on_assembly=on_assembly)
    rebuild = functools.partial(_rebuild, build, params, out_dir, progress, say)
    state = _Watched.read(params)
    try:
        rebuild()
        say(f"watching {params}" + (f" and {state.data}" if state.data else "") + " (Ctrl-C stops)")
        while _watch_until_retarget(state, watch_files, stop, debounce_ms, rebuild, say):
            say(f"now watching {params}" + (f" and {state.data}" if state.data else ""))
    except KeyboardInterrupt:
        pass
    say("stopped")
    return 0


def _rebuild(
    build: Callable[..., BuildResult],
    params: Path,
    out_dir: str | Path | None,
    progress: Callable[[str], None] | None,
    say: Callable[[str], None],
) -> None:
    """One build, and a line saying what it wrote, its failed checks and the stages it rebuilt
    and reused; a bad edit says why and leaves the last good export."""
    try:
        res = build(params, out_dir, progress)
    except (ParamError, OutputError, GeometryError) as exc:
        say(f"not rebuilt, the last good export stays: {' '.join(str(exc).split())}")
        return
    failed = [r for r in res.results if r.passed is False]
    reused = [s["stage"] for s in res.stages if s["status"] == "reused"]
    built = [s["stage"] for s in res.stages if s["status"] == "built"]
    say(
        f"wrote {res.out_dir}/ in {res.seconds:.1f} s; {len(failed)} failed checks; "
        f"rebuilt: {', '.join(built) or 'nothing'}; reused: {', '.join(reused) or 'nothing'}"
    )


def _watch_until_retarget(
    state: _Watched,
    watch_files: Callable[..., Any],
    stop: threading.Event | None,
    debounce_ms: int,
    rebuild: Callable[[], None],
    say: Callable[[str], None],
) -> bool:
    """Watch the files of ``state``, rebuilding after each edit, until stopped (False) or until an
    edit names another calibration data file (True: watch again, with that one)."""
    files = state.files()
    folders = sorted({f.parent for f in files if f.parent.is_dir()})
    for changes in watch_files(
        *folders,
        debounce=debounce_ms,
        stop_event=stop,
        raise_interrupt=False,
        recursive=False,  # the files sit in these folders, not below
        watch_filter=lambda _change, path: Path(path).resolve() in files,
        rust_timeout=CATCH_UP_MS,
        yield_on_timeout=True,
    ):
        if _on_save(state, changes, rebuild, say):
            return True
    return False


def _on_save(
    state: _Watched, changes: set, rebuild: Callable[[], None], say: Callable[[str], None]
) -> bool:
    """Act on one batch of file events (none: a catch-up look at the files): say what changed and
    rebuild, unless nothing did. True when the edit names another calibration data file."""
    params, data = state.params, state.data
    now = (_bytes(params), _bytes(data))
    if not changes and now == state.seen:
        return False  # no event, and the files are as last acted on
    state.seen = now
    new = _read(params)
    diff = (
        changed_keys(state.last, new)
        if new is not None
        else ["(the file is not valid TOML yet)" if params.exists() else "(the file is gone)"]
    )
    new_data = _data_file(params, new) if new is not None else data
    new_bytes = _bytes(new_data)
    data_changed = new_data == data and new_bytes != state.data_bytes
    if new is not None and not diff and not data_changed:
        return False  # saved without a change
    if diff:
        say(f"{params.name} changed: " + "; ".join(diff))
    if data_changed:
        say(
            f"{data.name} (calibration data) changed"
            if new_bytes is not None
            else f"{data.name} (calibration data) is gone"
        )
    if new is not None:
        state.last = new
    state.data_bytes = new_bytes
    rebuild()
    if new_data == data:
        return False
    state.data = new_data
    return True


__all__ = ["watch", "changed_keys"]

"""PrusaSlicer's command line as the printability checks use it, and the cache of slices it owns.

Slicing takes seconds per part, so the checks never start the slicer: :func:`slice_stls`
(``bvsr check EXPORT --slice``) slices every STL of an export's ``print_jobs`` not yet in the cache,
with a time limit, and :func:`check_slicing` reports the cached result for that exact file (the
STL's SHA-256, the slicer version and the options; ``~/.cache/bvsr_cad/slices.json``, or
``$BVSR_CACHE``), or ``passed: null`` with the command that slices it. The cache is a memo of the
slicer's verdicts: a slice of the same bytes with the same slicer and options gives the same
verdict, and slicing every part again costs minutes.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import tempfile
import time
from collections.abc import Callable, Collection
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BadInput
from .environment import SLICER, slice_cache_path, slicer_exe, slicer_identity
from .export import Export
from .result import CheckResult

SLICER_INSTALL = "apt-get install prusa-slicer"
#: How ``bvsr`` slices an export; the slicing checks name it when a result is missing.
SLICE_COMMAND = "bvsr check {export} --slice"
SLICE_WORKERS = 2
SLICER_OPTIONS = ("--layer-height", "0.3", "--first-layer-height", "0.3", "--fill-density", "15%")


class SlicerMissingError(RuntimeError, BadInput):
    """Slicing was asked for and PrusaSlicer's command line is not installed."""


@dataclass(frozen=True)
class SliceItem:
    """One printed STL of an export: ``name`` is ``<job>/<part>``, ``rel`` its path in the
    export."""

    name: str
    rel: str
    path: Path
    volume: list[float]


def slice_items(exp: Export) -> list[SliceItem]:
    """Every STL the manifest's ``print_jobs`` name, in their order."""
    return [
        SliceItem(
            f"{job['name']}/{it['part']}",
            it["stl"],
            exp.root / it["stl"],
            list(job["build_volume_mm"]),
        )
        for job in exp.manifest.get("print_jobs") or []
        for it in job["items"]
    ]


def _slicer_version(exe: str) -> str:
    """The version PrusaSlicer prints (this starts the slicer; only :func:`slice_stls` calls it)."""
    try:
        out = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return "PrusaSlicer (unknown version)"
    for line in (out.stdout + out.stderr).splitlines():
        if line.startswith("PrusaSlicer-"):
            return line.split()[0]
    return "PrusaSlicer (unknown version)"


#: Key of the cache entry that maps an installed slicer (see :func:`slicer_identity`) to its
#: version, so that the checks find cached results without starting the slicer.
_CACHE_SLICERS = "slicers"


def _read_cache() -> dict[str, Any]:
    try:
        cache = json.loads(slice_cache_path().read_text())
    except (OSError, ValueError):
        return {}
    return cache if isinstance(cache, dict) else {}


def _update_cache(entries: dict[str, Any], slicers: dict[str, str]) -> None:
    """Merge into the cache file as it is now (another process may have added to it) and replace it
    atomically."""
    path = slice_cache_path()
    cache = _read_cache()
    cache.update(entries)
    known = cache.get(_CACHE_SLICERS)
    cache[_CACHE_SLICERS] = {**(known if isinstance(known, dict) else {}), **slicers}
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".slices-", suffix=".json", dir=path.parent)
        with os.fdopen(fd, "w") as f:
            json.dump(cache, f, indent=1)
        os.replace(tmp, path)
    except OSError:
        pass  # a read-only home only costs the cache


def _cache_key(item: SliceItem, version: str) -> str:
    h = hashlib.sha256(item.path.read_bytes())
    h.update(json.dumps([version, SLICER_OPTIONS, item.volume]).encode())
    return h.hexdigest()


def _slice(stl: Path, volume: list[float], timeout_s: float, exe: str = SLICER) -> dict[str, Any]:
    vx, vy, vz = volume
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            exe,
            "--export-gcode",
            *SLICER_OPTIONS,
            "--bed-shape",
            f"0x0,{vx:g}x0,{vx:g}x{vy:g},0x{vy:g}",
            "--max-print-height",
            f"{vz:g}",
            "--center",
            f"{vx / 2:g},{vy / 2:g}",
            "--output",
            str(Path(tmp) / "out.gcode"),
            str(stl),
        ]
        t0 = time.perf_counter()
        try:
            res = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            return {
                "ok": False,
                "seconds": timeout_s,
                "layers": 0,
                "error": f"timed out after {timeout_s:g} s",
            }
        gcode = Path(tmp) / "out.gcode"
        layers = 0
        if gcode.is_file():
            layers = sum(1 for line in gcode.open() if line.startswith(";LAYER_CHANGE"))
        errors = [
            l
            for l in (res.stdout + res.stderr).splitlines()
            if "error" in l.lower() and "[trace]" not in l
        ]
        ok = res.returncode == 0 and gcode.is_file() and layers > 0
        return {
            "ok": ok,
            "seconds": time.perf_counter() - t0,
            "layers": layers,
            "error": "" if ok else (errors[-1] if errors else f"exit code {res.returncode}"),
        }


def _slice_command(exp: Export) -> str:
    """The command that slices this export, naming it as ``EXPORT``: the checks' results (kept in
    the manifest and the report, and reused from the build cache) must not depend on the folder."""
    return SLICE_COMMAND.format(export="EXPORT")


def slice_stls(
    exp: Export,
    items: list[SliceItem] | None = None,
    progress: Callable[[str], None] | None = None,
    workers: int = SLICE_WORKERS,
) -> dict[str, dict[str, Any]]:
    """Slice every STL of ``items`` (default: all of the export's) that the cache does not hold yet,
    with ``workers`` slicers at a time, and store each result in the cache as soon as it is known.

    Returns:
        ``{item name: result}`` for the STLs sliced now (``ok``, ``layers``, ``seconds``, ``error``,
        ``when``).

    Raises:
        SlicerMissingError: PrusaSlicer's command line is not installed.
    """
    say = progress or (lambda _m: None)
    exe = slicer_exe()
    if exe is None:
        raise SlicerMissingError(
            f"slicing needs PrusaSlicer's command line, `{SLICER}`, which is not on PATH; "
            f"install it with `{SLICER_INSTALL}` (or put a PrusaSlicer 2.5+ `{SLICER}` "
            "on PATH)"
        )
    items = slice_items(exp) if items is None else items
    version = _slicer_version(exe)
    slicers = {slicer_identity(exe): version}
    cache = _read_cache()
    keys = {it.name: _cache_key(it, version) for it in items}
    todo = [it for it in items if keys[it.name] not in cache]
    timeout_s = float(exp.manifest["fabrication"]["slicer_timeout_s"])
    n = max(1, min(workers, os.cpu_count() or 1))
    say(
        f"slicing {len(todo)} of {len(items)} STLs with {version} ({n} at a time; "
        f"{len(items) - len(todo)} already in {slice_cache_path()})"
    )
    done: dict[str, dict[str, Any]] = {}
    if not todo:
        _update_cache({}, slicers)
        return done
    with ThreadPoolExecutor(max_workers=n) as pool:
        futures = {pool.submit(_slice, it.path, it.volume, timeout_s, exe): it for it in todo}
        for k, fut in enumerate(as_completed(futures), 1):
            it = futures[fut]
            res = {**fut.result(), "when": time.strftime("%Y-%m-%d %H:%M:%S")}
            done[it.name] = res
            _update_cache({keys[it.name]: res}, slicers)
            state = f"ok, {res['layers']} layers" if res["ok"] else f"FAILED ({res['error']})"
            say(f"slice {k}/{len(todo)} {it.rel}: {state}, {res['seconds']:.1f} s")
    return done


def check_slicing(
    exp: Export, items: list[SliceItem] | None = None, sliced_now: Collection[str] = ()
) -> list[CheckResult]:
    """One ``slice:<job>/<part>`` result per STL from the slice cache; never starts the slicer.

    An STL the cache does not hold (or a slicer :func:`slice_stls` has not run yet) is reported
    ``passed: None`` with the command that slices it. ``sliced_now`` names the items sliced in this
    run.
    """
    items = slice_items(exp) if items is None else items
    command = _slice_command(exp)
    exe = slicer_exe()
    cache = _read_cache()
    version = None
    if exe is not None:
        try:
            version = (cache.get(_CACHE_SLICERS) or {}).get(slicer_identity(exe))
        except (OSError, AttributeError):
            version = None
    out = []
    for it in items:
        r = cache.get(_cache_key(it, version)) if version else None
        if not isinstance(r, dict):
            why = (
                f"{SLICER} is not installed ({SLICER_INSTALL}); then `{command}` slices it"
                if exe is None
                else "not sliced in the build (builds and checks never start the slicer) and not "
                "in the slice "
                f"cache; `{command}` slices it"
            )
            out.append(CheckResult(f"slice:{it.name}", None, None, 0, "errors", it.rel, why))
            continue
        how = (
            "sliced now"
            if it.name in sliced_now
            else f"cached result of {r.get('when', '?')} (same STL, slicer and options)"
        )
        note = (
            f"{version}, {' '.join(SLICER_OPTIONS)}: {r.get('layers', 0)} layers in "
            f"{r.get('seconds', 0.0):.1f} s, {how}"
        )
        if not r.get("ok"):
            note += f"; {r.get('error', '')}"
        out.append(
            CheckResult(
                f"slice:{it.name}",
                bool(r.get("ok")),
                0 if r.get("ok") else 1,
                0,
                "errors",
                it.rel,
                note,
            )
        )
    return out

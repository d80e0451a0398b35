"""The content-addressed artifact cache of `bvsr build`.

A stage's entry is keyed by the SHA-256 of exactly what the stage reads:
its name, the fingerprint of this package's code (every ``.py`` and data
file of ``bvsr_cad``, so an edited model never serves a stale result, and
the versions of Python and of the libraries it computes with) and
the inputs the stage declares where it is defined (a projection of the
parameters, the bytes of a data file). An entry is a folder of files written
into a temporary folder and renamed into place, so two builds at once never
see a half-written entry; the first to finish wins and the other's copy is
dropped. The cache is bounded: after every write the least recently used
entries go until it fits (``BVSR_CACHE_MAX_MB``, default 2048 MB).

Where: ``$BVSR_CACHE/artifacts`` (default ``~/.cache/bvsr_cad/artifacts``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import os
import pickle
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

from ..folders import cache_folder

DEFAULT_MAX_MB = 2048.0
_DONE = ".done"
#: In the name of an entry's temporary folder, ``.<key[:12]>.tmp-*``, beside the entries.
_TMP = ".tmp-"
#: In an entry of :func:`object_stage`: the objects the stage hands on, pickled.
_OBJECTS = "objects.pkl"

#: Inside a temporary folder of a build (its export) or of the cache (an entry being written): the
#: writing process's PID and start time (PID reuse safe), so that a later run removes only dead
#: ones.
OWNER_FILE = ".bvsr-build-owner"
#: A replaced export is renamed away and deleted within seconds, and a temporary folder is claimed
#: as soon as it is made; one older than this without an owner was orphaned.
ORPHAN_AGE_S = 60.0


def process_start(pid: int) -> str | None:
    """The process's start time in clock ticks (Linux /proc), or None if there is no such
    process."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        if not Path("/proc/self/stat").exists():  # no /proc: fall back to a signal-0 probe
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                return None
            except PermissionError:
                return "?"
            return "?"
        return None
    return stat.rsplit(")", 1)[1].split()[19]


def claim(tmp: Path) -> None:
    """Mark a temporary folder as this process's."""
    pid = os.getpid()
    (tmp / OWNER_FILE).write_text(f"{pid} {process_start(pid)}\n")


def owner_alive(folder: Path) -> bool:
    """The process that made ``folder`` (:func:`claim`) is still running (or the folder is too new
    to have been claimed)."""
    try:
        pid_s, start = (folder / OWNER_FILE).read_text().split()
    except (OSError, ValueError):
        try:
            return (
                time.time() - folder.stat().st_mtime < ORPHAN_AGE_S
            )  # just created, not yet claimed
        except OSError:
            return False
    now = process_start(int(pid_s))
    return now is not None and (now == start or now == "?")


def cache_root() -> Path:
    """``$BVSR_CACHE/artifacts`` (default ``~/.cache/bvsr_cad/artifacts``), made absolute: a
    relative ``BVSR_CACHE`` is where the user stands, not the folder a second process works in."""
    return cache_folder() / "artifacts"


#: The installed distributions whose code computes what the stages store: every runtime dependency
#: of ``pyproject.toml`` (``tests/test_cache.py`` holds the two lists together) and the OCP builds
#: under build123d and CadQuery (the CAD kernel that tessellates every STL). A new MuJoCo or OCP
#: moves results that this package's source does not.
RESULT_DISTRIBUTIONS = (
    "build123d",
    "cadquery",
    "cadquery-ocp",
    "cadquery-ocp-novtk",
    "dask",
    "distributed",
    "libigl",
    "manifold3d",
    "matplotlib",
    "mujoco",
    "networkx",
    "numpy",
    "optuna",
    "pandas",
    "pyarrow",
    "pybullet",
    "python-fcl",
    "pyvista",
    "rtree",
    "scipy",
    "shapely",
    "trimesh",
    "vtk",
    "watchfiles",
    "yourdfpy",
)


def distribution_versions() -> dict[str, str | None]:
    """The installed version of each of :data:`RESULT_DISTRIBUTIONS` (None: not installed), and
    Python's."""
    from importlib import metadata

    def version(name: str) -> str | None:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return None

    return {"python": sys.version, **{name: version(name) for name in RESULT_DISTRIBUTIONS}}


# Once per process: every key it makes names the code it runs, even if a file is edited meanwhile.
@lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 over this package's source and data files (path and bytes, sorted) and the versions
    of Python and of the libraries it computes with (:func:`distribution_versions`). The default
    inputs (``defaults/``, the repository's ``params/``) are inputs, keyed by what a stage reads of
    them: an edit of ``params/bvsr.toml`` must not move every stage's key."""
    pkg = Path(__file__).resolve().parents[1]  # bvsr_cad
    h = hashlib.sha256()
    for p in sorted(pkg.rglob("*")):
        rel = p.relative_to(pkg).parts
        if (
            p.is_file()
            and p.suffix in (".py", ".toml", ".json", ".csv", ".js", ".mjs")
            and "__pycache__" not in rel
            and not (rel[0] == "defaults" and p.suffix != ".py")
        ):
            h.update(p.relative_to(pkg).as_posix().encode())
            h.update(p.read_bytes())
    h.update(json.dumps(distribution_versions(), sort_keys=True).encode())
    return h.hexdigest()


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, bytes):
        return hashlib.sha256(value).hexdigest()
    if isinstance(value, Path):
        return str(value)
    return value


def stage_key(stage: str, **inputs: Any) -> str:
    """The cache key of ``stage`` for exactly what it reads.

    Args:
        stage: the stage's name.
        **inputs: everything the stage reads (dataclasses, dicts, numbers, strings, bytes).

    Returns:
        A SHA-256 hex digest over the stage, its inputs and :func:`code_fingerprint` (the package's
        code and the libraries' versions), so an edited model never serves a stale entry.
    """
    text = json.dumps(
        {"stage": stage, "code": code_fingerprint(), "inputs": _plain(inputs)},
        sort_keys=True,
        allow_nan=True,
        default=repr,
    )
    return hashlib.sha256(text.encode()).hexdigest()


def spec_without(spec: Any, *fields: str) -> dict[str, Any]:
    """A stage's view of the parameters: every table but ``fields`` (``"table"`` or
    ``"table.key"``)."""
    plain = _plain(spec)
    for name in fields:
        table, _, key = name.partition(".")
        if key:
            plain.get(table, {}).pop(key, None)
        else:
            plain.pop(table, None)
    return plain


class ArtifactCache:
    """Entries are folders ``<root>/<key[:2]>/<key>/`` with a ``.done`` marker written last."""

    def __init__(self, root: Path | None = None, max_bytes: float | None = None):
        self.root = Path(root).absolute() if root is not None else cache_root()
        mb = float(os.environ.get("BVSR_CACHE_MAX_MB", DEFAULT_MAX_MB))
        self.max_bytes = max_bytes if max_bytes is not None else mb * 1e6

    def _entry(self, key: str) -> Path:
        return self.root / key[:2] / key

    def get(self, key: str) -> Path | None:
        """The entry's folder, marked as just used, or None."""
        entry = self._entry(key)
        done = entry / _DONE
        if not done.is_file():
            return None
        try:
            os.utime(done)
        except OSError:
            return None
        return entry

    def put(self, key: str, fill: Callable[[Path], None], evict: bool = True) -> Path:
        """Make the entry by ``fill(folder)`` in a temporary folder, then rename it into place.
        Without ``evict`` the cache is not trimmed now (many small entries in a row: the caller
        calls :meth:`evict` once after them)."""
        entry = self._entry(key)
        entry.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{key[:12]}{_TMP}", dir=entry.parent))
        try:
            claim(tmp)
            fill(tmp)
            (tmp / OWNER_FILE).unlink(missing_ok=True)
            (tmp / _DONE).write_text(f"{time.time():.3f}\n")
            try:
                tmp.rename(entry)
            except OSError:  # another build put it first: theirs is as good
                shutil.rmtree(tmp, ignore_errors=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        if evict:
            self.evict()
        return entry

    def clean_leftovers(self) -> list[Path]:
        """Remove the temporary folders of entries whose writing process is gone (a build killed
        with SIGKILL while it filled one); a live writer's are kept. Returns what was removed."""
        removed = []
        if not self.root.is_dir():
            return removed
        for folder in self.root.glob(f"*/.*{_TMP}*"):
            if folder.is_dir() and not owner_alive(folder):
                shutil.rmtree(folder, ignore_errors=True)
                removed.append(folder)
        return removed

    def entries(self) -> list[tuple[float, int, Path]]:
        """(last use, size in bytes, folder) of every complete entry."""
        out = []
        if not self.root.is_dir():
            return out
        for done in self.root.glob(f"*/*/{_DONE}"):
            folder = done.parent
            try:
                size = sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
                out.append((done.stat().st_mtime, size, folder))
            except OSError:
                continue
        return out

    def evict(self) -> list[Path]:
        """Remove least recently used entries until the cache fits; returns what went."""
        entries = sorted(self.entries())
        total = sum(size for _, size, _ in entries)
        removed = []
        for _, size, folder in entries:
            if total <= self.max_bytes:
                break
            shutil.rmtree(folder, ignore_errors=True)
            total -= size
            removed.append(folder)
        return removed


def copy_tree(src: Path, dst: Path, skip: tuple[str, ...] = (_DONE,)) -> None:
    """Copy the files of ``src`` into ``dst`` (created), keeping relative paths."""
    for p in src.rglob("*"):
        rel = p.relative_to(src)
        if rel.parts[0] in skip:
            continue
        target = dst / rel
        if p.is_dir():
            target.mkdir(parents=True, exist_ok=True)
        else:
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(p, target)


def _shape(cls: type, wrapped: Any, label: str, rgba: tuple[float, ...] | None) -> Any:
    shape = cls(wrapped)
    shape.label = label
    if rgba is not None:
        shape.color = sys.modules["build123d"].Color(*rgba)
    return shape


class _Pickler(pickle.Pickler):
    """Pickles a build123d shape as its B-rep (OCCT's binary format, build123d's own reducer of the
    wrapped shape: exact geometry and any triangulation), its label and colour; not the boolean
    history build123d keeps (which OCCT cannot serialise and no stage reads)."""

    def reducer_override(self, obj: Any) -> Any:
        bd = sys.modules.get("build123d")  # no build123d loaded: no shape to pickle
        if bd is not None and isinstance(obj, bd.Shape):
            return _shape, (
                type(obj),
                obj.wrapped,
                obj.label,
                tuple(obj.color) if obj.color is not None else None,
            )
        return NotImplemented


def _dumps(objects: Any) -> bytes:
    buf = io.BytesIO()
    _Pickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump(objects)
    return buf.getvalue()


def object_stage(
    cache: ArtifactCache | None, key: str, make: Callable[[Path], Any], dst: Path
) -> tuple[Any, bool]:
    """A stage that writes files and hands objects on to later stages (B-reps, meshes, scenes).

    ``make(folder)`` writes the stage's files into ``folder`` and returns its objects (picklable).
    From the cache, the entry's files are copied into ``dst`` and its objects unpickled, as ``make``
    left them; else ``make`` runs (into a new entry when there is a cache). Either way, and without
    a cache, the objects handed on are the ones read back from their pickle: a B-rep read back from
    OCCT's binary form is the same geometry, but OCCT's volumes and areas of it can differ from the
    original's in the last bit, and a build from the cache must equal one without, file for file.
    Returns (objects, reused).
    """
    hit = cache.get(key) if cache is not None else None
    if hit is not None:
        copy_tree(hit, dst, skip=(_DONE, _OBJECTS))
        return pickle.loads((hit / _OBJECTS).read_bytes()), True
    if cache is None:
        return pickle.loads(_dumps(make(dst))), False
    made: list[bytes] = []

    def fill(folder: Path) -> None:
        made.append(_dumps(make(folder)))
        (folder / _OBJECTS).write_bytes(made[0])

    copy_tree(cache.put(key, fill), dst, skip=(_DONE, _OBJECTS))
    return pickle.loads(made[0]), False


def value_stage(
    cache: ArtifactCache | None, key: str, compute: Callable[[], Any]
) -> tuple[Any, bool]:
    """A stage that writes no file and hands on a picklable value (check verdicts): from the cache,
    or ``compute()`` stored in a new entry (left for the caller's :meth:`ArtifactCache.evict`).
    Returns (value, reused)."""
    hit = cache.get(key) if cache is not None else None
    if hit is not None:
        return pickle.loads((hit / _OBJECTS).read_bytes()), True
    value = compute()
    if cache is not None:
        data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
        cache.put(key, lambda folder: (folder / _OBJECTS).write_bytes(data), evict=False)
        value = pickle.loads(data)  # as a build from the cache hands it on
    return value, False


def file_sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


__all__ = [
    "ArtifactCache",
    "value_stage",
    "file_sha256",
    "stage_key",
    "spec_without",
    "code_fingerprint",
    "distribution_versions",
    "RESULT_DISTRIBUTIONS",
    "cache_root",
    "copy_tree",
    "object_stage",
]

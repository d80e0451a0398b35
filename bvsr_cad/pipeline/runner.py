"""A build's stages and the one runner that caches, times and reports them.

A :class:`Stage` declares what it reads: the parameters less the tables and keys it ignores, values
it derives from them, the calibration's data file. Its cache key is made from that declaration and
nothing else (:meth:`Runner.key`), so a stage added to a build's list needs no edit here. The
stage's function writes its files into a folder and returns its products; :meth:`Runner.run` takes
them from the cache, or runs the function (into a new cache entry where there is a cache), times it
and adds its line to the stage report (``bvsr build --json``). Writers and checks never see the
cache: a build hands them a :class:`bvsr_cad.memo.Memo` over it (:func:`cache_memo`), keyed by
what their own steps read.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from ..memo import Memo
from .cache import ArtifactCache, object_stage, spec_without, stage_key, value_stage

if TYPE_CHECKING:
    from .publish import StageLog

T = TypeVar("T")


@dataclass(frozen=True)
class Stage:
    """One stage of a build and what it reads.

    Attributes:
        label: its name in the stage report and the progress lines.
        key: its cache entries' name; None: not cached (it runs at every build).
        ignore: the parameters it does not read (``"table"`` or ``"table.key"``): the rest are part
            of its key. None: it reads the parameters only through ``derived``.
        derived: what it reads of the parameters besides, as named values (a flag, a choice, a
            sub-table).
        data: it reads the calibration's data file.
        say: the progress line said before it runs.
    """

    label: str
    key: str | None = None
    ignore: tuple[str, ...] | None = None
    derived: Callable[[Any], dict[str, Any]] | None = None
    data: bool = False
    say: str | None = None

    def inputs(self, spec: Any, data: bytes = b"") -> dict[str, Any]:
        """What the stage reads of ``spec`` and the calibration ``data``, as its key hashes it."""
        out: dict[str, Any] = {}
        if self.ignore is not None:
            out["spec"] = spec_without(spec, *self.ignore)
        if self.derived is not None:
            out.update(self.derived(spec))
        if self.data:
            out["data"] = data
        return out

    def key_for(self, spec: Any, data: bytes = b"") -> str:
        """The stage's cache key for ``spec`` and ``data``: its name and :meth:`inputs`."""
        if self.key is None:
            raise ValueError(f"stage {self.label!r} is not cached: it has no key")
        return stage_key(self.key, **self.inputs(spec, data))


class Runner:
    """Runs a build's stages into its folder from the parameters ``spec`` and the calibration
    ``data``; ``cache``: the artifact cache (None: every stage runs, ``--no-cache``); ``log``: the
    stage report."""

    def __init__(
        self, spec: Any, data: bytes, cache: ArtifactCache | None, folder: Path, log: StageLog
    ):
        self.spec, self.data, self.cache, self.folder, self.log = spec, data, cache, folder, log
        self.say = log.say
        self._hits: dict[str, Path | None] = {}
        self._pending: dict[str, float] = {}

    def key(self, stage: Stage) -> str:
        return stage.key_for(self.spec, self.data)

    def hit(self, stage: Stage) -> Path | None:
        """The cache's entry of ``stage`` for these inputs, or None (not held, or no cache)."""
        if self.cache is None or stage.key is None:
            return None
        key = self.key(stage)
        if key not in self._hits:
            self._hits[key] = self.cache.get(key)
        return self._hits[key]

    def put(self, stage: Stage, fill: Callable[[Path], None]) -> None:
        """Store an entry of ``stage`` that ``fill(folder)`` writes (a stage whose products come
        from elsewhere, a second process); nothing without a cache."""
        if self.cache is not None:
            self._hits[self.key(stage)] = self.cache.put(self.key(stage), fill)

    def run(self, stage: Stage, make: Callable[[Path], T]) -> T:
        """``stage``'s products: ``make(folder)`` writes its files into ``folder`` and returns them
        (picklable). From the cache, the entry's files are copied into the build's folder and its
        products read back; else ``make`` runs (into a new entry, when there is a cache). Products
        handed on are always the ones read back from their pickle
        (:func:`bvsr_cad.pipeline.cache.object_stage`), so a build from the cache equals one
        without, file for file."""
        if stage.say:
            self.say(stage.say)
        t = time.perf_counter()
        if stage.key is None:
            product, reused = make(self.folder), False
        else:
            product, reused = object_stage(self.cache, self.key(stage), make, self.folder)
        self.record(stage, reused, time.perf_counter() - t)
        return product

    @contextmanager
    def timed(self, stage: Stage) -> Iterator[None]:
        """Time the block as part of ``stage`` (a stage whose work is spread over the build): its
        seconds join the stage's line when :meth:`run` or :meth:`record` writes it."""
        t = time.perf_counter()
        try:
            yield
        finally:
            self._pending[stage.label] = (
                self._pending.get(stage.label, 0.0) + time.perf_counter() - t
            )

    def record(self, stage: Stage, reused: bool, seconds: float = 0.0) -> None:
        """``stage``'s line in the stage report: ``seconds`` and what :meth:`timed` counted for
        it."""
        self.log.record(stage.label, reused, seconds + self._pending.pop(stage.label, 0.0))

    @property
    def memo(self) -> Memo:
        """The memo this build hands its writers (:func:`cache_memo` of its cache)."""
        return cache_memo(self.cache)


def cache_memo(cache: ArtifactCache | None) -> Memo:
    """The :class:`bvsr_cad.memo.Memo` over ``cache``: a step's result keyed by its name, its inputs
    and the bytes of its files (hashed only where there is a cache), through :func:`object_stage`
    (files under ``dst``) or :func:`value_stage` (a value). Without a cache each step runs now, its
    objects handed on as a cached build's would be (read back from their pickle)."""

    def memo(
        name: str,
        inputs: Mapping[str, Any],
        make: Callable[..., T],
        dst: Path | None = None,
        files: Sequence[Path] = (),
    ) -> tuple[T, bool]:
        hashes = [hashlib.sha256(Path(f).read_bytes()).hexdigest() for f in files] if cache else []
        key = stage_key(name, **inputs, files=hashes)
        if dst is None:
            return value_stage(cache, key, make)
        return object_stage(cache, key, make, dst)

    return memo


__all__ = ["Runner", "Stage", "cache_memo"]

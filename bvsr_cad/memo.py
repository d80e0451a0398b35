"""The one memo vocabulary: how code below the pipeline has a step of its own remembered between
builds without seeing the artifact cache.

A writer or a check that has a slow step takes a :class:`Memo` as an argument and calls it with the
step's name, every input the step reads and the step itself::

    value, reused = memo(name, inputs, make)  # a value (check verdicts)
    value, reused = memo(name, inputs, make, dst, files=paths)  # files under dst, and a value

``inputs`` are values (numbers, strings, lists, dicts, dataclasses); ``files`` are read by their
bytes. The pipeline hands in the memo of its artifact cache
(:func:`bvsr_cad.pipeline.runner.cache_memo`), which gives the step's result for the same name,
inputs and bytes from the cache; called without one, a writer or a check runs each step now
(:func:`run_now`). So nothing below the pipeline imports the cache, and a step that forgets an
input it reads is the one rule to keep (the cache-edit tests build every benchmark edit both ways).

The memos that stay in bvsr_cad, each with its reason, are listed in docs/architecture.md.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol, TypeVar

T = TypeVar("T")


class Memo(Protocol):
    """``memo(name, inputs, make, dst=None, files=())`` -> ``(value, reused)``: ``make()`` (or
    ``make(dst)``, which writes its files under ``dst``) for this ``name``, ``inputs`` and the bytes
    of ``files``, or the remembered result of the same (its files copied into ``dst``)."""

    def __call__(
        self,
        name: str,
        inputs: Mapping[str, Any],
        make: Callable[..., T],
        dst: Path | None = None,
        files: Sequence[Path] = (),
    ) -> tuple[T, bool]: ...


def run_now(
    name: str,
    inputs: Mapping[str, Any],
    make: Callable[..., T],
    dst: Path | None = None,
    files: Sequence[Path] = (),
) -> tuple[T, bool]:
    """The memo of a writer or a check called alone: the step runs now, nothing is remembered."""
    return (make() if dst is None else make(dst)), False


class InMemory:
    """A memo held in memory for the life of its owner: each name's last value, given again for the
    same inputs (values only: no ``dst``, no ``files``). Its one user,
    :class:`bvsr_cad.checks.run.Checks`, keeps a check group run early while what it read is
    unchanged (its inputs: the state of those reads)."""

    def __init__(self) -> None:
        #: ``name -> (inputs, value)`` of each name's last step.
        self.kept: dict[str, tuple[Mapping[str, Any], Any]] = {}

    def __call__(
        self,
        name: str,
        inputs: Mapping[str, Any],
        make: Callable[..., T],
        dst: Path | None = None,
        files: Sequence[Path] = (),
    ) -> tuple[T, bool]:
        if dst is not None or files:
            raise ValueError("an in-memory memo keeps values, not files")
        kept = self.kept.get(name)
        if kept is not None and kept[0] == inputs:
            return kept[1], True
        value = make()
        self.kept[name] = (inputs, value)
        return value, False

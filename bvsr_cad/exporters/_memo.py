"""A writer's own steps that a build caches: the build hands the writer a memo
(:meth:`bvsr_cad.pipeline.runner.Runner.memo`), ``memo(name, inputs, make, dst, files=())``, which
gives ``make(dst)``'s products (its files written under ``dst``) for these ``inputs`` and the bytes
of ``files``. A writer called without one runs each step now (:func:`now`): writers never see the
cache.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")
#: ``memo(name, inputs, make, dst, files=())``: see the module's docstring.
Memo = Callable[..., Any]


def now(
    name: str,
    inputs: dict[str, Any],
    make: Callable[[Path], T],
    dst: Path,
    files: Sequence[Path] = (),
) -> T:
    """The memo of a writer called alone: ``make(dst)``, run now."""
    return make(dst)

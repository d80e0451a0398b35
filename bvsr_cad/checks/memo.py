"""Check verdicts reused from the artifact cache when what the checks read is unchanged.

A group of checks declares, beside the check (a ``*_reads`` function), what
it reads from an export: the files (hashed by content, so a rebuilt but
byte-identical STL still matches) and the manifest values. Its verdicts are
stored under the key of the group's name, those values and those hashes (and
the package's code, :func:`bvsr_cad.cache.stage_key`), so an edit that leaves
them unchanged (a rod material: no mesh moves) reuses them, and the verdicts
are the ones a fresh run gives. Without a cache every group runs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..cache import ArtifactCache, file_sha256, stage_key, value_stage
from .export import Export
from .result import CheckResult


class CheckMemo:
    def __init__(self, exp: Export, cache: ArtifactCache | None = None):
        self.exp, self.cache = exp, cache
        self._sha: dict[str, str] = {}
        self.reused = self.run = 0

    def __call__(self, group: str, reads: tuple[list[str], Any],
                 compute: Callable[[], list[CheckResult]]) -> list[CheckResult]:
        """``compute()``'s verdicts, or the cached ones of the same ``reads`` (files, manifest values)."""
        if self.cache is None:
            return compute()
        files, values = reads
        for rel in files:
            if rel not in self._sha:
                self._sha[rel] = file_sha256(self.exp.root / rel)
        key = stage_key(f"checks:{group}", files=[(rel, self._sha[rel]) for rel in files], values=values)
        results, reused = value_stage(self.cache, key, compute)
        self.reused += reused
        self.run += not reused
        return results

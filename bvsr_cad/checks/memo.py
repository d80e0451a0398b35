"""Check verdicts reused when what the checks read is unchanged.

A group of checks declares, beside the check (a ``*_reads`` function), what it reads from an
export: the files (hashed by content, so a rebuilt but byte-identical STL still matches) and the
manifest values. Its verdicts are a step of the :class:`bvsr_cad.memo.Memo` the build hands in (the
one over its artifact cache), named after the group, with those values and those hashes as its
inputs, so an edit that leaves them unchanged (a rod material: no mesh moves) reuses them, and the
verdicts are the ones a fresh run gives. Without a memo every group runs.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..memo import Memo, run_now
from .export import Export
from .result import CheckResult


class CheckMemo:
    """The verdicts of an export's check groups through ``memo``, each file hashed once."""

    def __init__(self, exp: Export, memo: Memo | None = None):
        self.exp, self.memo = exp, memo or run_now
        self._sha: dict[str, str] = {}
        self.reused = self.run = 0

    def __call__(
        self, group: str, reads: tuple[list[str], Any], compute: Callable[[], list[CheckResult]]
    ) -> list[CheckResult]:
        """``compute()``'s verdicts, or the kept ones of the same ``reads`` (files, manifest
        values)."""
        if self.memo is run_now:
            return compute()
        files, values = reads
        for rel in files:
            if rel not in self._sha:
                self._sha[rel] = hashlib.sha256(Path(self.exp.root / rel).read_bytes()).hexdigest()
        results, reused = self.memo(
            f"checks:{group}",
            {"read_files": [(rel, self._sha[rel]) for rel in files], "values": values},
            compute,
        )
        self.reused += reused
        self.run += not reused
        return results

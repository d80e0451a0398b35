"""Check verdicts reused when what the checks read is unchanged.

A group of checks declares, beside the check (a ``*_reads`` function), what
it reads from an export: the files (hashed by content, so a rebuilt but
byte-identical STL still matches) and the manifest values. Its verdicts are
kept in a store under the group's name, those values and those hashes (the
build's store is its artifact cache, keyed as its stages are:
:func:`bvsr_cad.pipeline.runner.verdict_store`), so an edit that leaves them
unchanged (a rod material: no mesh moves) reuses them, and the verdicts are
the ones a fresh run gives. Without a store every group runs.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .export import Export
from .result import CheckResult

#: ``store(name, inputs, compute)``: the verdicts of ``compute()`` kept for ``name`` and ``inputs``,
#: and whether they were kept already.
VerdictStore = Callable[[str, dict[str, Any], Callable[[], Any]], tuple[Any, bool]]


class CheckMemo:
    def __init__(self, exp: Export, store: VerdictStore | None = None):
        self.exp, self.store = exp, store
        self._sha: dict[str, str] = {}
        self.reused = self.run = 0

    def __call__(
        self, group: str, reads: tuple[list[str], Any], compute: Callable[[], list[CheckResult]]
    ) -> list[CheckResult]:
        """``compute()``'s verdicts, or the kept ones of the same ``reads`` (files, manifest
        values)."""
        if self.store is None:
            return compute()
        files, values = reads
        for rel in files:
            if rel not in self._sha:
                self._sha[rel] = hashlib.sha256(Path(self.exp.root / rel).read_bytes()).hexdigest()
        results, reused = self.store(
            f"checks:{group}",
            {"files": [(rel, self._sha[rel]) for rel in files], "values": values},
            compute,
        )
        self.reused += reused
        self.run += not reused
        return results

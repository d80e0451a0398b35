"""Checks on the SOA mold set saved in an export (filled in by the molds issue)."""

from __future__ import annotations

from .export import Export
from .result import CheckResult


def check_molds(exp: Export) -> list[CheckResult]:
    return []

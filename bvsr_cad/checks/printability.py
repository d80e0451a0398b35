"""Printability checks on every printed part (filled in by the fabrication issue)."""

from __future__ import annotations

from .export import Export
from .result import CheckResult


def check_printability(exp: Export) -> list[CheckResult]:
    return []

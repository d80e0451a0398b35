"""Checks on the kinematic analyses saved in an export (filled in by the kinematics issue)."""

from __future__ import annotations

from .export import Export
from .result import CheckResult


def check_analyses(exp: Export) -> list[CheckResult]:
    return []

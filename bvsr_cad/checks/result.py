"""The result every check returns; the CLI and the tests consume the same objects."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any


@dataclass(frozen=True)
class CheckResult:
    """One check: ``passed`` is True/False, or None for an informational comparison."""

    name: str
    passed: bool | None
    value: Any
    limit: Any
    unit: str
    where: str
    note: str = ""

    def __post_init__(self) -> None:
        # Checks compute with numpy; the JSON contract wants plain bools and numbers.
        for key in ("passed", "value", "limit"):
            v = getattr(self, key)
            if hasattr(v, "item") and getattr(v, "ndim", 0) == 0:
                object.__setattr__(self, key, v.item())

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    def line(self) -> str:
        mark = {True: "PASS", False: "FAIL", None: "INFO"}[self.passed]
        val = f"{self.value:.4g}" if isinstance(self.value, float) else str(self.value)
        lim = f"{self.limit:.4g}" if isinstance(self.limit, float) else str(self.limit)
        text = f"{mark}  {self.name}: {val} {self.unit} (limit {lim} {self.unit}) [{self.where}]"
        return text + (f"  {self.note}" if self.note else "")


def overall(results: list[CheckResult]) -> bool:
    return all(r.passed is not False for r in results)

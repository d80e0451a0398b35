"""``tools/mutate.py`` checks that the tests catch physically wrong answers by applying each of its faults
to the source: a fault whose snippet no longer occurs in the code (the code moved on) checks nothing, and
four had rotted that way unnoticed. Each must apply, exactly once."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_fault_of_the_mutation_check_applies_to_the_code_as_it_is(monkeypatch):
    spec = importlib.util.spec_from_file_location("bvsr_mutate", ROOT / "tools" / "mutate.py")
    mutate = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "bvsr_mutate", mutate)  # its dataclasses look their module up
    spec.loader.exec_module(mutate)
    assert len(mutate.FAULTS) >= 30
    assert len({f.name for f in mutate.FAULTS}) == len(mutate.FAULTS)
    assert mutate.snippet_problems(ROOT, mutate.FAULTS) == []

"""The command's table of bad-input errors (exit code 2) names each error class by its module: a
module that moved, or a class renamed, would make that error a traceback with exit code 1,
silently."""

from __future__ import annotations

import importlib

from bvsr_cad import cli


def test_every_bad_input_error_the_command_names_exists_where_it_says():
    for module, name in cli._BAD_INPUT:
        cls = getattr(importlib.import_module(f"bvsr_cad.{module}"), name, None)
        assert isinstance(cls, type) and issubclass(cls, Exception), f"bvsr_cad.{module}.{name}"

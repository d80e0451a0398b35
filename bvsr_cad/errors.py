"""The two kinds of error the command line tells apart from a bug, as base classes.

An error class that means the user's input cannot be used (a parameter file, a measurements file, an
output folder, a host robot, a missing extra, ...) subclasses :class:`BadInput` beside its own base
(``ValueError``, ``RuntimeError``, ...), so that code catching the usual base is unchanged. The
command line maps :class:`BadInput` to exit code 2 and prints its message, which names the key or
file the user wrote, its value and what is allowed. :class:`GeneratorFailure` marks the CAD kernel
failing on parameters that passed validation (exit code 2 too, with advice on what to change).

This module imports nothing, so every layer can subclass these and ``bvsr`` classifies an error
without importing the module that raised it.
"""

from __future__ import annotations


class BadInput(Exception):
    """The user's input cannot be used: exit code 2, the message printed as it is."""


class GeneratorFailure(Exception):
    """A part generator failed on parameters that passed validation (a case the rules checked at
    load do not cover yet): exit code 2, with the keys to change."""

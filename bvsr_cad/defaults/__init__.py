"""The default inputs that travel with the package: the two tails' parameter files, the paper's
measurements and the design studies.

They sit in the folders their relative paths expect: a study's ``base = "../params/bvsr.toml"`` and
a parameter file's ``calibration.data_file = "../data/paper_bvsr.csv"`` resolve here, in a copy that
``bvsr init`` writes, and in the repository, whose ``params/``, ``data/`` and ``studies/`` are links
to these folders (one copy of each file).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

#: The folders of default inputs, and the suffixes of the files that are inputs (the package data of
#: ``pyproject.toml`` takes the same).
FOLDERS = {"params": ".toml", "data": ".csv", "studies": ".toml"}

#: The tail ``bvsr build`` builds when given no file.
DEFAULT_PARAMS = "params/bvsr.toml"


def folder() -> Path:
    """The installed folder of the defaults.

    Raises:
        RuntimeError: the package is imported from an archive (a zip), where the builds could not
            read a parameter file's relative paths beside it.
    """
    root = resources.files(__package__)
    if not isinstance(root, Path):
        raise RuntimeError(
            f"bvsr_cad's default files are inside an archive ({root}); install the package "
            "as a wheel (pip install bvsr_cad) to use them"
        )
    return root


def files() -> list[str]:
    """Every default file, as a path relative to :func:`folder` (``params/bvsr.toml``, ...),
    sorted."""
    root = resources.files(__package__)
    return sorted(
        f"{name}/{f.name}"
        for name, suffix in FOLDERS.items()
        for f in root.joinpath(name).iterdir()
        if f.is_file() and f.name.endswith(suffix) and not f.name.startswith(".")
    )


def path(relative: str) -> Path:
    """The installed file ``relative`` (e.g. ``params/bvsr.toml``)."""
    return folder() / relative

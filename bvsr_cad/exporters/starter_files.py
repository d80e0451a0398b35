"""``bvsr init``: editable copies of the default inputs (:mod:`bvsr_cad.defaults`), in the folders
their relative paths expect, so that a copied study still finds its base parameter file and a copied
parameter file its measurements."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .. import defaults
from ..errors import BadInput

#: What ``bvsr init`` tells about each file it writes.
STARTER_FILES = {
    "params/bvsr.toml": "the paper's tail (two segments): edit this one",
    "params/bvsr_l.toml": "the paper's longer BVSR_L tail (three segments)",
    "data/paper_bvsr.csv": "the paper's measurements: `bvsr calibrate` fits to them, the build "
    "compares",
    "studies/vertebra.toml": "the paper's vertebra study (rod material and diameter)",
    "studies/optimise.toml": "an Optuna search for the most root torque per gram",
}


class StarterExistsError(FileExistsError, BadInput):
    """Files ``bvsr init`` would overwrite (it writes none of them then)."""

    def __init__(self, paths: list[Path]):
        self.paths = paths
        super().__init__(
            f"{', '.join(map(str, paths))} already exist{'s' if len(paths) == 1 else ''}; nothing "
            "was written (--force overwrites)"
        )


def write_starter(folder: str | Path, force: bool = False) -> list[Path]:
    """Write every default file under ``folder`` (``params/``, ``data/``, ``studies/``); returns
    their paths.

    Raises:
        StarterExistsError: one or more of the files exist and ``force`` is false; nothing is
            written then.
    """
    root = Path(folder)
    targets = {rel: root / rel for rel in defaults.files()}
    clash = [p for p in targets.values() if p.exists() or p.is_symlink()]
    if clash and not force:
        raise StarterExistsError(clash)
    source = resources.files(defaults)
    for rel, target in targets.items():
        data = source.joinpath(rel).read_bytes()  # before writing: ``target`` may be this very file
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
    return list(targets.values())

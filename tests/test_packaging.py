"""The package outside the repository: the default inputs it carries, `bvsr init`, the one
version, and the extras a command or a check asks for. The wheel itself, installed into a fresh
virtualenv and used in an empty folder, is tools/wheel_check.sh's."""

from __future__ import annotations

import fnmatch
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path
from types import SimpleNamespace

import pytest

from bvsr_cad import __version__, cli, defaults, extras
from bvsr_cad.checks.robot import check_pybullet, check_urdf_tools
from bvsr_cad.parameters.load import load_spec
from bvsr_cad.parameters.study import load_study

from .conftest import ROOT

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
#: The repository's default inputs, listed by hand (the folders the issue names).
REPOSITORY_FILES = [
    "data/paper_bvsr.csv",
    "params/bvsr.toml",
    "params/bvsr_l.toml",
    "studies/optimise.toml",
    "studies/vertebra.toml",
]


def test_one_copy_of_the_default_inputs():
    """The repository's params/, data/ and studies/ are links to the package's folders, and the
    package data of pyproject.toml takes every file in them."""
    for name in ("params", "data", "studies"):
        assert (ROOT / name).is_symlink()
        assert (ROOT / name).resolve() == (ROOT / "bvsr_cad" / "defaults" / name).resolve()
    assert defaults.files() == REPOSITORY_FILES
    patterns = PYPROJECT["tool"]["setuptools"]["package-data"]["bvsr_cad.defaults"]
    assert all(any(fnmatch.fnmatch(f, p) for p in patterns) for f in REPOSITORY_FILES)
    assert (
        defaults.path("params/bvsr.toml").read_bytes()
        == (ROOT / "params" / "bvsr.toml").read_bytes()
    )


def test_the_wheel_takes_every_data_file_of_the_package():
    """Each file under bvsr_cad/ that is not Python is package data of its package (pyproject.toml's
    patterns, globbed as setuptools globs them): the wheel carries it."""
    pkg = ROOT / "bvsr_cad"
    patterns = PYPROJECT["tool"]["setuptools"]["package-data"]
    taken = {
        f
        for name, globs in patterns.items()
        for g in globs
        for f in (ROOT / name.replace(".", "/")).glob(g)
        if f.is_file()
    }
    data = {
        f
        for f in pkg.rglob("*")
        if f.is_file()
        and f.suffix not in (".py", ".pyc")
        and "__pycache__" not in f.parts
        and not f.name.startswith(".")
    }
    assert sorted(p.relative_to(pkg).as_posix() for p in data - taken) == []


def test_init_writes_copies_whose_relative_paths_resolve(tmp_path, capsys):
    assert cli.main(["init", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for rel in REPOSITORY_FILES:
        assert (tmp_path / rel).read_bytes() == (ROOT / rel).read_bytes(), rel
        assert rel in out
    assert "bvsr build" in out and "bvsr check exports/bvsr" in out
    spec = load_spec(tmp_path / "params" / "bvsr.toml")
    data = (tmp_path / "params" / spec.calibration.data_file).resolve()
    assert data == (tmp_path / "data" / "paper_bvsr.csv").resolve()
    study = load_study(tmp_path / "studies" / "vertebra.toml")
    assert study.base_path.resolve() == (tmp_path / "params" / "bvsr.toml").resolve()


def test_init_never_overwrites_without_force(tmp_path, capsys):
    mine = tmp_path / "params" / "bvsr.toml"
    mine.parent.mkdir()
    mine.write_text("# my tail\n")
    assert cli.main(["init", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert str(mine) in err and "--force" in err
    assert mine.read_text() == "# my tail\n"
    assert not (
        tmp_path / "data"
    ).exists()  # nothing written, not even the files that did not exist
    assert cli.main(["init", str(tmp_path), "--force"]) == 0
    assert mine.read_bytes() == (ROOT / "params" / "bvsr.toml").read_bytes()


def test_build_without_a_file_takes_this_folders_copy_else_the_packaged_tail(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    said = []
    args = SimpleNamespace(params=None, func=cli.cmd_build)
    packaged = Path(cli._params_or_default(args, said.append))
    assert packaged.read_bytes() == (ROOT / "params" / "bvsr.toml").read_bytes()
    assert len(said) == 1 and "bvsr init" in said[0]
    cli.main(["init", "-q"])
    assert cli._params_or_default(args, said.append) == "params/bvsr.toml" and len(said) == 1
    assert (
        cli._params_or_default(SimpleNamespace(params="x.toml", func=cli.cmd_build), said.append)
        == "x.toml"
    )


def test_watch_without_a_file_asks_for_bvsr_init(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["watch"]) == 2
    assert "bvsr init" in capsys.readouterr().err


def test_one_version(capsys):
    """pyproject.toml's version, as installed, is the package's, the command's and the
    manifest's."""
    assert __version__ == metadata.version("bvsr_cad") == PYPROJECT["project"]["version"]
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"bvsr_cad {__version__}"
    res = subprocess.run(
        [sys.executable, "-m", "bvsr_cad", "--version"], capture_output=True, text=True, check=True
    )
    assert res.stdout.strip() == f"bvsr_cad {__version__}"
    from bvsr_cad.exporters import manifest

    assert manifest.__version__ is __version__


def test_extras_name_the_modules_their_distributions_install():
    """Each extra of :mod:`bvsr_cad.extras` is an extra of pyproject.toml, and its modules are
    installed here (the tests run with every extra)."""
    optional = PYPROJECT["project"]["optional-dependencies"]
    for extra in extras.MODULES:
        assert extra in optional
        assert extras.missing(extra) == [], extra
    assert set(optional["studies"]) and not {"dask", "optuna", "pandas", "pybullet", "yourdfpy"} & {
        r.split(">")[0].split("=")[0] for r in PYPROJECT["project"]["dependencies"]
    }


def test_a_command_needing_a_missing_extra_exits_2_with_the_install_line(monkeypatch, capsys):
    monkeypatch.setitem(extras.MODULES, "studies", ("dask", "bvsr_no_such_module"))
    assert cli.main(["sweep", str(ROOT / "studies" / "vertebra.toml"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "bvsr_no_such_module" in err and "pip install 'bvsr_cad[studies]'" in err
    monkeypatch.setitem(extras.MODULES, "gpu", ("jax", "bvsr_no_such_module.mjx"))
    with pytest.raises(
        extras.ExtraMissing,
        match=r"^MJX needs the 'gpu' extra \(bvsr_no_such_module.mjx not "
        r"installed\): pip install 'bvsr_cad\[gpu\]'$",
    ):
        extras.require("gpu", "MJX")


def test_a_check_needing_a_missing_extra_is_skipped_never_passed(monkeypatch, tmp_path):
    monkeypatch.setitem(extras.MODULES, "crosscheck", ("bvsr_no_such_module",))
    exp = SimpleNamespace(root=tmp_path, manifest={"robot": {"urdf": "robot/bvsr.urdf"}})
    results = [
        r for r in check_pybullet(exp) + check_urdf_tools(exp) if r.name != "urdf_check_urdf"
    ]
    assert [r.name for r in results] == ["pybullet_masses", "urdf_yourdfpy"]
    for r in results:
        assert r.passed is None and r.value is None and r.skipped
        assert "pip install 'bvsr_cad[crosscheck]'" in r.note


def test_viewer_scenes_are_the_same_bytes_on_every_python():
    """The gzip header of a scene file is RFC 1952's with no name, no time stamp, level 1 (XFL 4)
    and the OS byte 255 on every Python (3.13's gzip writes 255, 3.11 and 3.12 write 3): an export
    built on 3.13 equals one built on 3.12 file for file."""
    import base64
    import gzip
    import json

    from bvsr_cad.exporters.viewer import scene_script

    glb = bytes(range(256)) * 40
    text = scene_script("rest", glb)
    packed = base64.b64decode(
        json.loads("[" + text[text.index(",") + 1 : text.rindex(")")] + "]")[0]
    )
    assert packed[:10] == bytes.fromhex("1f8b08000000000004ff")
    assert gzip.decompress(packed) == glb

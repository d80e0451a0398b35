"""Parameter files: both defaults load; every kind of bad file is refused with
exit code 2 and a message naming the file, the key and what is allowed."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from bvsr_cad.cli import main
from bvsr_cad.parameters import layout, panel_rules
from bvsr_cad.parameters.load import ParamError, load_spec, spec_from_dict

from .conftest import PARAMS, write_toml


@pytest.mark.parametrize("name,segments,panels", [("bvsr", 2, 7), ("bvsr_l", 3, 10)])
def test_defaults_load(name, segments, panels):
    spec = load_spec(PARAMS / f"{name}.toml")
    assert spec.name == name and spec.segments == segments and spec.panels == panels
    assert spec.joint.panel_thickness_mm == pytest.approx(6.0)
    # Table I length: N H_a + (N + 1) x 6 mm.
    assert spec.length_mm == pytest.approx({2: 261.06, 3: 388.59}[segments])


def test_auto_taper_is_the_largest_feasible_cone(bvsr_spec):
    beta = panel_rules.max_feasible_taper_deg(bvsr_spec)
    # Independent closed form for the binding rule (pocket webs at the tip panel):
    # 2 r_tip sin 36 - d_pocket = min gap, r_tip = D_a/2 - z_tip tan(beta).
    j, fab = bvsr_spec.joint, bvsr_spec.fabrication
    d_pocket = j.base_diameter_mm + fab.pocket_clearance_mm
    r_tip = (fab.min_pocket_gap_mm + d_pocket) / (2 * math.sin(math.radians(36)))
    z_tip = (bvsr_spec.panels - 1) * j.joint_height_mm
    expected = math.degrees(math.atan((j.pitch_diameter_mm / 2 - r_tip) / z_tip))
    assert beta == pytest.approx(expected, abs=1e-6)
    assert "pocket_lower" in panel_rules.binding_constraint(bvsr_spec)
    # Just past it, validation refuses a fixed taper.
    with pytest.raises(ParamError, match="taper.half_angle_deg"):
        spec_from_dict({**_as_dict(bvsr_spec), "taper": {"half_angle_deg": beta + 0.01}})


def _as_dict(spec):
    import dataclasses

    return dataclasses.asdict(spec)


@pytest.mark.parametrize("name", ["bvsr", "bvsr_l"])
def test_the_web_rule_between_cuts_flags_every_pair_a_pair_by_pair_test_flags(name):
    """panel_problems tests only the pairs of cuts whose plan-view circles come near (numpy's gaps,
    :func:`~bvsr_cad.parameters.panel_rules._near_pairs`): on every panel, from no cone to well past
    the feasible one (where webs break), it flags the same pairs, in the same order, as testing
    every pair."""
    import numpy as np

    spec = load_spec(PARAMS / f"{name}.toml")
    fab = spec.fabrication
    flagged_somewhere = 0
    for beta in np.linspace(0.0, math.radians(3.0 * panel_rules.max_feasible_taper_deg(spec)), 25):
        for k in range(spec.panels):
            lay = layout.panel_layout(spec, k, beta)
            cuts = list(lay.cuts)
            every = []
            for i, a in enumerate(cuts):
                for b in cuts[i + 1 :]:
                    if not panel_rules._z_overlap(a, b) or "setscrew" in (a.role, b.role):
                        continue
                    gap, nested = panel_rules._circle_gap(a, b)
                    need = (
                        fab.min_pocket_gap_mm if a.role == b.role == "pocket" else fab.min_wall_mm
                    )
                    if not nested and gap < need - 1e-9:
                        every.append((a.name, b.name))
            names = {c.name for c in cuts}
            found = [
                p.features
                for p in panel_rules.panel_problems(spec, lay)
                if len(p.features) == 2 and set(p.features) <= names
            ]
            assert found == every, (name, beta, k)
            flagged_somewhere += len(every)
    assert flagged_somewhere > 0  # the sweep reaches cones where webs between cuts break


def test_soa_fold_residual_is_computed_not_forced(bvsr_spec):
    soa = bvsr_spec.soa
    rise = (soa.long_side_mm - soa.short_side_mm) / 2 / math.tan(math.radians(soa.dihedral_deg / 2))
    assert rise * 4 == pytest.approx(34.370, abs=1e-3)
    assert soa.built_origami_height_mm == pytest.approx(35.0)  # fold_height_from = origami_height
    assert soa.implied_dihedral_deg == pytest.approx(72.83, abs=0.01)
    shorter = spec_from_dict(
        {
            **_as_dict(bvsr_spec),
            "soa": {**_as_dict(bvsr_spec)["soa"], "fold_height_from": "dihedral"},
        }
    )
    assert shorter.soa.built_height_mm == pytest.approx(34.370 + 2.6, abs=1e-3)


def _bad_cases() -> list:
    """The cases of tests/data/bad_params.toml as pytest params (id: the case's description)."""
    cases = tomllib.loads((Path(__file__).parent / "data" / "bad_params.toml").read_text())["case"]
    return [
        pytest.param(c.get("set", {}), c.get("delete", []), c["expect"], id=c["desc"])
        for c in cases
    ]


def _edit(data: dict, path: str) -> tuple[dict, str]:
    """The table holding dotted ``path`` (created where missing) and the last key."""
    *tables, key = path.split(".")
    for name in tables:
        data = data.setdefault(name, {})
    return data, key


BAD = _bad_cases()


@pytest.mark.parametrize("edits,deletions,key", BAD)
def test_bad_parameters_exit_2_and_name_the_key(tmp_path, data, edits, deletions, key, capsys):
    for path, value in edits.items():
        table, name = _edit(data, path)
        table[name] = value
    for path in deletions:
        table, name = _edit(data, path)
        del table[name]
    path = write_toml(tmp_path / "bad.toml", data)
    with pytest.raises(ParamError) as err:
        load_spec(path)
    assert key in str(err.value) and str(path) in str(err.value)
    out = tmp_path / "out"
    assert main(["build", str(path), "-o", str(out), "-q"]) == 2
    msg = capsys.readouterr().err
    assert key in msg and "bad.toml" in msg
    assert not out.exists()


def test_broken_toml_exit_2(tmp_path, capsys):
    path = tmp_path / "broken.toml"
    path.write_text('name = "bvsr"\n[joint\ngap_mm = 36.51\n')
    assert main(["build", str(path), "-o", str(tmp_path / "o"), "-q"]) == 2
    assert "not valid TOML" in capsys.readouterr().err


def test_missing_file_exit_2(tmp_path, capsys):
    assert main(["build", str(tmp_path / "nope.toml"), "-q"]) == 2
    assert "file not found" in capsys.readouterr().err


def test_every_error_is_collected(tmp_path, data):
    data["joint"]["gap_mm"] = -1.0
    data["soa"]["pleats"] = 2.5
    data["lightening"]["colour"] = "red"
    with pytest.raises(ParamError) as err:
        load_spec(write_toml(tmp_path / "bad.toml", data))
    assert len(err.value.problems) == 3


def test_thin_mold_wall_names_the_rule_and_the_smallest_wall(data):
    """casting.cavity_wall_mm = 3.0 is refused at load, with why and what is allowed (not
    mid-build).

    Hand calculation: the pins sit mid-wall, so the wall needs a pin socket (3.0 + 0.2 mm) and
    casting.min_print_wall_mm = 1.2 mm on both sides: 3.2 + 2 x 1.2 = 5.6 mm. The bolts in the block
    corners need (sqrt 2 - 1)(rho + wall) >= sqrt 2 (1.7 + 2.4) + 1.7 with rho = 1.003 x 12.39 mm
    (the bellows corners): wall >= 5.69 mm, which binds.
    """
    data["casting"]["cavity_wall_mm"] = 3.0
    with pytest.raises(ParamError) as err:
        spec_from_dict(data, "bad.toml")
    msg = str(err.value)
    assert "casting.cavity_wall_mm = 3.0: mold set:" in msg
    assert (
        "1.30 mm short of casting.min_print_wall_mm" in msg
    )  # 3.0 / 2 - 3.2 / 2 = -0.1 mm web, 1.2 needed
    rho = 1.003 * ((18.21 / 2 - 1.2) * math.sqrt(2) + 1.2)
    wall = (math.sqrt(2) * (3.4 / 2 + 2 * 1.2) + 3.4 / 2) / (math.sqrt(2) - 1) - rho
    assert f"allowed: >= {math.ceil(wall * 100) / 100:.2f} mm" in msg
    data["casting"]["cavity_wall_mm"] = math.ceil(wall * 100) / 100
    spec_from_dict(data, "ok.toml")  # and that wall loads


def _generator_fails(monkeypatch, error):
    """Make the panel generator fail inside parts/panel.py as the kernel would."""
    import bvsr_cad.parts.panel as panel_module

    def broken(*_args, **_kwargs):
        raise error

    monkeypatch.setattr(panel_module, "cut_all", broken)


@pytest.mark.parametrize(
    "error",
    [
        "GeometryError('panel0: the kernel produced 2 solids instead of one')",
        "ValueError('joint.pitch_diameter_mm = 45.87: a rule the loader missed')",
    ],
)
def test_generator_failure_exits_2_with_advice_not_a_traceback(
    tmp_path, monkeypatch, capsys, error
):
    from bvsr_cad.parts.kernel import GeometryError  # noqa: F401 - used by eval

    _generator_fails(monkeypatch, eval(error))
    out = tmp_path / "out"
    assert main(["build", str(PARAMS / "bvsr.toml"), "-o", str(out), "--no-cache", "-q"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1  # one paragraph
    assert "bvsr.toml passed validation, but building a panel failed" in err
    assert "Nothing was published" in err and not out.exists()
    advice = (
        "change joint.pitch_diameter_mm"
        if "pitch" in error
        else "change [fabrication] (min_wall_mm"
    )
    assert advice in err


def test_a_value_error_outside_the_generators_keeps_its_traceback(monkeypatch):
    import bvsr_cad.assembly.assemble as build_module

    def bug(*_args, **_kwargs):
        raise ValueError("a bug, not a parameter")

    monkeypatch.setattr(build_module, "build_assembly", bug)
    with pytest.raises(ValueError, match="a bug"):
        main(["workspace", str(PARAMS / "bvsr.toml"), "--samples", "1", "-q"])


def test_a_bad_file_is_refused_before_the_pipeline_is_imported(tmp_path):
    """`bvsr build` refuses a bad parameter file without importing the pipeline (4-9 s of imports
    a user would wait for a one-key range error), and classifies it without importing it."""
    import subprocess
    import sys

    bad = tmp_path / "bad.toml"
    bad.write_text((PARAMS / "bvsr.toml").read_text().replace("pleats = 2 ", "pleats = 0 "))
    code = (
        "import sys; from bvsr_cad.cli import main; rc = main(['build', sys.argv[1], '-o', "
        "sys.argv[2], '-q']); "
        "print(rc, 'bvsr_cad.pipeline.stages' in sys.modules, 'build123d' in sys.modules)"
    )
    run = subprocess.run(
        [sys.executable, "-c", code, str(bad), str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.stdout.split() == ["2", "False", "False"], run.stdout + run.stderr
    assert "soa.pleats = 0" in run.stderr and not (tmp_path / "out").exists()


def test_the_command_ends_with_mains_exit_code_and_all_it_printed(tmp_path):
    """`python -m bvsr_cad.cli` (as the `bvsr` script, :func:`bvsr_cad.cli.console`) ends without
    the interpreter's teardown: with main's exit code, and every line it printed on either
    stream."""
    bad = tmp_path / "bad.toml"
    bad.write_text((PARAMS / "bvsr.toml").read_text().replace("segments = 2", "segments = 0", 1))
    done = subprocess.run(
        [sys.executable, "-m", "bvsr_cad.cli", "build", str(bad), "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2 and "segments" in done.stderr and "bvsr: error" in done.stderr, (
        done.stderr
    )
    assert not (tmp_path / "out").exists()
    buffered = {
        k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"
    }  # a pipe's block buffering
    helped = subprocess.run(
        [sys.executable, "-m", "bvsr_cad.cli", "build", "--help"],
        capture_output=True,
        text=True,
        timeout=300,
        env=buffered,
    )
    # The whole help, to its last line (what is still buffered when main returns is flushed first).
    assert helped.returncode == 0 and helped.stdout.startswith("usage: bvsr build")
    assert helped.stdout.rstrip().endswith("~/.cache/bvsr_cad/artifacts)")


ALLOCATIONS = r"""
import ctypes, sys
import numpy as np
fields = ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
          "fordblks", "keepcost")
class Info(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in fields]
libc = ctypes.CDLL(None)
libc.mallinfo2.restype = Info
if sys.argv[1] == "tuned":
    from bvsr_cad.process import tune_allocator
    assert tune_allocator()
a = np.ones(2 << 20)  # 16 MiB, a build's large temporary
mapped = libc.mallinfo2().hblkhd  # bytes in blocks of their own mapping
del a
kept = libc.mallinfo2().fordblks  # free bytes the heap keeps for the next allocation
print(mapped, kept)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_a_bvsr_process_reuses_freed_memory():
    """:func:`bvsr_cad.process.tune_allocator` (the command and its second processes):
    a large array comes from the heap and, freed, stays there for the next one; with glibc's
    defaults it is a mapping of its own, handed back to the kernel when freed, whose pages the
    kernel zeroes again at the next one (a cold build's minor page faults 690,000-725,000 with the
    defaults, 503,000-524,000 tuned). Read from glibc's own accounting (``mallinfo2``): page-fault
    counts move with transparent huge pages."""
    import ctypes

    if not hasattr(ctypes.CDLL(None), "mallinfo2"):
        pytest.skip("glibc before 2.33: no mallinfo2")
    out = {
        mode: [
            int(x)
            for x in subprocess.run(
                [sys.executable, "-c", ALLOCATIONS, mode],
                capture_output=True,
                text=True,
                check=True,
                timeout=120,
            ).stdout.split()
        ]
        for mode in ("default", "tuned")
    }
    (mapped_default, _), (mapped_tuned, kept_tuned) = out["default"], out["tuned"]
    array_bytes = 16 << 20
    assert (
        mapped_default >= array_bytes and mapped_tuned < array_bytes and kept_tuned >= array_bytes
    ), out


COLLECTIONS = r"""
import gc, sys
from bvsr_cad import process
if sys.argv[1] == "entry":
    process.tune_process()  # what the entry points call
def collections():
    return sum(s["collections"] for s in gc.get_stats())
before = collections()
if sys.argv[1] == "plain":
    import bvsr_cad.analysis.run
    during = collections() - before
else:
    with process.library_imports():
        assert not gc.isenabled()
        import bvsr_cad.analysis.run
        during = collections() - before
print(during, gc.isenabled(), gc.get_freeze_count())
"""


def test_library_imports_pause_the_garbage_collector():
    """:func:`bvsr_cad.process.library_imports`: the libraries' imports (the CAD
    kernel, scipy, trimesh, ...) run without Python's cyclic collector, which ran hundreds of times
    over them otherwise (0.4-0.5 CPU s a process); it runs again after, and only an entry point's
    process (:func:`~bvsr_cad.process.tune_collector`) freezes what was imported (a
    library call in someone else's process leaves its collector as it was)."""
    out = {
        mode: subprocess.run(
            [sys.executable, "-c", COLLECTIONS, mode],
            capture_output=True,
            text=True,
            check=True,
            timeout=300,
        ).stdout.split()
        for mode in ("plain", "library", "entry")
    }
    plain, library, entry = ((int(n), on == "True", int(frozen)) for n, on, frozen in out.values())
    assert plain[0] > 100 and plain[1] and plain[2] == 0, out
    assert library == (0, True, 0), out
    assert entry[0] == 0 and entry[1] and entry[2] > 100_000, out


MUJOCO_IMPORT = r"""
import os, sys
from bvsr_cad import process
if sys.argv[1] == "entry":
    process.tune_process()  # what the entry points call
import mujoco
print("glfw" in sys.modules, os.environ.get("MUJOCO_GL", "-"))
"""


@pytest.mark.parametrize("users", [None, "glfw"])
def test_a_bvsr_process_loads_no_opengl_for_mujoco(users):
    """:func:`bvsr_cad.process.no_mujoco_rendering` (the command and its second
    processes): ``import mujoco`` loads no GLFW, whose binding starts a Python interpreter at import
    (0.1 s a process); an environment that names MuJoCo's OpenGL keeps it."""
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    if users:
        env["MUJOCO_GL"] = users
    out = {
        mode: subprocess.run(
            [sys.executable, "-c", MUJOCO_IMPORT, mode],
            capture_output=True,
            text=True,
            check=True,
            timeout=120,
            env=env,
        ).stdout.split()
        for mode in ("plain", "entry")
    }
    if users is None:
        assert out == {"plain": ["True", "-"], "entry": ["False", "disable"]}, out
    else:
        assert out == {"plain": ["True", users], "entry": ["True", users]}, out


BLAS_THREADS = r"""
import sys
from bvsr_cad import process
if sys.argv[1] == "entry":
    process.tune_process()  # what the entry points call
import numpy, scipy.linalg
from threadpoolctl import threadpool_info
print(sorted({i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas"}))
"""


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="OpenBLAS runs one thread on one core anyway")
def test_a_bvsr_process_runs_openblas_on_one_thread():
    """:func:`bvsr_cad.process.one_blas_thread` (the command and its second
    processes): numpy's and scipy's OpenBLAS on one thread, where they would take one per core; a
    number the environment sets is kept."""
    pytest.importorskip("threadpoolctl")
    from bvsr_cad.process import BLAS_THREAD_VARIABLES

    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}

    def threads(mode: str, **extra: str) -> list[int]:
        done = subprocess.run(
            [sys.executable, "-c", BLAS_THREADS, mode],
            capture_output=True,
            text=True,
            check=True,
            timeout=120,
            env={**env, **extra},
        )
        return json.loads(done.stdout)

    assert threads("entry") == [1]
    assert threads("plain")[0] > 1  # OpenBLAS's default: a thread per core
    assert threads("entry", OPENBLAS_NUM_THREADS="2") == [2]
    assert threads("entry", OMP_NUM_THREADS="2") == [2]


@pytest.mark.parametrize("value", ["0", "-1", "two", "1.5"])
def test_a_bad_process_count_exits_2_naming_the_variable_before_anything_is_written(
    tmp_path, monkeypatch, capsys, value
):
    """``BVSR_PROCESSES`` must be a whole number, 1 or more: anything else is refused with exit code
    2, the variable, its value and what it may be, and nothing written."""
    monkeypatch.setenv("BVSR_PROCESSES", value)
    assert main(["build", str(PARAMS / "bvsr.toml"), "-o", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"BVSR_PROCESSES={value!r}" in err and "whole number, 1 or more" in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()


_PROCESSES = """
import os, sys
os.sched_setaffinity(0, set(sorted(os.sched_getaffinity(0))[: int(sys.argv[1])]))
from bvsr_cad.process import build_processes
from bvsr_cad.pipeline.processes.worker import SecondProcess
child = SecondProcess.start("bvsr_cad.pipeline.processes.analyses_process", [], os.getcwd())
print(build_processes(), child is not None)
if child is not None:
    child.close()
"""


@pytest.mark.skipif(
    not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2,
    reason="needs two cores this process may run on",
)
@pytest.mark.parametrize(
    ("cores", "cap", "expected"), [(1, None, "1 False"), (2, None, "2 True"), (2, "1", "1 False")]
)
def test_a_build_starts_second_processes_only_on_cores_it_may_use(tmp_path, cores, cap, expected):
    """A build's second processes go one a core this process may run on (its CPU affinity, as
    ``taskset`` sets it), capped by ``BVSR_PROCESSES``: pinned to one core, or capped to one
    process, it starts none."""
    env = {k: v for k, v in os.environ.items() if k != "BVSR_PROCESSES"}
    if cap is not None:
        env["BVSR_PROCESSES"] = cap
    out = subprocess.run(
        [sys.executable, "-c", _PROCESSES, str(cores)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split("\n")[-2] == expected, out.stdout

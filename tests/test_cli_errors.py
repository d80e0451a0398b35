"""Every error that means bad input subclasses :class:`bvsr_cad.errors.BadInput`, and the command
maps that one class to exit code 2 with its message: an error class that lost the base would end in
a traceback and exit code 1, silently. The list below is written here, from the command's
documented refusals (a file, an export, an output folder, a host, a missing extra or slicer), not
read from the code under test."""

from __future__ import annotations

import importlib

import pytest

from bvsr_cad import cli
from bvsr_cad.errors import BadInput, GeneratorFailure

#: Each bad-input error, its module and the base it had before BadInput (code catching that base
#: must still catch it).
BAD_INPUT = (
    ("analysis.calibrate", "CalibrationError", ValueError),
    ("analysis.limits", "UselessResultError", ValueError),
    ("checks.export", "ExportError", ValueError),
    ("checks.slicer", "SlicerMissingError", RuntimeError),
    ("extras", "ExtraMissing", ImportError),
    ("parameters.load", "ParamError", ValueError),
    ("parameters.load", "InputFileError", ValueError),
    ("parameters.measurements", "MeasurementError", ValueError),
    ("parameters.study", "StudyError", ValueError),
    ("exporters.ocp_viewer", "ViewerUnavailable", RuntimeError),
    ("exporters.mount", "MountError", ValueError),
    ("exporters.starter_files", "StarterExistsError", FileExistsError),
    ("pipeline.publish", "OutputError", ValueError),
    ("simulation.sim", "SimulationInputError", ValueError),
    ("simulation.quadruped", "QuadrupedInputError", ValueError),
    ("studies.sweep", "SweepError", RuntimeError),
)


@pytest.mark.parametrize(("module", "name", "base"), BAD_INPUT, ids=[n for _m, n, _b in BAD_INPUT])
def test_every_bad_input_error_is_a_bad_input_and_keeps_its_base(module, name, base):
    cls = getattr(importlib.import_module(f"bvsr_cad.{module}"), name)
    assert issubclass(cls, BadInput) and issubclass(cls, base), f"bvsr_cad.{module}.{name}"


def test_a_bad_input_exits_2_with_its_message_and_no_traceback(monkeypatch, capsys):
    from bvsr_cad.simulation.sim import SimulationInputError

    def refuse(args):
        raise SimulationInputError("simulate.pressure_bar = 9: allowed 0 < p <= 6")

    monkeypatch.setattr(cli, "cmd_build", refuse)
    assert cli.main(["build", "params/bvsr.toml"]) == 2
    assert capsys.readouterr().err == "bvsr: error: simulate.pressure_bar = 9: allowed 0 < p <= 6\n"


def test_the_kernels_failure_is_a_generator_failure_and_a_bug_stays_a_traceback(monkeypatch):
    from bvsr_cad.parts.kernel import GeometryError

    assert issubclass(GeometryError, GeneratorFailure) and issubclass(GeometryError, RuntimeError)

    def bug(args):
        raise KeyError("a bug")

    monkeypatch.setattr(cli, "cmd_build", bug)
    with pytest.raises(KeyError):
        cli.main(["build", "params/bvsr.toml"])

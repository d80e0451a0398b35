"""Reading an export folder: the manifest and the meshes it names."""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ..errors import BadInput


class ExportError(ValueError, BadInput):
    """The folder is not a readable bvsr export."""


@dataclass
class Export:
    root: Path
    manifest: dict[str, Any]

    @classmethod
    def open(cls, root: str | Path, manifest: dict[str, Any] | None = None) -> Export:
        """The export at ``root``; ``manifest``: its manifest as a build hands it to its checks
        before the file is written (None: read from ``root/manifest.json``)."""
        root = Path(root).resolve()  # checks may change the working folder (MuJoCo logs)
        path = root / "manifest.json"
        if not root.is_dir():
            raise ExportError(f"{root}: not a folder; expected an export made by `bvsr build`")
        if manifest is None:
            if not path.is_file():
                raise ExportError(
                    f"{root}: no manifest.json; expected an export made by `bvsr build`"
                )
            try:
                manifest = json.loads(path.read_text())
            except json.JSONDecodeError as exc:
                raise ExportError(f"{path}: not valid JSON ({exc})") from None
        for key in ("name", "parts", "mass_g"):
            if key not in manifest:
                raise ExportError(f"{path}: missing key {key!r}")
        return cls(root, manifest)

    @cached_property
    def parts(self) -> list[dict[str, Any]]:
        return list(self.manifest["parts"])

    def mesh(self, rel: str) -> trimesh.Trimesh:
        # process=False keeps the file's own vertices: a check must see what a slicer sees.
        mesh = trimesh.load(self.root / rel, file_type="stl", force="mesh", process=False)
        mesh.merge_vertices()
        return mesh

    def part_frame_mesh(self, part: dict[str, Any]) -> trimesh.Trimesh:
        """The part's STL moved back from print orientation into the part frame."""
        mesh = self.mesh(part["files"]["stl"])
        mesh.apply_transform(np.linalg.inv(np.asarray(part["print_transform"], float)))
        return mesh

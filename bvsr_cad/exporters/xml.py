"""The one XML helper of the URDF and MJCF writers: numbers as attribute text, element trees to
files."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation


def num(v: float) -> str:
    """A number as attribute text: 10 significant digits (about 1e-10 relative, below every
    tolerance)."""
    return f"{float(v):.10g}"


def vec(values) -> str:
    return " ".join(num(v) for v in values)


def quat_wxyz(R: np.ndarray) -> str:
    """MuJoCo's quaternion order (w, x, y, z) of a rotation matrix."""
    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return vec((w, x, y, z))


def origin_attrs(T) -> dict[str, str]:
    """URDF ``<origin xyz rpy>`` of a 4x4 transform (metres, fixed-axis roll-pitch-yaw)."""
    T = np.asarray(T, float)
    rpy = Rotation.from_matrix(T[:3, :3]).as_euler("xyz")
    return {"xyz": vec(T[:3, 3]), "rpy": vec(rpy)}


def write_tree(root: ET.Element | ET.ElementTree, path: Path, declaration: bool = True) -> None:
    """Indent and write an element tree as UTF-8."""
    tree = root if isinstance(root, ET.ElementTree) else ET.ElementTree(root)
    ET.indent(tree)
    tree.write(path, encoding="utf-8", xml_declaration=declaration)

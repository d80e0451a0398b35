"""Bill of materials: ``bom.csv`` and ``bom.md`` with a quantity column.

Every row is computed from the typed products (the assembly, the rigid twin's pieces, the mold set;
quantities from :func:`bvsr_cad.assembly.fabrication.made_items`, the list the print jobs read too):
parts with their counts, materials, processes and masses; rods with cut lengths; fasteners by
standard designation; pneumatic items with the tube length of every line from the panel layout (the
tube rings) and the tail length; valves per the paper's system (pressure and vacuum per line);
totals per product.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from ..assembly.assemble import Assembly
from ..assembly.fabrication import made_items
from ..assembly.pneumatic_lines import line_tube_lengths_mm, tube_routes_mm
from ..assembly.products import RIGID_MATERIAL
from ..parameters.standard_parts import metric, size_for_clearance_hole, size_for_tap_drill
from ..parameters.tables import FabricationPackage
from ..parameters.twin import rigid_joining
from ..parts.mold import MoldSet
from ..parts.rigid_tail import RigidPiece

#: Preferred lengths of ISO 4762 socket head cap screws, mm.
ISO_4762_LENGTHS_MM = (6, 8, 10, 12, 16, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 80, 90, 100)

FIELDS = (
    "product",
    "category",
    "item",
    "designation",
    "quantity",
    "unit",
    "material",
    "process",
    "mass_each_g",
    "mass_total_g",
    "notes",
)


@dataclass(frozen=True)
class BomRow:
    product: str  # BVSR, rigid tail, molds, pneumatics
    category: str  # part, rod, fastener, pneumatic, total
    item: str
    designation: str
    quantity: float
    unit: str  # pcs, mm
    material: str
    process: str
    mass_each_g: float | None
    mass_total_g: float | None
    notes: str = ""


def _mold_bolt_length_mm(mold_set: MoldSet, thread: float) -> tuple[int, float]:
    block = mold_set.info.get("block_mm")
    grip = float(block[2]) if block else 0.0
    need = grip + metric(thread).nut_height_mm + 1.0
    for length in ISO_4762_LENGTHS_MM:
        if length >= need:
            return length, grip
    return int(math.ceil(need / 5.0) * 5), grip


def bom_rows(
    asm: Assembly, pieces: Sequence[RigidPiece] = (), mold_set: MoldSet | None = None
) -> list[BomRow]:
    """Every BOM row of the three products (parts, rods, fasteners, pneumatics, totals)."""
    spec = asm.spec
    items = made_items(asm, pieces, mold_set)
    roles: dict[str, int] = {}  # the panels' cuts by role: what the panels are built with
    for lay in asm.panel_layouts:
        for c in lay.cuts:
            roles[c.role] = roles.get(c.role, 0) + 1
    bvsr, bvsr_mass = _bvsr_part_rows(asm, items)
    pneumatics, total_tube, lines = _pneumatic_rows(asm, roles)
    rigid, rigid_mass = _rigid_tail_rows(spec, items, pieces)
    molds, mold_mass = _mold_rows(spec, items, mold_set)
    rows = [*bvsr, *_bvsr_fastener_rows(asm, roles), *pneumatics, *rigid, *molds]

    d_tube = spec.tubes.outer_diameter_mm
    rows.append(
        BomRow(
            "BVSR",
            "total",
            "BVSR modelled mass",
            "panels + SOAs + rods",
            1,
            "",
            "",
            "",
            bvsr_mass,
            bvsr_mass,
            "fittings, tubes, adhesive and inserts not weighed",
        )
    )
    if pieces:
        rows.append(
            BomRow(
                "rigid tail",
                "total",
                "rigid tail mass",
                "all pieces, solid PLA",
                1,
                "",
                RIGID_MATERIAL,
                "FDM",
                rigid_mass,
                rigid_mass,
                "infill lowers it",
            )
        )
    if mold_set is not None and mold_set.parts:
        rows.append(
            BomRow(
                "molds",
                "total",
                "mold material",
                "rigid sets + cores",
                1,
                "",
                "",
                "FDM",
                mold_mass,
                mold_mass,
                "",
            )
        )
    rows.append(
        BomRow(
            "pneumatics",
            "total",
            "tube",
            f"PU tube {d_tube:g} mm, all lines",
            round(total_tube, 1),
            "mm",
            "PU",
            "cut",
            None,
            None,
            f"{lines} lines",
        )
    )
    return rows


def _bvsr_part_rows(asm: Assembly, items) -> tuple[list[BomRow], float]:
    """The BVSR's parts and rods, and their modelled mass, g."""
    spec = asm.spec
    rows: list[BomRow] = []
    bvsr_mass = 0.0
    for it in (i for i in items if i.product == "BVSR"):
        part = asm.parts[it.source]
        bvsr_mass += it.quantity * it.mass_each_g
        if it.kind == "rod":
            info = part.info
            rows.append(
                BomRow(
                    "BVSR",
                    "rod",
                    it.label,
                    f"{spec.material(it.material).name}, D "  # the name says its form: rod, cord
                    f"{info['diameter_mm']:g} mm, cut to {info['cut_length_mm']:.2f} mm",
                    it.quantity,
                    "pcs",
                    it.material,
                    "cut",
                    it.mass_each_g,
                    it.quantity * it.mass_each_g,
                    "thread both ends to match the panel sockets"
                    if spec.vertebra.socket == "threaded"
                    else "held by set screws",
                )
            )
        else:
            names = [i.name for i in asm.instances_of(it.source)]
            rows.append(
                BomRow(
                    "BVSR",
                    "part",
                    it.label,
                    it.kind + (f" ({part.info['panel_kind']})" if it.kind == "panel" else ""),
                    it.quantity,
                    "pcs",
                    it.material,
                    it.process,
                    it.mass_each_g,
                    it.quantity * it.mass_each_g,
                    ", ".join(names[:3]) + (" ..." if len(names) > 3 else ""),
                )
            )
    return rows, bvsr_mass


def _bvsr_fastener_rows(asm: Assembly, roles: dict[str, int]) -> list[BomRow]:
    """The BVSR's inserts and set screws, counted from the panel layouts."""
    spec = asm.spec
    rows: list[BomRow] = []
    mount_inserts = sum(
        1 for lay in asm.panel_layouts for c in lay.cuts if c.name.startswith("mount_insert")
    )
    payload_inserts = sum(
        1 for lay in asm.panel_layouts for c in lay.cuts if c.name.startswith("payload_insert")
    )
    if mount_inserts:
        rows.append(
            BomRow(
                "BVSR",
                "fastener",
                "mount insert",
                f"M3 heat-set insert, {spec.mount.insert_diameter_mm:g} "
                f"mm bore, {spec.mount.insert_depth_mm:g} mm long",
                mount_inserts,
                "pcs",
                "brass",
                "bought",
                None,
                None,
                "root mount to the robot (plus M3 screws of the robot's length)",
            )
        )
    if payload_inserts:
        rows.append(
            BomRow(
                "BVSR",
                "fastener",
                "payload insert",
                f"M3 heat-set insert, "
                f"{spec.payload.insert_diameter_mm:g} mm bore, {spec.payload.insert_depth_mm:g} mm "
                "long",
                payload_inserts,
                "pcs",
                "brass",
                "bought",
                None,
                None,
                "tip payload mount",
            )
        )
    if spec.vertebra.socket == "set_screw":
        size = size_for_tap_drill(spec.socket.set_screw_tap_drill_mm).diameter_mm
        rows.append(
            BomRow(
                "BVSR",
                "fastener",
                "rod set screw",
                f"ISO 4026 M{size:g} x 4 set screw, flat point",
                roles.get("setscrew", 0),
                "pcs",
                "steel",
                "bought",
                None,
                None,
                "one per panel socket",
            )
        )
    return rows


def _pneumatic_rows(asm: Assembly, roles: dict[str, int]) -> tuple[list[BomRow], float, int]:
    """The fittings, each line's tube, tees or manifolds and valves; the tubes' total length, mm,
    and the number of lines."""
    spec = asm.spec
    lines = spec.segments * 5
    d_tube = spec.tubes.outer_diameter_mm
    fitting = BomRow(
        "pneumatics",
        "pneumatic",
        "root fitting",
        f"push-in fitting M5 x tube {d_tube:g} mm, straight",
        roles.get("port", 0),
        "pcs",
        "",
        "bought",
        None,
        None,
        "segment 1's five lines, in the root mount's tapped ports",
    )
    tubes, total_tube = _tube_rows(asm)
    valves = _valve_rows(spec.fabrication_package, lines, d_tube)
    return [fitting, *tubes, *valves], total_tube, lines


def _tube_rows(asm: Assembly) -> tuple[list[BomRow], float]:
    """Each line's tube, cut to its route inside the tail with a bending allowance and a lead to
    the valves; their total length, mm."""
    spec = asm.spec
    fp = spec.fabrication_package
    d_tube = spec.tubes.outer_diameter_mm
    routes = tube_routes_mm(asm)
    cut = line_tube_lengths_mm(asm)
    rows = []
    total_tube = 0.0
    for line, inside in routes.items():
        length = cut[line]
        total_tube += length
        rows.append(
            BomRow(
                "pneumatics",
                "pneumatic",
                f"tube {line}",
                f"PU tube {d_tube:g} x {spec.tubes.inner_diameter_mm:g} mm, cut to {length:.1f} mm",
                length,
                "mm",
                "PU",
                "cut",
                None,
                None,
                f"{inside:.1f} mm inside the tail (+{100 * fp.tube_bend_allowance:.0f} % for "
                f"bending) + {fp.tube_lead_mm:g} mm lead to the valves",
            )
        )
    return rows, total_tube


def _valve_rows(fp: FabricationPackage, lines: int, d_tube: float) -> list[BomRow]:
    """What joins each line to its valves (a tee for two, else a manifold) and the valves."""
    joiner = (
        BomRow(
            "pneumatics",
            "pneumatic",
            "tee",
            f"push-in tee, tube {d_tube:g} mm",
            lines,
            "pcs",
            "",
            "bought",
            None,
            None,
            "joins each line to its pressure and its vacuum valve",
        )
        if fp.valves_per_line == 2
        else BomRow(
            "pneumatics",
            "pneumatic",
            "manifold",
            f"push-in manifold 1 x {fp.valves_per_line}",
            lines,
            "pcs",
            "",
            "bought",
            None,
            None,
            "joins each line to its valves",
        )
    )
    valves = BomRow(
        "pneumatics",
        "pneumatic",
        "solenoid valve",
        "2/2-way solenoid valve, 24 V DC",
        lines * fp.valves_per_line,
        "pcs",
        "",
        "bought",
        None,
        None,
        f"{fp.valves_per_line} per line x {lines} lines (paper: 20 valves for 10 channels)",
    )
    return [joiner, valves]


def _rigid_tail_rows(spec, items, pieces: Sequence[RigidPiece]) -> tuple[list[BomRow], float]:
    """The rigid comparison tail's pieces, dowel pins, tie rod and nuts, and its mass, g."""
    rows: list[BomRow] = []
    rigid_mass = 0.0
    if not pieces:
        return rows, rigid_mass
    size = {p.name: p.size_mm for p in pieces}
    for it in (i for i in items if i.product == "rigid tail"):
        rigid_mass += it.mass_each_g
        sx, sy, sz = size[it.source]
        rows.append(
            BomRow(
                "rigid tail",
                "part",
                it.label,
                f"rigid tail piece {sx:.1f} x {sy:.1f} x {sz:.1f} mm",
                it.quantity,
                "pcs",
                it.material,
                it.process,
                it.mass_each_g,
                it.mass_each_g,
                "mass at solid density; infill lowers it",
            )
        )
    j = rigid_joining(spec)
    rows.append(
        BomRow(
            "rigid tail",
            "fastener",
            "dowel pin",
            j.pin_designation,
            j.pin_count,
            "pcs",
            "steel",
            "bought",
            None,
            None,
            "one per SOA column end",
        )
    )
    rows.append(
        BomRow(
            "rigid tail",
            "fastener",
            "tie rod",
            f"{j.tie_rod_designation} threaded rod, cut to {j.tie_rod_cut_length_mm:.1f} mm",
            1,
            "pcs",
            "steel",
            "cut",
            None,
            None,
            "through the rod column, clamps every piece",
        )
    )
    rows.append(
        BomRow(
            "rigid tail",
            "fastener",
            "tie rod nut",
            j.nut_designation + " hex nut",
            j.nut_count,
            "pcs",
            "steel",
            "bought",
            None,
            None,
            "in the root and tip nut pockets",
        )
    )
    return rows, rigid_mass


def _mold_rows(spec, items, mold_set: MoldSet | None) -> tuple[list[BomRow], float]:
    """The mold parts and cores, the mold bolts and nuts, and the molds' printed mass, g."""
    fp = spec.fabrication_package
    rows: list[BomRow] = []
    mold_mass = 0.0
    for it in (i for i in items if i.product == "molds"):
        sac = it.kind == "mold_core"
        mold_mass += it.quantity * it.mass_each_g
        rows.append(
            BomRow(
                "molds",
                "part",
                it.label,
                "sacrificial core (dissolve after casting)"
                if sac
                else f"mold {mold_set.parts[it.source].role}",
                it.quantity,
                "pcs",
                it.material,
                "FDM",
                it.mass_each_g,
                it.quantity * it.mass_each_g,
                "one per SOA cast" if sac else f"{fp.mold_sets} mold sets",
            )
        )
    if mold_set is not None and mold_set.parts:
        thread = size_for_clearance_hole(spec.casting.bolt_hole_diameter_mm).diameter_mm
        length, grip = _mold_bolt_length_mm(mold_set, thread)
        rows.append(
            BomRow(
                "molds",
                "fastener",
                "mold bolt",
                f"ISO 4762 M{thread:g} x {length}",
                4 * fp.mold_sets,
                "pcs",
                "steel",
                "bought",
                None,
                None,
                f"four per set through lid, halves and plate (grip {grip:.1f} mm)",
            )
        )
        rows.append(
            BomRow(
                "molds",
                "fastener",
                "mold nut",
                f"ISO 4032 M{thread:g} hex nut",
                4 * fp.mold_sets,
                "pcs",
                "steel",
                "bought",
                None,
                None,
                "four per set",
            )
        )
    return rows, mold_mass


def _fmt(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.2f}" if not v.is_integer() else f"{int(v)}"
    return str(v)


def write_bom(root: Path, rows: list[BomRow]) -> dict[str, Any]:
    """Write ``bom.csv`` and ``bom.md``; returns the manifest's ``bom`` section."""
    with (root / "bom.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: _fmt(v) for k, v in asdict(r).items()})
    lines = [
        "# Bill of materials",
        "",
        "Counts from the assembly; masses from the B-rep volumes and the densities in the "
        "parameter file.",
        "",
    ]
    for product in dict.fromkeys(r.product for r in rows):
        lines += [
            f"## {product}",
            "",
            "| item | designation | qty | unit | material | process | mass each (g) "
            "| mass total (g) | notes |",
            "|---|---|---:|---|---|---|---:|---:|---|",
        ]
        for r in rows:
            if r.product == product:
                item = f"**{r.item}**" if r.category == "total" else r.item
                lines.append(
                    f"| {item} | {r.designation} | {_fmt(r.quantity)} | {r.unit} | {r.material} | "
                    f"{r.process} | {_fmt(r.mass_each_g)} | {_fmt(r.mass_total_g)} | {r.notes} |"
                )
        lines.append("")
    (root / "bom.md").write_text("\n".join(lines))
    totals = {
        r.item: {"quantity": r.quantity, "unit": r.unit, "mass_g": r.mass_total_g}
        for r in rows
        if r.category == "total"
    }
    counts = {
        "printed_parts": sum(
            r.quantity for r in rows if r.category == "part" and r.process in ("MJF", "FDM")
        ),
        "cast_parts": sum(r.quantity for r in rows if r.process == "cast"),
        "fasteners": sum(r.quantity for r in rows if r.category == "fastener" and r.unit == "pcs"),
        "valves": sum(r.quantity for r in rows if r.item == "solenoid valve"),
    }
    return {"csv": "bom.csv", "md": "bom.md", "rows": len(rows), "totals": totals, "counts": counts}

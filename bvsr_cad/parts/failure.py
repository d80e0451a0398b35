"""What to tell the user when a part generator fails on parameters that passed validation: which
part, the keys its message names (else the tables that shape that generator), and that the rules
checked at load do not cover this combination yet.

Imports nothing heavy: ``bvsr`` reads it to word an error, before or without the CAD kernel.
"""

from __future__ import annotations

import re
from pathlib import Path

#: Which parameters shape each generator (bvsr_cad/parts/<module>.py), for the advice after a
#: failure.
GENERATOR_PARAMETERS = {
    "mold": (
        "the SOA casting mold set",
        "[casting] (cavity_wall_mm, pins, bolts, gate, vents) or [soa]",
    ),
    "rigid_tail": (
        "the rigid comparison tail",
        "[fabrication_package] (printer_*_mm, pin_*, tie_rod_*) or "
        "[joint] (panel_diameter_mm, joint_height_mm)",
    ),
    "panel": (
        "a panel",
        "[fabrication] (min_wall_mm, min_pocket_gap_mm), [tubes], [lightening], [mount], "
        "[payload], [socket] or [joint]",
    ),
    "soa": ("the SOA", "[soa] (facet_thickness_mm, fillet_radius_mm, sides, dihedral_deg)"),
    "vertebra": ("the rod", "[vertebra] or [joint]"),
}


def raised_in_parts(exc: BaseException) -> str | None:
    """The generator module (``bvsr_cad/parts/<name>.py``) the exception was raised in, innermost
    first (the kernel helpers' module only when no generator is on the traceback); None if none."""
    tb, found = exc.__traceback__, None
    while tb is not None:
        path = Path(tb.tb_frame.f_code.co_filename)
        if path.parent.name == "parts" and path.parent.parent.name == "bvsr_cad":
            found = path.stem if path.stem != "kernel" or found is None else found
        tb = tb.tb_next
    return found


def generator_failure(exc: BaseException, source: str | None, published: str = "") -> str:
    """One paragraph for a generator that failed on a parameter file that loaded: what, where, what
    to change.

    Args:
        exc: the failure, its traceback through ``bvsr_cad/parts/``.
        source: the parameter file the user named (None: "the input").
        published: a sentence on what was published (the build's: nothing).

    Returns:
        ``bvsr: error: ...``: the part, the message, the keys to change (those the message names,
        else the generator's tables) and the request to report the file.
    """
    where = raised_in_parts(exc)
    part, params = GENERATOR_PARAMETERS.get(
        where or "", ("a part", "the parameters of the part it names")
    )
    text = " ".join(str(exc).split())
    # The keys a message leads with ("casting.cavity_wall_mm = 3.0: ..."), else every key it
    # mentions.
    named = list(dict.fromkeys(re.findall(r"(?:^|; )([a-z_]+\.[a-z_]+) = ", text))) or list(
        dict.fromkeys(re.findall(r"\b[a-z_]+\.[a-z_]+_(?:mm|deg|percent|material|thread)\b", text))
    )
    change = f"change {', '.join(named)}" if named else f"change {params}"
    return (
        f"bvsr: error: {source or 'the input'} passed validation, but building {part} failed: "
        f"{text}."
        f"{published} To build it, {change}; the rules checked at load do not cover this "
        "combination yet, "
        "so please report the parameter file with this message."
    )

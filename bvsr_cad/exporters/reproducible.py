"""Byte-reproducible files: the same parameter file gives the same bytes in every build.

Two writers stamp the time or chance into their files: OCCT's STEP writer
(the header's ``FILE_NAME`` time stamp, assembly usage ids counted across the
process's writes, and the colour entities written in the order of an in-memory map)
and the 3MF writer (each zip entry's date, and a random ``p:UUID`` per object and
build item).
:func:`make_reproducible` rewrites both, over a whole export folder, to a
fixed time and to UUIDs derived from the file's name and the item's place
(still unique within the file); the real build time lives in the manifest's ``volatile``
section with the other fields that change from build to build.
"""

from __future__ import annotations

import re
import uuid
import zipfile
from collections.abc import Callable
from pathlib import Path

#: The time stamp every STEP header carries (ISO 8601, as OCCT writes it).
FIXED_STEP_TIME = "1970-01-01T00:00:00"
#: The date of every zip entry (the earliest a zip can hold).
FIXED_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
_STEP_STAMP = re.compile(rb"(FILE_NAME\('(?:[^']|'')*',\s*')[^']*(')")


_NAUO = re.compile(
    rb"(NEXT_ASSEMBLY_USAGE_OCCURRENCE\(')([^']*)(',')((?:[^']|'')*)(')((?:'(?:[^']|'')*'|[^';])*;)"
)
_LINE_BREAK = re.compile(rb"\s*\n\s*")
_REF = re.compile(rb"#(\d+)")


def _quote_split(body: bytes) -> list[bytes]:
    """``body`` split at its quotes: the even parts lie outside its quoted strings (a quote inside a
    string is doubled, which splits it into two strings with nothing between: the same result)."""
    return body.split(b"'")


def _outside_strings(body: bytes, change: Callable[[bytes], bytes]) -> bytes:
    """``body`` with ``change`` applied to the text outside its quoted strings."""
    parts = _quote_split(body)
    parts[::2] = [change(p) for p in parts[::2]]
    return b"'".join(parts)


def _references(body: bytes) -> list[int]:
    """The entity numbers ``body`` refers to (``#n`` outside its strings), in order."""
    return [int(r) for part in _quote_split(body)[::2] for r in _REF.findall(part)]


def _unwrapped(text: bytes) -> bytes:
    """``text`` (outside strings) without OCCT's line breaks: removed, or one space between two
    words."""

    def join(m: re.Match) -> bytes:
        a, b = text[m.start() - 1 : m.start()], text[m.end() : m.end() + 1]
        return b" " if a.isalnum() and b.isalnum() else b""

    return _LINE_BREAK.sub(join, text)


def _fixed_nauo_ids(data: bytes) -> bytes:
    """OCCT numbers assembly usages with a counter that runs on across a process's STEP writes;
    number them by their instance names' order instead (unique names: 1..n), so the id follows the
    file. Each usage is written on one line: OCCT breaks the line where the counter's digits pushed
    it past its width, which would otherwise depend on how many files the process wrote before."""
    names = [m.group(4) for m in _NAUO.finditer(data)]
    if len(set(names)) != len(names):
        return data
    order = {name: i + 1 for i, name in enumerate(sorted(names))}
    return _NAUO.sub(
        lambda m: (
            m.group(1)
            + str(order[m.group(4)]).encode()
            + m.group(3)
            + m.group(4)
            + m.group(5)
            + _outside_strings(m.group(6), _unwrapped)
        ),
        data,
    )


#: The first entity of the presentation section OCCT writes after the geometry: one per coloured
#: shape.
_PRESENTATION = b"MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION"
_ENTITY_START = re.compile(rb"^#(\d+)\s*=\s*", re.M)


def _canonical_presentation(data: bytes) -> bytes:
    """The STEP file with its presentation section (the colours: from the first
    ``MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION`` to the end of the data) in one order
    that follows the file's content, not the writer's memory.

    OCCT writes one presentation block per coloured shape in the order of an in-memory map, which
    changed from run to run (measured), and defines each colour in the first block that uses it.
    Here every entity of the section is named by a digest of its text, with its references into the
    section replaced by their digests (references to the geometry before it kept as numbers, which
    are reproducible); the blocks are then written in the order of their digests, each entity
    numbered, from the section's first number on, where a depth-first walk first reaches it, and on
    one line. The entities, their references and what they mean are unchanged. A file without such a
    section, one whose section has a cycle of references, or one whose entities before it refer into
    it (never seen: renumbering would break them), is returned as it is."""
    found = _presentation_section(data)
    if found is None:
        return data
    start, end, bodies = found
    inner = {n: [r for r in _references(body) if r in bodies] for n, body in bodies.items()}
    try:
        roots = _roots_by_digest(bodies, inner)
    except (ValueError, RecursionError):
        return data
    new = _depth_first_numbers(roots, inner, min(bodies))
    if len(new) != len(bodies):
        return data
    renumbered = {
        new[n]: _outside_strings(
            body,
            lambda t: _REF.sub(lambda m: b"#%d" % new.get(int(m.group(1)), int(m.group(1))), t),
        )
        for n, body in bodies.items()
    }
    out = b"".join(b"#%d = %s\n" % (n, renumbered[n]) for n in sorted(renumbered))
    return data[:start] + out + data[end + 1 :]


def _presentation_section(data: bytes) -> tuple[int, int, dict[int, bytes]] | None:
    """Where the presentation section of a STEP file begins and ends (the newline before
    ``ENDSEC;``) and its entities' bodies by number, each on one line; None where there is no such
    section or it cannot be renumbered: an entity without its end, numbers that do not run on from
    the first, or an entity before it that refers into it."""
    start = data.find(_PRESENTATION)
    if start < 0:
        return None
    start = data.rfind(b"\n", 0, start) + 1
    end = data.find(b"\nENDSEC;", start)
    if end < 0:
        return None
    section = data[start : end + 1]
    heads = list(_ENTITY_START.finditer(section))
    if not heads or heads[0].start() != 0:
        return None
    bodies: dict[int, bytes] = {}
    for head, nxt in zip(heads, heads[1:] + [None]):
        body = section[head.end() : nxt.start() if nxt else len(section)].rstrip()
        if not body.endswith(b";"):
            return None
        bodies[int(head.group(1))] = _outside_strings(body, _unwrapped)
    first = min(bodies)
    if first != int(heads[0].group(1)) or len(bodies) != len(heads):
        return None
    digits = len(str(first))
    if any(int(r) >= first for r in re.findall(rb"#(\d{%d,})" % digits, data[:start])):
        return None
    return start, end, bodies


def _roots_by_digest(bodies: dict[int, bytes], inner: dict[int, list[int]]) -> list[int]:
    """The section's roots (the entities no other of it refers to) in the order of their digests: a
    digest is of an entity's text with its references into the section (``inner``) replaced by
    theirs. Raises ValueError (or RecursionError) on a cycle of references."""
    import hashlib

    digests: dict[int, bytes] = {}
    walking: set[int] = set()

    def digest(number: int) -> bytes:
        if number not in digests:
            if number in walking:
                raise ValueError("a cycle of references")
            walking.add(number)
            text = _outside_strings(
                bodies[number],
                lambda t: _REF.sub(
                    lambda m: (
                        b"@" + digest(int(m.group(1))) if int(m.group(1)) in bodies else m.group(0)
                    ),
                    t,
                ),
            )
            walking.discard(number)
            digests[number] = hashlib.sha256(text).hexdigest().encode()
        return digests[number]

    referenced = {r for refs in inner.values() for r in refs}
    return sorted((n for n in bodies if n not in referenced), key=digest)


def _depth_first_numbers(
    roots: list[int], inner: dict[int, list[int]], first: int
) -> dict[int, int]:
    """Each entity's new number, from ``first`` on, in the order a depth-first walk from the
    ``roots`` (in their order) through the references ``inner`` first reaches it."""
    new: dict[int, int] = {}
    for root in roots:
        stack = [root]
        while stack:
            n = stack.pop()
            if n in new:
                continue
            new[n] = first + len(new)
            stack.extend(reversed(inner[n]))
    return new


def fix_step(path: Path) -> bool:
    data = path.read_bytes()
    fixed = _STEP_STAMP.sub(rb"\g<1>" + FIXED_STEP_TIME.encode() + rb"\g<2>", data, count=1)
    fixed = _fixed_nauo_ids(fixed)
    fixed = _canonical_presentation(fixed)
    if fixed != data:
        path.write_bytes(fixed)
        return True
    return False


_UUID = re.compile(rb'(p:UUID=")[0-9a-fA-F-]{36}(")')


def _fixed_uuids(name: str, data: bytes) -> bytes:
    count = iter(range(1 << 30))
    return _UUID.sub(
        lambda m: (
            m.group(1)
            + str(uuid.uuid5(uuid.NAMESPACE_URL, f"bvsr_cad/{name}/{next(count)}")).encode()
            + m.group(2)
        ),
        data,
    )


def _fixed_entries(
    name: str, zin: zipfile.ZipFile
) -> tuple[list[tuple[zipfile.ZipInfo, bytes]], bool]:
    """The zip's entries with fixed UUIDs, and whether they and the dates were fixed already."""
    entries, same = [], True
    for info in zin.infolist():
        data = zin.read(info.filename)
        fixed = (
            _fixed_uuids(f"{name}/{info.filename}", data)
            if info.filename.endswith(".model")
            else data
        )
        same = same and info.date_time == FIXED_ZIP_TIME and fixed == data
        entries.append((info, fixed))
    return entries, same


#: Deflate's level for the 3MF files: 1, the fastest. The print jobs' 3MFs are meshes as XML,
#: written on a cold build's critical path: zlib's default level (6) makes them somewhat smaller
#: for several times the CPU; the format is the same deflate stream, so every reader takes it.
ZIP_COMPRESSLEVEL = 1


def _write_zip(
    path: Path, entries: list[tuple[zipfile.ZipInfo, bytes]], compress_type: int | None = None
) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with zipfile.ZipFile(tmp, "w") as zout:
        for info, data in entries:
            fixed = zipfile.ZipInfo(info.filename, date_time=FIXED_ZIP_TIME)
            fixed.compress_type = info.compress_type if compress_type is None else compress_type
            fixed.external_attr = info.external_attr
            zout.writestr(
                fixed, data, compresslevel=ZIP_COMPRESSLEVEL
            )  # a ZipInfo ignores the file's level
    tmp.replace(path)


def write_reproducible_bytes(path: Path, data: bytes) -> None:
    """``data`` as the whole of ``path``, written beside it and renamed into place: a reader sees
    the old file or the new one, never a part. For writers whose bytes follow their input alone (no
    time stamp, no chance), such as the GLB scenes."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    tmp.replace(path)


def fix_zip(path: Path) -> bool:
    with zipfile.ZipFile(path) as zin:
        entries, same = _fixed_entries(path.name, zin)
    if same:
        return False
    _write_zip(path, entries)
    return True


def write_reproducible_3mf(scene, path: Path) -> None:
    """A trimesh scene as a 3MF file as :func:`fix_zip` leaves it (fixed dates and UUIDs, deflated),
    compressed once: trimesh writes it stored, not deflated, and only the fixed entries are
    compressed."""
    import io

    with zipfile.ZipFile(
        io.BytesIO(scene.export(file_type="3mf", compression=zipfile.ZIP_STORED))
    ) as zin:
        entries, _same = _fixed_entries(path.name, zin)
    _write_zip(path, entries, zipfile.ZIP_DEFLATED)


def make_reproducible(root: Path, done: set[Path] | None = None) -> dict[str, int]:
    """Fix the time stamps of every STEP and 3MF file under ``root``; returns how many of each
    changed.

    ``done``: the files fixed by an earlier call (skipped; the files fixed now are added), for a
    build that fixes its files in two goes."""
    done = set() if done is None else done
    steps = [
        p
        for p in sorted(root.rglob("*"))
        if p.suffix.lower() in (".step", ".stp") and p not in done
    ]
    zips = [p for p in sorted(root.rglob("*.3mf")) if p not in done]
    out = {"step": sum(fix_step(p) for p in steps), "3mf": sum(fix_zip(p) for p in zips)}
    done.update(steps + zips)
    return out


__all__ = [
    "make_reproducible",
    "fix_step",
    "fix_zip",
    "write_reproducible_3mf",
    "write_reproducible_bytes",
    "FIXED_STEP_TIME",
]

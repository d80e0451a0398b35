"""Property-based tests over the parameter space (validation once, at load).

The property: every parameter file either is refused when it is read (``ParamError``, every problem
naming a key) or loads and then builds with every generator, each solid valid with a positive volume
and every rigid-twin piece inside the printer. Samples start from ``params/bvsr.toml`` and change 1
to 4 keys, each drawn from the rule declared in the field metadata of
:mod:`bvsr_cad.parameters.tables`: across the rule's whole range, near the file's value, at and just
beyond the rule's ends, any of its choices and one outside them, any material key or one that does
not exist (``use.*``, ``vertebra.material``,
``fabrication_package.core_material``/``mold_material``), or a material dropped from
``[materials]``.

Full geometry is too slow for hundreds of samples, so:

* ``test_every_sample_loads_or_is_refused_naming_a_key``: 200 samples (derandomized, reproducible in
  CI) through load and the closed-form checks (the twin's piece envelopes fit the printer, every
  material resolves, the mold's derived walls are what the rules require);
* ``test_loaded_samples_build_with_every_generator``: a bounded subset, 25 samples drawn the same
  way but only over the keys that shape geometry, near the file's values and among the valid choices
  (so most of them load), built in memory with every generator on one segment;
* ``test_cli_builds_drawn_samples`` (slow): the real ``bvsr build`` on 2 drawn samples that load
  (one segment, the smallest analyses): exit 0 (or exit 2 at load), never exit 1 or a traceback.

Outside CI, every geometry key was also driven to the extreme value that still loads (bisection on
load, 120 samples) and built with every generator: all built once the taper rule of
:func:`bvsr_cad.parameters.panel_rules.validate_layout` refused cones under 0.05 deg.

Run it with ``-s`` to see how many samples loaded and which rules refused the others.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import re
import subprocess
import sys
import tomllib
import typing
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, given, settings
from hypothesis import strategies as st

from bvsr_cad.parameters.load import ParamError, spec_from_dict
from bvsr_cad.parameters.molds import mold_dimensions
from bvsr_cad.parameters.tables import AUTO, TailSpec
from bvsr_cad.parameters.twin import fits_printer, piece_envelopes

from .conftest import PARAMS, write_toml

BASE = tomllib.loads((PARAMS / "bvsr.toml").read_text())
MATERIALS = sorted(BASE["materials"])
SETTINGS = dict(
    deadline=None,
    derandomize=True,
    database=None,
    print_blob=True,
    suppress_health_check=[
        HealthCheck.too_slow,
        HealthCheck.data_too_large,
        HealthCheck.filter_too_much,
    ],
)
#: Building geometry takes seconds: a failing sample is reported as drawn, not shrunk (minutes).
NO_SHRINK = dict(phases=(Phase.explicit, Phase.reuse, Phase.generate))


@dataclasses.dataclass(frozen=True)
class Key:
    """One key of a parameter file and its declared rule."""

    path: tuple[str, ...]
    typ: Any
    meta: tuple[tuple[str, Any], ...]

    @property
    def name(self) -> str:
        return ".".join(self.path)

    @property
    def rule(self) -> dict[str, Any]:
        return dict(self.meta)

    @property
    def current(self) -> Any:
        """The value in params/bvsr.toml (or the field's default when the file leaves it out)."""
        table = BASE
        for p in self.path[:-1]:
            table = table.get(p, {})
        if self.path[-1] in table:
            return table[self.path[-1]]
        cls = typing.get_type_hints(TailSpec)[self.path[0]]
        return {f.name: f.default for f in dataclasses.fields(cls)}[self.path[-1]]


def _keys() -> list[Key]:
    out = []
    hints = typing.get_type_hints(TailSpec)
    for f in dataclasses.fields(TailSpec):
        typ = hints[f.name]
        if f.name in (
            "name",
            "materials",
            "calibration",
        ):  # calibration: written by `bvsr calibrate`, tested there
            continue
        if dataclasses.is_dataclass(typ):
            sub = typing.get_type_hints(typ)
            out += [
                Key((f.name, g.name), sub[g.name], tuple(g.metadata.items()))
                for g in dataclasses.fields(typ)
            ]
        else:
            out.append(Key((f.name,), typ, tuple(f.metadata.items())))
    return out


KEYS = _keys()
#: Every key a message may name: "section.field", a top-level field, or a material of the table.
KNOWN = {k.name for k in KEYS} | {f"materials.{m}" for m in MATERIALS} | {"materials.PLA"}
TOP_LEVEL = {k.name for k in KEYS if len(k.path) == 1} | {"name"}
#: Keys that shape geometry (the others set analyses, BOM items and checks).
GEOMETRY_SECTIONS = {
    "joint",
    "soa",
    "vertebra",
    "taper",
    "fabrication",
    "tubes",
    "socket",
    "mount",
    "payload",
    "lightening",
    "casting",
    "segments",
    "joints_per_segment",
    "use",
}
GEOMETRY_FP = re.compile(r"printer_|pin_|tie_rod_|fdm_min_|core_material|mold_material")
GEOMETRY_KEYS = [
    k
    for k in KEYS
    if k.path[0] in GEOMETRY_SECTIONS
    or (k.path[0] == "fabrication_package" and GEOMETRY_FP.match(k.path[1]))
]
DROP = Key(("materials", "<drop>"), str, ())  # pseudo-key: remove a material from [materials]


def _bounds(rule: dict[str, Any]) -> tuple[float, float]:
    lo = rule["ge"] if rule.get("ge") is not None else rule["gt"]
    hi = rule["le"] if rule.get("le") is not None else rule["lt"]
    return float(lo), float(hi)


def _round(x: float) -> float:
    return float(round(x, 3))


def values(key: Key, near_only: bool = False) -> st.SearchStrategy:
    """Values for ``key`` drawn from its declared rule (``near_only``: valid choices and values near
    the file's)."""
    if key is DROP:
        return st.sampled_from(MATERIALS)
    rule, cur = key.rule, key.current
    if rule.get("choices"):
        valid = st.sampled_from(rule["choices"])
        if near_only:
            return valid
        wrong = (
            st.just("bogus")
            if isinstance(rule["choices"][0], str)
            else st.just(max(rule["choices"]) + 1.0)
        )
        return st.one_of(valid, wrong)
    if key.typ is str:  # a material key
        return (
            st.sampled_from(MATERIALS)
            if near_only
            else st.sampled_from(MATERIALS + ["unobtainium"])
        )
    if key.typ is Any:  # taper: a number or "auto"
        return (
            st.one_of(st.just(AUTO), st.floats(0.0, 0.35).map(_round))
            if near_only
            else st.one_of(
                st.just(AUTO), st.floats(0.0, 0.6).map(_round), st.floats(0.0, 10.0).map(_round)
            )
        )
    lo, hi = _bounds(rule)
    if key.typ is int:
        near = st.integers(max(int(lo), cur - 1), min(int(hi), cur + 1))
        if near_only:
            return near
        return st.one_of(
            near, st.integers(int(lo), int(hi)), st.sampled_from([int(lo) - 1, int(hi) + 1])
        )
    if cur:
        near = st.floats(0.85, 1.2).map(lambda f: _round(min(max(cur * f, lo), hi)))
    else:
        near = st.floats(lo, lo + 0.1 * (hi - lo)).map(_round)
    if near_only:
        return near
    across = st.floats(lo, hi, allow_nan=False, allow_subnormal=False).map(_round)
    span = hi - lo
    edges = st.sampled_from([lo, hi, _round(lo - 0.01 * span), _round(hi + 0.01 * span)])
    return st.one_of(near, across, edges)


@st.composite
def samples(draw, keys: list[Key] = KEYS, near_only: bool = False) -> dict[str, Any]:
    """{key name: value} for 1 to 4 distinct keys (plus, sometimes, a material dropped)."""
    pool = keys if near_only else keys + [DROP]
    chosen = draw(
        st.lists(st.sampled_from(pool), min_size=1, max_size=4, unique_by=lambda k: k.path)
    )
    return {k.name: draw(values(k, near_only)) for k in chosen}


def apply(changes: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(BASE)
    for name, value in changes.items():
        if name == DROP.name:
            data["materials"].pop(value)
            continue
        *tables, leaf = name.split(".")
        table = data
        for t in tables:
            table = table.setdefault(t, {})
        table[leaf] = value
    return data


STATS: dict[str, Counter] = {
    "load": Counter(),
    "refused_by": Counter(),
    "build": Counter(),
    "cli": Counter(),
}


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    load, build = STATS["load"], STATS["build"]
    print(
        f"\nparameter samples: {load['loaded']} loaded, {load['refused']} refused at load; "
        f"geometry built for {build['built']} (refused {build['refused']}); bvsr build: "
        f"{dict(STATS['cli'])}"
    )
    kinds = Counter()
    for rule, n in STATS["refused_by"].items():
        kinds[rule.split(": ")[0]] += n
    print(
        "refused at load, by the kind of rule of the first problem: "
        + "; ".join(f"{k} {n}" for k, n in kinds.most_common())
    )
    for rule, n in STATS["refused_by"].most_common():
        print(f"  refused {n:3d} x  {rule}")


#: What kind of rule a problem comes from, by its wording (for the statistics).
RULE_KINDS = (
    ("out of range", "declared range"),
    ("not allowed; allowed", "declared choices"),
    ("expected ", "declared type"),
    ("not a material", "material key"),
    ("materials.", "material key"),
    ("mold set:", "mold set (parameters/molds.py)"),
    ("rigid twin", "rigid twin (parameters/twin.py)"),
    ("taper.half_angle_deg", "taper"),
)


def _rule_of(problem: str) -> str:
    """'kind: key' of the rule a problem comes from, for the statistics."""
    kind = next((k for text, k in RULE_KINDS if text in problem), None)
    m = re.match(r"([A-Za-z_]+(?:\.[A-Za-z0-9_]+)?)(?: = |: )", problem)
    if m and not m.group(1).startswith("panel"):
        return f"{kind or 'derived geometry (parameters/layout.py)'}: {m.group(1)}"
    named = re.findall(r"fabrication\.[a-z_]+_mm", problem)
    return f"panel webs (parameters/layout.py): {', '.join(sorted(set(named))) or problem[:40]}"


def load_or_refuse(changes: dict[str, Any], count: bool = False) -> TailSpec | None:
    """Load the sample; a refusal must name a key in every problem. None when refused (``count``:
    tally the rule that refused it)."""
    try:
        spec = spec_from_dict(apply(changes), "sample.toml")
    except ParamError as err:
        assert err.problems and str(err).startswith("sample.toml: ")
        for problem in err.problems:
            named = any(k in problem for k in KNOWN) or re.match(
                rf"({'|'.join(TOP_LEVEL)}) = ", problem
            )
            assert named, f"{changes}: a problem names no key: {problem}"
        if count:
            STATS["refused_by"][_rule_of(err.problems[0])] += 1
        return None
    return spec


def cheap_checks(spec: TailSpec) -> None:
    """What a loaded spec promises without building: materials resolve, the twin fits, the mold's
    walls hold."""
    fp = spec.fabrication_package
    for key in (
        spec.use.panel,
        spec.use.soa,
        spec.vertebra.material,
        fp.core_material,
        fp.mold_material,
        "PLA",
    ):
        assert spec.material(key).density_g_cm3 > 0
    for env in piece_envelopes(spec):
        assert fits_printer(env.size_mm, fp), env
    d = mold_dimensions(spec.soa, spec.joint.base_diameter_mm, spec.casting)
    assert d.pin_socket_web_mm >= spec.casting.min_print_wall_mm
    assert d.plate_mm - spec.casting.core_print_mm >= spec.casting.min_print_wall_mm
    assert d.halves_height_mm > 0 and d.block_half_mm > d.cavity_radius_mm


@settings(max_examples=200, **SETTINGS)
@given(samples())
def test_every_sample_loads_or_is_refused_naming_a_key(changes):
    spec = load_or_refuse(changes, count=True)
    STATS["load"]["refused" if spec is None else "loaded"] += 1
    if spec is not None:
        cheap_checks(spec)


# --- Geometry for a bounded subset.


@functools.lru_cache(maxsize=8)
def _molds(soa, flange_diameter_mm, casting):
    from bvsr_cad.parts.mold import mold_set

    return mold_set(soa, flange_diameter_mm, casting)


def _sound(solid, what: str) -> None:
    assert solid.is_valid, f"{what}: invalid solid"
    assert solid.volume > 0, f"{what}: volume {solid.volume}"


def build_everything(spec: TailSpec) -> None:
    """Every generator, in memory, as the build calls them."""
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.parts.rigid_tail import rigid_tail_pieces

    asm = build_assembly(spec)
    for name, part in asm.parts.items():
        _sound(part.solid, name)
    molds = _molds(spec.soa, spec.joint.base_diameter_mm, spec.casting)
    _sound(molds.cast, "mold cast")
    for name, part in molds.parts.items():
        _sound(part.solid, f"mold {name}")
    for ch in molds.channels:
        _sound(ch.solid, f"mold channel {ch.name}")
    # The mold block is the one the rules judged.
    d = mold_dimensions(spec.soa, spec.joint.base_diameter_mm, spec.casting)
    assert molds.info["block_mm"] == pytest.approx(
        [2 * d.block_half_mm, 2 * d.block_half_mm, d.z_top_mm - d.z_bottom_mm]
    )
    transforms = {
        k: [np.asarray(i.transform) for i in asm.instances if i.name.startswith(f"j{k}_soa")]
        for k in range(1, spec.panels)
    }
    pieces = rigid_tail_pieces(spec, asm.panel_layouts, transforms)
    envelopes = piece_envelopes(spec, asm.panel_layouts)
    assert len(pieces) == len(envelopes) == spec.panels
    for piece, env in zip(pieces, envelopes):
        _sound(piece.solid, piece.name)
        assert fits_printer(piece.size_mm, spec.fabrication_package), (piece.name, piece.size_mm)
        # The closed-form envelope the load-time rule judges bounds the built piece.
        assert all(s <= e + 1e-6 for s, e in zip(piece.size_mm, env.size_mm)), (
            piece.name,
            piece.size_mm,
            env,
        )


#: The base of the built samples: the default file on one segment. Every generator, every part kind
#: and every rule is the same as on two; a sample builds in about half the time.
ONE_SEGMENT = {"segments": 1}
#: The command line's samples: one segment and the schema's smallest analyses (those keys shape no
#: geometry and are never drawn here).
SMALL_BUILD = {
    **ONE_SEGMENT,
    "analysis.workspace_protocol_cycles": 10,
    "analysis.build_workspace_samples": 100,
    "analysis.build_clearance_poses": 100,
}


@settings(max_examples=25, **SETTINGS, **NO_SHRINK)
@given(samples(GEOMETRY_KEYS, near_only=True))
def test_loaded_samples_build_with_every_generator(changes):
    """Built on one segment unless the sample draws the count (:data:`ONE_SEGMENT`)."""
    spec = load_or_refuse({**ONE_SEGMENT, **changes})
    if spec is None:
        STATS["build"]["refused"] += 1
        return
    cheap_checks(spec)
    build_everything(spec)
    STATS["build"]["built"] += 1


@pytest.mark.slow
@settings(max_examples=2, **SETTINGS, **NO_SHRINK)
@given(
    samples(
        [k for k in GEOMETRY_KEYS if k.path[0] != "segments" and k.path[0] != "joints_per_segment"],
        near_only=True,
    )
)
def test_cli_builds_drawn_samples(tmp_path_factory, changes):
    """The real command line on drawn samples: exit 0, or exit 2 at load; never exit 1 or a
    traceback. The tail is named other than the default, whose name no file may assume (its robot
    files are ``robot/<name>.xml``)."""
    changes = {**SMALL_BUILD, **changes}
    assume(load_or_refuse(changes) is not None)  # feasible samples: the refusals are tested above
    tmp = tmp_path_factory.mktemp("cli")
    path = write_toml(tmp / "sample.toml", {**apply(changes), "name": "drawn_sample"})
    bvsr = Path(sys.executable).with_name("bvsr")
    cmd = [str(bvsr)] if bvsr.exists() else [sys.executable, "-m", "bvsr_cad.cli"]
    res = subprocess.run(
        [*cmd, "build", str(path), "-o", str(tmp / "out"), "-q"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    STATS["cli"][f"exit {res.returncode}"] += 1
    assert "Traceback" not in res.stderr, res.stderr
    assert res.returncode in (0, 2), (changes, res.returncode, res.stdout, res.stderr)
    if res.returncode == 2:
        assert "problem(s) in the parameters" in res.stderr, (
            res.stderr
        )  # refused at load, naming the key
    else:
        manifest = json.loads((tmp / "out" / "manifest.json").read_text())
        assert manifest["robot"]["mjcf_model"] == "robot/drawn_sample.xml"
        assert (tmp / "out" / manifest["robot"]["mjcf_model"]).is_file()
        quadruped = manifest["quadruped"]
        if quadruped["installed"]:  # the tail mounted on the default host, by its own name
            assert (tmp / "out" / quadruped["scene"]).is_file()

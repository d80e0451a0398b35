"""TOML parameter file -> validated :class:`TailSpec`.

Every problem is collected before reporting, and each names the file, the
key, the value and what is allowed. Geometric feasibility is checked
afterwards, on the same derived numbers the generators build from: the
panels (pockets that overlap, a taper beyond the feasible one, ...) by
:func:`bvsr_cad.parameters.panel_rules.validate_layout`, the casting mold set by
:func:`bvsr_cad.parameters.molds.mold_problems` and the rigid twin (its
pins, tie rod and the printer it must fit) by
:func:`bvsr_cad.parameters.twin.twin_problems`, and what the analyses are asked for (a clearance the
straight tail already breaks, a workspace protocol that draws no pressure) by
:mod:`bvsr_cad.parameters.feasibility`. A file that loads builds.
"""

from __future__ import annotations

import dataclasses
import hashlib
import re
import tomllib
import typing
from pathlib import Path
from typing import Any

from ..errors import BadInput
from .tables import _SCHEMA, AUTO, NO_ROD, Material, TailSpec
from .twin import RIGID_TWIN_MATERIAL

#: The rigid comparison tail (parts/rigid_tail.py, the fabrication package) is printed in this
#: material.


class InputFileError(ValueError, BadInput):
    """A user's input file with ``problems``, each naming the key, its value and what is allowed."""

    what = "the file"

    def __init__(self, path: str | Path, problems: list[str]):
        self.path = str(path)
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{self.path}: {len(self.problems)} problem(s) in {self.what}:\n{lines}")

    def __reduce__(self):  # pickles (a second process hands it back to the build)
        return (type(self), (self.path, self.problems))


class ParamError(InputFileError):
    """A parameter file that cannot describe a buildable tail."""

    what = "the parameters"


def _allowed(meta: dict[str, Any]) -> str:
    if meta.get("choices"):
        return "one of " + ", ".join(repr(c) for c in meta["choices"])
    bounds = []
    for key, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
        if meta.get(key) is not None:
            bound = meta[key]  # whole numbers in full (a seed's 2147483647, not 2.14748e+09)
            bounds.append(
                f"{sym} {int(bound) if float(bound).is_integer() else format(bound, 'g')}"
            )
    return " and ".join(bounds) if bounds else "any value"


def _check_value(key: str, value: Any, typ: Any, meta: dict[str, Any], problems: list[str]) -> Any:
    """Type- and range-check one scalar; returns the converted value or None."""
    auto = ""
    if typ is Any:  # float or "auto"
        if value == AUTO:
            return AUTO
        typ, auto = float, f" or {AUTO!r}"
    if typ is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            problems.append(f"{key} = {value!r}: expected a number ({_allowed(meta)}){auto}")
            return None
        value = float(value)
    elif typ is int:
        if isinstance(value, bool) or not isinstance(value, int):
            problems.append(f"{key} = {value!r}: expected an integer ({_allowed(meta)})")
            return None
    elif typ is str:
        if not isinstance(value, str):
            problems.append(f"{key} = {value!r}: expected a string")
            return None
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        problems.append(f"{key} = {value!r}: not allowed; allowed: {_allowed(meta)}")
        return None
    if isinstance(value, (int, float)):
        ok = True
        ok &= meta.get("gt") is None or value > meta["gt"]
        ok &= meta.get("ge") is None or value >= meta["ge"]
        ok &= meta.get("lt") is None or value < meta["lt"]
        ok &= meta.get("le") is None or value <= meta["le"]
        if not ok:
            problems.append(f"{key} = {value!r}: out of range; allowed: {_allowed(meta)}")
            return None
    return value


def _build(cls: type, data: Any, prefix: str, problems: list[str]) -> Any:
    if not isinstance(data, dict):
        problems.append(f"{prefix or 'file'} = {data!r}: expected a table [{prefix}]")
        return None
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            where = f"{prefix}.{key}" if prefix else key
            problems.append(
                f"{where}: unknown key; allowed keys in [{prefix or 'top level'}]: "
                f"{', '.join(fields)}"
            )
    values: dict[str, Any] = {}
    for name, f in fields.items():
        key = f"{prefix}.{name}" if prefix else name
        typ = hints[name]
        if name not in data:
            if f.default is not dataclasses.MISSING:
                values[name] = f.default
            elif f.default_factory is not dataclasses.MISSING:
                values[name] = f.default_factory()
            else:
                problems.append(f"{key}: missing ({f.metadata.get('doc', '')})")
                values[name] = None
            continue
        raw = data[name]
        if dataclasses.is_dataclass(typ):
            values[name] = _build(typ, raw, key, problems)
        elif f.metadata.get("keys"):  # a table of named numbers, each with its own rule
            values[name] = _named_values(key, raw, _SCHEMA[f.metadata["keys"]], problems)
        elif typing.get_origin(typ) is dict:
            if not isinstance(raw, dict) or not raw:
                problems.append(f"{key}: expected a non-empty table of [{key}.<name>] entries")
                values[name] = None
                continue
            values[name] = {k: _build(Material, v, f"{key}.{k}", problems) for k, v in raw.items()}
        else:
            values[name] = _check_value(key, raw, typ, dict(f.metadata), problems)
    if any(v is None for v in values.values()):
        return None
    return cls(**values)


def _named_values(key: str, raw: Any, rules: dict[str, dict[str, Any]], problems: list[str]) -> Any:
    """A table of numbers whose names and rules come from ``rules`` (e.g. [calibration.fitted])."""
    if not isinstance(raw, dict):
        problems.append(f"{key} = {raw!r}: expected a table [{key}]")
        return None
    out = {}
    for name, value in raw.items():
        if name not in rules:
            problems.append(f"{key}.{name}: unknown name; allowed: {', '.join(rules)}")
            continue
        meta = {k: rules[name].get(k) for k in ("gt", "ge", "lt", "le")}
        checked = _check_value(f"{key}.{name}", value, float, meta, problems)
        if checked is not None:
            out[name] = checked
    return out if len(out) == len(raw) else None


def spec_from_dict(data: dict[str, Any], source: str | Path = "<dict>") -> TailSpec:
    """Validate a parsed parameter mapping and return the frozen spec.

    Raises:
        ParamError: naming every bad key, its value and what is allowed.
    """
    from .feasibility import clearance_problems
    from .molds import mold_problems
    from .panel_rules import soa_is_sound, validate_layout  # reads the layout and tables only
    from .twin import twin_problems

    problems: list[str] = []
    spec = _build(TailSpec, data, "", problems)
    if spec is not None:
        if not re.fullmatch(r"[A-Za-z0-9_-]+", spec.name):
            problems.append(f"name = {spec.name!r}: only letters, digits, '_' and '-' are allowed")
        problems += material_problems(spec) + actuation_problems(spec)
    if problems:
        raise ParamError(source, problems)
    # Geometry: the panels, then what the generators build on them (one set of derived numbers each,
    # shared with the generators: parameters/layout.py, parameters/molds.py, parameters/twin.py).
    problems = validate_layout(spec)
    problems += (
        mold_problems(spec.soa, spec.joint.base_diameter_mm, spec.casting)
        if soa_is_sound(spec)
        else []
    )
    if not problems:
        # What the analyses are asked for, against what the layout gives them
        # (parameters/feasibility.py).
        problems = twin_problems(spec) + clearance_problems(spec)
    if problems:
        raise ParamError(source, problems)
    return spec


def material_problems(spec: TailSpec) -> list[str]:
    """Every material key named anywhere in the spec (and the rigid twin's fixed one) must be in
    [materials]."""
    out = []
    allowed = ", ".join(spec.materials)
    for key, value in (
        ("use.panel", spec.use.panel),
        ("use.soa", spec.use.soa),
        ("vertebra.material", spec.vertebra.material),
        ("fabrication_package.core_material", spec.fabrication_package.core_material),
        ("fabrication_package.mold_material", spec.fabrication_package.mold_material),
    ):
        if key == "vertebra.material" and value == NO_ROD:
            continue
        if value not in spec.materials:
            extra = f" (or {NO_ROD!r}: no rod)" if key == "vertebra.material" else ""
            out.append(
                f"{key} = {value!r}: not a material in [materials]; allowed: {allowed}{extra}"
            )
    rod = spec.calibration.rod_material
    if rod and rod not in spec.materials:
        out.append(
            f"calibration.rod_material = {rod!r}: not a material in [materials]; allowed: {allowed}"
        )
    if RIGID_TWIN_MATERIAL not in spec.materials:
        out.append(
            f"materials.{RIGID_TWIN_MATERIAL}: missing; the rigid comparison tail is printed in "
            f"{RIGID_TWIN_MATERIAL!r} and its mass needs [materials.{RIGID_TWIN_MATERIAL}] (the "
            "file names: "
            f"{allowed})"
        )
    return out


def actuation_problems(spec: TailSpec) -> list[str]:
    """The workspace protocol draws a pressurised line from atmospheric up to its maximum and a
    depressurised one from its minimum up to atmospheric: each range must run upwards, and one must
    be wider than a point (else the workspace is empty)."""
    a = spec.actuation
    out = []
    if a.workspace_pressurised_max_kpa_abs < a.atmospheric_kpa:
        out.append(
            "actuation.workspace_pressurised_max_kpa_abs = "
            f"{a.workspace_pressurised_max_kpa_abs!r}: below "
            f"actuation.atmospheric_kpa = {a.atmospheric_kpa!r} (a pressurised line draws from "
            "atmospheric "
            f"up to it); allowed: >= {a.atmospheric_kpa:g} kPa (absolute)"
        )
    if a.workspace_depressurised_min_kpa_abs > a.atmospheric_kpa:
        out.append(
            "actuation.workspace_depressurised_min_kpa_abs = "
            f"{a.workspace_depressurised_min_kpa_abs!r}: above "
            f"actuation.atmospheric_kpa = {a.atmospheric_kpa!r} (a depressurised line draws from "
            "it up to "
            f"atmospheric); allowed: 0 to {a.atmospheric_kpa:g} kPa (absolute)"
        )
    if (
        a.workspace_pressurised_max_kpa_abs
        == a.atmospheric_kpa
        == a.workspace_depressurised_min_kpa_abs
    ):
        out.append(
            "actuation.workspace_pressurised_max_kpa_abs = "
            f"{a.workspace_pressurised_max_kpa_abs!r} and "
            "actuation.workspace_depressurised_min_kpa_abs = "
            f"{a.workspace_depressurised_min_kpa_abs!r}: both "
            f"at actuation.atmospheric_kpa = {a.atmospheric_kpa!r}, so the workspace protocol "
            "draws no pressure "
            "and its workspace is the straight tail's tip alone; allowed: a pressurised maximum "
            "above it or a "
            "depressurised minimum below it"
        )
    return out + _soa_stiffness_problems(a)


def _soa_stiffness_problems(a) -> list[str]:
    """The SOA's axial stiffness k = m_a P + n_a (Eq 4) must stay positive at the lowest gauge
    pressure a model draws (the vacuum limit, or the workspace protocol's depressurised minimum):
    with k <= 0 an SOA pushes harder the more it is stretched, and the statics have no equilibrium
    to converge to."""
    p_kpa = min(a.pressure_min_kpa, a.workspace_depressurised_min_kpa_abs - a.atmospheric_kpa)
    k_n_per_m = a.stiffness_slope_n_per_m_per_kpa * p_kpa + a.stiffness_offset_n_per_m
    if k_n_per_m > 0:
        return []
    bound = (
        f"actuation.stiffness_slope_n_per_m_per_kpa < {a.stiffness_offset_n_per_m / -p_kpa:.4g}"
        if p_kpa < 0
        else f"actuation.stiffness_offset_n_per_m > {-k_n_per_m + a.stiffness_offset_n_per_m:.4g}"
    )
    return [
        f"actuation.stiffness_slope_n_per_m_per_kpa = {a.stiffness_slope_n_per_m_per_kpa!r} with "
        f"actuation.stiffness_offset_n_per_m = {a.stiffness_offset_n_per_m!r}: the SOA's stiffness "
        f"m_a P + n_a is {k_n_per_m:.4g} N/m at {p_kpa:g} kPa (gauge; the lowest pressure drawn), "
        f"and an SOA that pushes harder the more it stretches has no equilibrium; allowed: {bound}"
    ]


def read_input_text(path: Path, error: type) -> str:
    """A user's input file as text; ``error(path, [problem])`` when it is missing or unreadable."""
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(path, ["file not found"]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(path, [f"cannot read the file: {exc}"]) from None


def load_spec(path: str | Path) -> TailSpec:
    """Read and validate a TOML parameter file.

    Raises:
        ParamError: the file is missing, is not valid TOML, or describes an
            impossible tail.
    """
    path = Path(path)
    return spec_from_dict(read_toml(path, ParamError), path)


def read_toml(path: Path, error: type) -> dict[str, Any]:
    """A user's TOML file as a mapping; ``error(path, [problem])`` when it is unreadable or not
    TOML."""
    try:
        return tomllib.loads(read_input_text(path, error))
    except tomllib.TOMLDecodeError as exc:
        raise error(path, [f"not valid TOML: {exc}"]) from None


def params_sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


__all__ = ["ParamError", "load_spec", "spec_from_dict", "params_sha256"]

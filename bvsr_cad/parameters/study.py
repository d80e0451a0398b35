"""Study files for `bvsr sweep`: a base parameter file, the axes to vary, the metrics to record.

A study is TOML::

    name = "vertebra"                  # results go to exports/studies/<name>/ by default
    base = "../params/bvsr.toml"       # relative to the study file
    metrics = ["mass", "statics"]      # metric groups or single metrics (bvsr_cad.analysis.metrics)
    checks = false                     # true: every variant is exported and checked (slow, minutes)
    time_limit_s = 600                 # a variant running longer is recorded as "timeout"
    baseline = true                    # also run the base file itself (label "base")

    [conditions]                       # where the dynamic metrics are taken
    pressure_bar = 6.0
    motion = "extension"
    payload_g = 0.0

    [set]                              # fixed on every variant
    "fabrication_package.tie_rod_thread" = 2.0

    [grid]                             # every combination (a full factorial) ...
    "vertebra.material" = ["rubber", "TPU", "nylon", "PVC"]

    [[variants]]                       # ... and/or listed variants
    label = "no vertebra"
    "vertebra.material" = "none"

    [random]                           # or: random samples
    samples = 20
    seed = 1
    [random.space]
    "lightening.hole_diameter_mm" = { low = 0.0, high = 8.0 }
    "vertebra.material" = ["nylon", "PVC"]

    [optuna]                           # or: an Optuna search
    trials = 24
    seed = 1
    objectives = [{ metric = "root_torque_per_mass_nm_per_kg", direction = "maximize" }]
    constraints = [{ metric = "checks_failed", max = 0 }]
    [optuna.space]
    "vertebra.diameter_mm" = [4.0, 5.0, 6.0]   # a list: categorical; a table: low/high (step, log)

A key is a dotted path of the parameter file (``table.key``;
``materials.nylon.youngs_modulus_mpa``). Every problem is found when the study is loaded
(:class:`StudyError` lists them all, naming the key, its value and what is allowed); a variant whose
values make an impossible tail is not a problem of the study: it becomes a result row with the
loader's reason.
"""

from __future__ import annotations

import collections.abc
import copy
import dataclasses
import difflib
import hashlib
import itertools
import json
import math
import os
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .load import InputFileError, read_toml
from .tables import TailSpec

DIRECTIONS = ("maximize", "minimize")
TOP_KEYS = {
    "name",
    "base",
    "metrics",
    "checks",
    "time_limit_s",
    "baseline",
    "conditions",
    "set",
    "grid",
    "variants",
    "random",
    "optuna",
    "expect",
}


class StudyError(InputFileError):
    """A study file that cannot run; ``problems`` name each key, its value and what is allowed."""

    what = "the study"


@dataclass(frozen=True)
class Dimension:
    """One axis of a random or Optuna search: ``choices`` (categorical) or ``low``..``high``."""

    key: str
    choices: tuple | None = None
    low: float | None = None
    high: float | None = None
    step: float | None = None
    log: bool = False

    def sample(self, rng: np.random.Generator) -> Any:
        if self.choices is not None:
            return self.choices[int(rng.integers(len(self.choices)))]
        if self.log:
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        value = float(rng.uniform(self.low, self.high))
        if self.step:  # on the grid low + k step, and never above high
            value = self.low + math.floor((value - self.low) / self.step + 0.5) * self.step
            value = value - self.step if value > self.high else value
        return value


@dataclass(frozen=True)
class Variant:
    """One tail of a study: the overrides on the base and the full parameter mapping they give."""

    label: str
    overrides: dict[str, Any]
    data: dict[str, Any] = field(repr=False)

    @property
    def key(self) -> str:
        """Hash of the variant's parameters (the whole mapping, so an edited base is a new
        variant)."""
        text = json.dumps(self.data, sort_keys=True, separators=(",", ":"), default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Objective:
    metric: str
    direction: str


@dataclass(frozen=True)
class Constraint:
    """``metric`` must be >= ``min`` and/or <= ``max`` for a variant to count as feasible."""

    metric: str
    min: float | None = None
    max: float | None = None

    def violation(self, value: float | None) -> float:
        """<= 0 when satisfied (Optuna's convention); a missing value violates by 1."""
        if value is None or (isinstance(value, float) and math.isnan(value)):
            return 1.0
        v = float(value)
        return max(
            (self.min - v) if self.min is not None else -math.inf,
            (v - self.max) if self.max is not None else -math.inf,
        )


@dataclass(frozen=True)
class Expectation:
    """A trend a source reports, checked on the results: ``metric`` rises (or falls) with ``versus``
    (another metric or an axis), as the sign of their rank correlation over the variants."""

    metric: str
    versus: str
    sign: int  # +1 rises, -1 falls
    source: str


@dataclass(frozen=True)
class Study:
    path: Path
    name: str
    base_path: Path
    base_data: dict[str, Any] = field(repr=False)
    kind: str
    metrics: tuple[str, ...]
    checks: bool
    time_limit_s: float
    baseline: bool
    conditions: dict[str, Any]
    fixed: dict[str, Any]
    grid: dict[str, list]
    listed: tuple[dict[str, Any], ...]
    space: tuple[Dimension, ...]
    samples: int
    seed: int
    trials: int
    objectives: tuple[Objective, ...]
    constraints: tuple[Constraint, ...]
    expect: tuple[Expectation, ...] = ()
    sampler: str = "tpe"

    @property
    def axes(self) -> list[str]:
        """Every key a variant may change (grid, listed variants, or the search space)."""
        keys = list(self.grid) + [d.key for d in self.space]
        for v in self.listed:
            keys += [k for k in v if k != "label"]
        return list(dict.fromkeys(keys))

    def variant(self, overrides: dict[str, Any], label: str | None = None) -> Variant:
        data = copy.deepcopy(self.base_data)
        for key, value in {**self.fixed, **overrides}.items():
            set_path(data, key, value)
        text = label or (", ".join(f"{k}={_short(v)}" for k, v in overrides.items()) or "base")
        return Variant(text, dict(overrides), data)

    def variants(self) -> list[Variant]:
        """The grid, the listed variants and the random samples (an Optuna study asks as it
        goes)."""
        out = [self.variant({}, "base")] if self.baseline else []
        if self.grid:
            keys = list(self.grid)
            for combo in itertools.product(*(self.grid[k] for k in keys)):
                out.append(self.variant(dict(zip(keys, combo))))
        for v in self.listed:
            over = {k: x for k, x in v.items() if k != "label"}
            out.append(self.variant(over, v.get("label")))
        if self.kind == "random":
            rng = np.random.default_rng(self.seed)
            for _ in range(self.samples):
                out.append(self.variant({d.key: d.sample(rng) for d in self.space}))
        unique: dict[str, Variant] = {}
        for v in out:
            unique.setdefault(v.key, v)
        return list(unique.values())


def _short(v: Any) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def get_path(data: dict[str, Any], key: str, default: Any = None) -> Any:
    """The value at a dotted key, or ``default`` where the file leaves the key to the schema's
    default."""
    node: Any = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return default
        node = node[part]
    return node


def set_path(data: dict[str, Any], key: str, value: Any) -> None:
    parts = key.split(".")
    node = data
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value


def known_keys(data: dict[str, Any]) -> list[str]:
    """Every dotted key a study may set: the base file's, and every schema field with a default."""
    keys: list[str] = []

    def walk(node: Any, prefix: str) -> None:
        if isinstance(node, dict):
            for k, v in node.items():
                walk(v, f"{prefix}.{k}" if prefix else k)
        else:
            keys.append(prefix)

    walk(data, "")

    def fields(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            key = f"{prefix}.{f.name}" if prefix else f.name
            hint = hints[f.name]
            if dataclasses.is_dataclass(hint):
                fields(hint, key)
            elif typing.get_origin(hint) not in (dict, Mapping, collections.abc.Mapping):
                keys.append(key)

    fields(TailSpec, "")
    return sorted(set(keys))


def _check_key(key: str, where: str, allowed: list[str], problems: list[str]) -> None:
    if key in allowed or (key.startswith("materials.") and key.count(".") == 2):
        return
    near = difflib.get_close_matches(key, allowed, n=3)
    hint = (
        f"; did you mean {', '.join(near)}?"
        if near
        else "; a key is 'table.key' of the parameter file"
    )
    problems.append(f"{where} {key!r}: not a parameter{hint}")


def _dimension(key: str, raw: Any, where: str, problems: list[str]) -> Dimension | None:
    if isinstance(raw, list):
        if not raw:
            problems.append(f"{where}.{key} = []: a list of choices needs at least one value")
            return None
        return Dimension(key, choices=tuple(raw))
    if isinstance(raw, dict):
        extra = set(raw) - {"low", "high", "step", "log"}
        low, high = raw.get("low"), raw.get("high")
        if extra or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in (low, high)
        ):
            problems.append(
                f"{where}.{key} = {raw!r}: expected {{ low = number, high = number }} "
                f"(optional step, log) or a list of choices"
            )
            return None
        if not low < high:
            problems.append(f"{where}.{key}: low = {low} must be below high = {high}")
            return None
        step = raw.get("step")
        log = bool(raw.get("log", False))
        if log and low <= 0:
            problems.append(f"{where}.{key}: log = true needs low > 0 (found {low})")
            return None
        return Dimension(
            key,
            low=float(low),
            high=float(high),
            step=None if step is None else float(step),
            log=log,
        )
    problems.append(f"{where}.{key} = {raw!r}: expected a list of choices or {{ low, high }}")
    return None


def load_study(path: str | Path) -> Study:
    """Read and validate a study file.

    Raises:
        StudyError: naming every problem (unknown keys, empty axes, bad ranges, no axes, a bad base
            file).
    """
    path = Path(path)
    raw = read_toml(path, StudyError)
    problems: list[str] = []
    for k in raw:
        if k not in TOP_KEYS:
            problems.append(f"{k}: unknown key; allowed: {', '.join(sorted(TOP_KEYS))}")
    name = raw.get("name", path.stem)
    if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
        problems.append(f"name = {name!r}: letters, digits, '_' and '-' only")
    base_path, base_data = _study_base(raw, path, problems)
    allowed = known_keys(base_data) if base_data else []

    def check_key(key: str, where: str) -> None:
        """An unknown key is a problem (not judged when the base file itself could not be read)."""
        if allowed:
            _check_key(key, where, allowed, problems)

    options = _study_options(raw, problems)
    fixed, grid, listed = _study_axes(raw, check_key, problems)
    search = _study_search(raw, check_key, problems)
    expect = _study_expectations(raw, problems)
    if search["kind"] == "grid" and not grid and not listed:
        problems.append("no axes: give [grid], [[variants]], [random] or [optuna]")
    if problems:
        raise StudyError(path, problems)
    return Study(
        path=path,
        name=name,
        base_path=base_path,
        base_data=base_data,
        **options,
        fixed=dict(fixed),
        grid={k: list(v) for k, v in grid.items()},
        listed=tuple(listed),
        **search,
        expect=tuple(expect),
    )


def _study_base(
    raw: dict[str, Any], path: Path, problems: list[str]
) -> tuple[Path, dict[str, Any]]:
    """The base parameter file's path (relative to the study) and its data, its data file made
    absolute."""
    base_raw = raw.get("base")
    base_data: dict[str, Any] = {}
    base_path = path.parent / str(base_raw or "")
    if not isinstance(base_raw, str) or not base_raw:
        problems.append(
            "base: missing; the parameter file the variants start from (relative to the study)"
        )
    else:
        try:
            base_data = read_toml(base_path, StudyError)
        except StudyError as exc:
            problems += [f"base = {base_raw!r} ({base_path}): {p}" for p in exc.problems]
    _absolute_data_file(base_data, base_path)
    return base_path, base_data


def _study_options(raw: dict[str, Any], problems: list[str]) -> dict[str, Any]:
    """What each variant reports and under which conditions: metrics, checks, time limit, baseline,
    conditions (as :class:`Study`'s fields)."""
    metrics = raw.get("metrics", [])
    if not isinstance(metrics, list) or not metrics or not all(isinstance(m, str) for m in metrics):
        problems.append(f"metrics = {metrics!r}: a non-empty list of metric groups or metric names")
        metrics = []
    checks = raw.get("checks", False)
    if not isinstance(checks, bool):
        problems.append(f"checks = {checks!r}: true or false")
    limit = raw.get("time_limit_s", 900.0)
    if isinstance(limit, bool) or not isinstance(limit, (int, float)) or not limit > 0:
        problems.append(f"time_limit_s = {limit!r}: a number of seconds > 0")
        limit = 900.0
    baseline = raw.get("baseline", True)
    if not isinstance(baseline, bool):
        problems.append(f"baseline = {baseline!r}: true or false")
    conditions = raw.get("conditions", {})
    if not isinstance(conditions, dict) or set(conditions) - {
        "pressure_bar",
        "motion",
        "payload_g",
    }:
        problems.append(f"conditions = {conditions!r}: a table of pressure_bar, motion, payload_g")
        conditions = {}
    if conditions.get("motion", "extension") not in ("extension", "flexion", "waggle"):
        problems.append(
            f"conditions.motion = {conditions['motion']!r}: extension, flexion or waggle"
        )
    for k in ("pressure_bar", "payload_g"):
        v = conditions.get(k, 0.0)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0:
            problems.append(f"conditions.{k} = {v!r}: a number >= 0")
    return {
        "metrics": tuple(metrics),
        "checks": bool(checks),
        "time_limit_s": float(limit),
        "baseline": bool(baseline),
        "conditions": dict(conditions),
    }


def _study_axes(
    raw: dict[str, Any], check_key: collections.abc.Callable[[str, str], None], problems: list[str]
) -> tuple[dict, dict, list]:
    """The values every variant sets (``set``), the grid's axes and the listed variants."""
    fixed = raw.get("set", {})
    if not isinstance(fixed, dict):
        problems.append(f"set = {fixed!r}: a table of 'table.key' = value")
        fixed = {}
    for k in fixed:
        check_key(k, "set")
    grid = raw.get("grid", {})
    if not isinstance(grid, dict):
        problems.append(f"grid = {grid!r}: a table of 'table.key' = [values]")
        grid = {}
    for k, values in grid.items():
        check_key(k, "grid")
        if not isinstance(values, list) or not values:
            problems.append(f"grid.{k} = {values!r}: a non-empty list of values")
    listed = raw.get("variants", [])
    if not isinstance(listed, list) or not all(isinstance(v, dict) for v in listed):
        problems.append(
            "variants: an array of tables ([[variants]]), each 'table.key' = value and an optional "
            "label"
        )
        listed = []
    for i, v in enumerate(listed, start=1):
        for k in v:
            if k != "label":
                check_key(k, f"variants[{i}]")
    return fixed, grid, listed


def _study_search(
    raw: dict[str, Any], check_key: collections.abc.Callable[[str, str], None], problems: list[str]
) -> dict[str, Any]:
    """The study's kind (grid, random or optuna) and its search: space, samples or trials, seed, and
    for Optuna its objectives, constraints and sampler (as :class:`Study`'s fields)."""
    out: dict[str, Any] = {
        "kind": "grid",
        "space": (),
        "samples": 0,
        "seed": 1,
        "trials": 0,
        "sampler": "tpe",
        "objectives": (),
        "constraints": (),
    }
    space: list[Dimension] = []
    if "random" in raw and "optuna" in raw:
        problems.append(
            "random and optuna: a study is one of them (grid and listed variants may join either)"
        )
    for section in ("random", "optuna"):
        if section not in raw:
            continue
        out["kind"] = section
        sec = raw[section]
        if not isinstance(sec, dict):
            problems.append(f"{section}: a table")
            continue
        known = {
            "random": {"samples", "seed", "space"},
            "optuna": {"trials", "seed", "space", "objectives", "constraints", "sampler"},
        }[section]
        for k in sec:
            if k not in known:
                problems.append(f"{section}.{k}: unknown key; allowed: {', '.join(sorted(known))}")
        count_key = "samples" if section == "random" else "trials"
        count = sec.get(count_key)
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            problems.append(f"{section}.{count_key} = {count!r}: an integer >= 1")
            count = 0
        seed = sec.get("seed", 1)
        if isinstance(seed, bool) or not isinstance(seed, int):
            problems.append(f"{section}.seed = {seed!r}: an integer")
            seed = 1
        out["seed"] = seed
        dims = sec.get("space", {})
        if not isinstance(dims, dict) or not dims:
            problems.append(
                f"{section}.space: a non-empty table of 'table.key' = [choices] or {{ low, high }}"
            )
            dims = {}
        for k, v in dims.items():
            check_key(k, f"{section}.space")
            d = _dimension(k, v, f"{section}.space", problems)
            if d is not None:
                space.append(d)
        if section == "random":
            out["samples"] = count
        else:
            out["trials"] = count
            out.update(_optuna_goals(sec, problems))
    out["space"] = tuple(space)
    return out


def _optuna_goals(sec: dict[str, Any], problems: list[str]) -> dict[str, Any]:
    """An Optuna study's objectives, constraints and sampler."""
    objectives: list[Objective] = []
    constraints: list[Constraint] = []
    objs = sec.get("objectives", [])
    if not isinstance(objs, list) or not objs:
        problems.append("optuna.objectives: a non-empty list of { metric = ..., direction = ... }")
        objs = []
    for o in objs:
        if (
            not isinstance(o, dict)
            or set(o) != {"metric", "direction"}
            or o["direction"] not in DIRECTIONS
        ):
            problems.append(
                f"optuna.objectives: {o!r}: expected {{ metric = name, direction = "
                f"'maximize' or 'minimize' }}"
            )
            continue
        objectives.append(Objective(o["metric"], o["direction"]))
    for c in sec.get("constraints", []):
        ok = (
            isinstance(c, dict)
            and "metric" in c
            and set(c) <= {"metric", "min", "max"}
            and ("min" in c or "max" in c)
        )
        if not ok:
            problems.append(
                f"optuna.constraints: {c!r}: expected {{ metric = name, min = x and/or max = y }}"
            )
            continue
        constraints.append(Constraint(c["metric"], c.get("min"), c.get("max")))
    sampler = sec.get("sampler", "tpe")
    if sampler not in ("tpe", "random"):
        problems.append(f"optuna.sampler = {sampler!r}: 'tpe' or 'random'")
    return {"objectives": tuple(objectives), "constraints": tuple(constraints), "sampler": sampler}


def _study_expectations(raw: dict[str, Any], problems: list[str]) -> list[Expectation]:
    """The ``[[expect]]`` tables: which metric rises or falls with which axis, and the source saying
    so."""
    expect: list[Expectation] = []
    raw_expect = raw.get("expect", [])
    if not isinstance(raw_expect, list):
        problems.append(f"expect = {raw_expect!r}: an array of tables ([[expect]])")
        raw_expect = []
    for i, e in enumerate(raw_expect, start=1):
        ok = (
            isinstance(e, dict)
            and "metric" in e
            and (("rises_with" in e) != ("falls_with" in e))
            and set(e) <= {"metric", "rises_with", "falls_with", "source"}
        )
        if not ok:
            problems.append(
                f"expect[{i}] = {e!r}: expected {{ metric = name, rises_with = name (or "
                "falls_with), "
                f"source = text }}"
            )
            continue
        versus = e.get("rises_with", e.get("falls_with"))
        expect.append(
            Expectation(
                e["metric"], versus, 1 if "rises_with" in e else -1, str(e.get("source", ""))
            )
        )
    return expect


def _absolute_data_file(data: dict[str, Any], base_path: Path) -> None:
    """A calibration's data file is relative to its parameter file: make it absolute, so a variant's
    mapping means the same file wherever the variant is written."""
    cal = data.get("calibration")
    if isinstance(cal, dict) and isinstance(cal.get("data_file"), str) and cal["data_file"]:
        cal["data_file"] = os.path.normpath(str((base_path.parent / cal["data_file"]).resolve()))


__all__ = [
    "Study",
    "StudyError",
    "Expectation",
    "Variant",
    "Dimension",
    "Objective",
    "Constraint",
    "load_study",
    "set_path",
    "get_path",
]

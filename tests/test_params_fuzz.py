"""Every one-key edit of the default file either loads or is refused naming the key the user edited.

Each number of the geometry tables times 0.3 and times 3 (106 edits). A refusal must name the edited
key, not only derived geometry (the port depth for a new joint height, the SOA's valley interior for
a new fold, the mold gate for a new flange, ...), and no edit may crash.
"""

from __future__ import annotations

import copy
import tomllib

import pytest

from bvsr_cad.parameters.load import ParamError, spec_from_dict

from .conftest import PARAMS

TABLES = (
    "joint",
    "soa",
    "tubes",
    "socket",
    "mount",
    "payload",
    "lightening",
    "fabrication",
    "taper",
    "casting",
)
BASE = tomllib.loads((PARAMS / "bvsr.toml").read_text())
EDITS = [
    (f"{table}.{key}", factor)
    for table in TABLES
    for key, value in BASE[table].items()
    if isinstance(value, (int, float)) and not isinstance(value, bool)
    for factor in (0.3, 3.0)
]


@pytest.mark.parametrize("key,factor", EDITS, ids=[f"{k}x{f:g}" for k, f in EDITS])
def test_a_one_key_edit_loads_or_names_its_key(key, factor):
    data = copy.deepcopy(BASE)
    table, name = key.split(".")
    value = data[table][name]
    data[table][name] = value * factor if isinstance(value, float) else max(1, int(value * factor))
    try:
        spec_from_dict(data, "edited.toml")
    except ParamError as exc:
        assert any(key in line for line in exc.problems), exc.problems

"""The build's stage runner (bvsr_cad.pipeline.runner): a stage declared in a list runs through it
with no edit of the runner, keyed by exactly what it declares it reads."""

from __future__ import annotations

import dataclasses

from bvsr_cad.pipeline.cache import ArtifactCache, spec_without, stage_key
from bvsr_cad.pipeline.publish import StageLog
from bvsr_cad.pipeline.runner import Runner, Stage

#: A stage of the kind a new export file adds: the tail's name and rod material, written to one
#: file.
SUMMARY = Stage(
    "parameter summary",
    "summary",
    ignore=None,
    say="parameter summary",
    derived=lambda spec: {"name": spec.name, "rod": spec.vertebra.material},
)


def _summary(spec, folder):
    (folder / "summary.txt").write_text(f"{spec.name}: {spec.vertebra.material} rod\n")
    return {"summary": {"file": "summary.txt"}}


def _run(spec, cache, folder, said):
    folder.mkdir()
    log = StageLog(said.append)
    return Runner(spec, b"", cache, folder, log).run(
        SUMMARY, lambda f: _summary(spec, f)
    ), log.stages


def test_a_new_stage_is_cached_by_what_it_declares(bvsr_spec, tmp_path):
    """Built once, then reused (its file copied from the cache, its products read back) while what
    it reads is unchanged; built again when a value it reads changes, not when another does."""
    cache = ArtifactCache(tmp_path / "cache")
    said: list[str] = []
    first, stages = _run(bvsr_spec, cache, tmp_path / "a", said)
    assert first == {"summary": {"file": "summary.txt"}} and [s["status"] for s in stages] == [
        "built"
    ]
    assert said[0] == "parameter summary" and said[1].startswith("stage parameter summary: built")
    again, stages = _run(bvsr_spec, cache, tmp_path / "b", said)
    assert again == first and [s["status"] for s in stages] == ["reused"]
    assert (tmp_path / "b" / "summary.txt").read_text() == (
        tmp_path / "a" / "summary.txt"
    ).read_text()
    unread = dataclasses.replace(bvsr_spec, segments=bvsr_spec.segments + 1)  # not among its reads
    assert [s["status"] for s in _run(unread, cache, tmp_path / "c", said)[1]] == ["reused"]
    pvc = dataclasses.replace(
        bvsr_spec, vertebra=dataclasses.replace(bvsr_spec.vertebra, material="PVC")
    )
    assert [s["status"] for s in _run(pvc, cache, tmp_path / "d", said)[1]] == ["built"]
    assert (tmp_path / "d" / "summary.txt").read_text().endswith("PVC rod\n")


def test_a_stage_key_is_its_declaration(bvsr_spec):
    """The key is the stage's name over the parameters less its ignore list, its derived values and
    the data file it reads: the same as stage_key given those by hand."""
    stage = Stage(
        "x",
        "x_stage",
        ignore=("materials", "vertebra.material"),
        data=True,
        derived=lambda spec: {"rod": spec.vertebra.has_rod},
    )
    by_hand = stage_key(
        "x_stage",
        spec=spec_without(bvsr_spec, "materials", "vertebra.material"),
        rod=bvsr_spec.vertebra.has_rod,
        data=b"measured",
    )
    assert stage.key_for(bvsr_spec, b"measured") == by_hand
    assert stage.key_for(bvsr_spec, b"other") != by_hand


def test_without_a_cache_every_stage_runs_and_hands_on_what_it_read_back(bvsr_spec, tmp_path):
    said: list[str] = []
    out, stages = _run(bvsr_spec, None, tmp_path / "a", said)
    assert out == {"summary": {"file": "summary.txt"}} and [s["status"] for s in stages] == [
        "built"
    ]
    out, stages = _run(bvsr_spec, None, tmp_path / "b", said)
    assert [s["status"] for s in stages] == ["built"]

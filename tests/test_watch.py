"""`bvsr watch`: a save triggers a rebuild that names the changed keys; a bad edit keeps the last
good export; stopping ends it cleanly. The builds are stand-ins here (the real one is tested
elsewhere); the file watching is the real watchfiles."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from bvsr_cad.parameters.load import ParamError
from bvsr_cad.parts.kernel import GeometryError
from bvsr_cad.pipeline.publish import BuildResult
from bvsr_cad.pipeline.watch import changed_keys, watch


def test_changed_keys_names_table_and_key():
    old = {"vertebra": {"material": "nylon", "diameter_mm": 6.0}, "segments": 2}
    new = {"vertebra": {"material": "pvc", "diameter_mm": 6.0}, "segments": 2, "extra": 1}
    assert changed_keys(old, new) == ["extra: added", "vertebra.material: 'nylon' -> 'pvc'"]


def _wait(cond, seconds=20.0):
    end = time.time() + seconds
    while time.time() < end:
        if cond():
            return True
        time.sleep(0.05)
    return False


def test_watch_rebuilds_on_save_and_survives_a_bad_edit(tmp_path):
    params = tmp_path / "tail.toml"
    params.write_text('name = "t"\n[vertebra]\nmaterial = "nylon"\n')
    calls, lines = [], []

    def build(path, out, progress):
        text = Path(path).read_text()
        calls.append(text)
        if "oops" in text:
            raise ParamError(path, ["vertebra.material = 'oops': not a material"])
        if "kernel" in text:
            raise GeometryError("panel0: the kernel produced 2 solids instead of one")
        return BuildResult(
            tmp_path / "out",
            [],
            0.01,
            [
                {"stage": "part files", "status": "reused", "seconds": 0.0},
                {"stage": "analyses", "status": "built", "seconds": 0.0},
            ],
        )

    stop = threading.Event()
    th = threading.Thread(
        target=watch,
        args=(params, None, lines.append),
        kwargs={"stop": stop, "debounce_ms": 100, "build": build},
        daemon=True,
    )
    th.start()
    assert _wait(lambda: any(line.startswith("watching") for line in lines))
    params.write_text('name = "t"\n[vertebra]\nmaterial = "pvc"\n')
    assert _wait(lambda: len(calls) == 2)
    assert _wait(lambda: any("vertebra.material: 'nylon' -> 'pvc'" in line for line in lines))
    assert _wait(lambda: any("rebuilt: analyses; reused: part files" in line for line in lines))
    params.write_text('name = "t"\n[vertebra]\nmaterial = "oops"\n')
    assert _wait(
        lambda: any("the last good export stays" in line and "oops" in line for line in lines)
    )
    params.write_text('name = "t"\n[vertebra]\nmaterial = "kernel"\n')
    assert _wait(
        lambda: any("the last good export stays" in line and "2 solids" in line for line in lines)
    )
    stop.set()
    th.join(10)
    assert not th.is_alive() and lines[-1] == "stopped"


def test_watch_rebuilds_when_the_calibration_data_is_saved_and_follows_a_new_data_file(tmp_path):
    """The build reads ``calibration.data_file`` (the measurement comparison): saving it rebuilds, a
    touch without a change does not, and once an edit names another file (in another folder) that
    one is watched."""
    (tmp_path / "data").mkdir()
    (tmp_path / "other").mkdir()
    data = tmp_path / "data" / "rows.csv"
    data.write_text("quantity,value\na,1\n")
    params = tmp_path / "tail.toml"
    params.write_text('name = "t"\n[calibration]\ndata_file = "data/rows.csv"\n')
    calls, lines = [], []

    def build(path, out, progress):
        calls.append(Path(path).read_text())
        return BuildResult(
            tmp_path / "out", [], 0.01, [{"stage": "analyses", "status": "built", "seconds": 0.0}]
        )

    stop = threading.Event()
    th = threading.Thread(
        target=watch,
        args=(params, None, lines.append),
        kwargs={"stop": stop, "debounce_ms": 100, "build": build},
        daemon=True,
    )
    th.start()
    assert _wait(lambda: any(line.startswith("watching") and str(data) in line for line in lines))
    data.write_text("quantity,value\na,2\n")
    assert _wait(lambda: len(calls) == 2)
    assert any(line == "rows.csv (calibration data) changed" for line in lines)
    data.write_text("quantity,value\na,2\n")  # saved again, same bytes
    time.sleep(1.0)
    assert len(calls) == 2
    moved = tmp_path / "other" / "more.csv"
    moved.write_text("quantity,value\nb,1\n")
    params.write_text('name = "t"\n[calibration]\ndata_file = "other/more.csv"\n')
    assert _wait(lambda: len(calls) == 3)
    assert _wait(
        lambda: any(line.startswith("now watching") and str(moved) in line for line in lines)
    )
    data.write_text("quantity,value\na,3\n")  # no longer read by the build
    moved.write_text("quantity,value\nb,2\n")
    assert _wait(lambda: len(calls) == 4)
    assert "more.csv (calibration data) changed" in lines
    time.sleep(1.0)
    since = lines[lines.index("more.csv (calibration data) changed") :]
    assert len(calls) == 4 and not any("rows.csv" in line for line in since)
    stop.set()
    th.join(10)
    assert not th.is_alive() and lines[-1] == "stopped"


def test_a_save_before_the_watcher_listens_is_built(tmp_path):
    """A save during the first build comes before the watcher is listening: it sends no event the
    watcher can see, and was missed until the next save (a CI run lost one between the "watching"
    line and the watcher's start). The watcher also compares the files with what it last acted on
    (every ``CATCH_UP_MS`` without an event), so it is built; and a file left as it was is not built
    again."""
    params = tmp_path / "tail.toml"
    params.write_text('name = "t"\n[vertebra]\nmaterial = "nylon"\n')
    calls, lines = [], []

    def build(path, out, progress):
        calls.append(Path(path).read_text())
        if len(calls) == 1:  # the designer saves while the first build runs
            params.write_text('name = "t"\n[vertebra]\nmaterial = "pvc"\n')
        return BuildResult(
            tmp_path / "out", [], 0.01, [{"stage": "analyses", "status": "built", "seconds": 0.0}]
        )

    stop = threading.Event()
    th = threading.Thread(
        target=watch,
        args=(params, None, lines.append),
        kwargs={"stop": stop, "debounce_ms": 100, "build": build},
        daemon=True,
    )
    th.start()
    assert _wait(lambda: len(calls) == 2)
    assert 'material = "pvc"' in calls[1]
    assert any("vertebra.material: 'nylon' -> 'pvc'" in line for line in lines)
    time.sleep(1.5)  # three catch-up intervals, nothing new
    assert len(calls) == 2
    stop.set()
    th.join(10)
    assert not th.is_alive() and lines[-1] == "stopped"

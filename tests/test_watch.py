"""`bvsr watch`: a save triggers a rebuild that names the changed keys; a bad edit keeps the last good
export; stopping ends it cleanly. The builds are stand-ins here (the real one is tested elsewhere);
the file watching is the real watchfiles."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from bvsr_cad.parameters.load import ParamError
from bvsr_cad.parts._kernel import GeometryError
from bvsr_cad.pipeline import BuildResult
from bvsr_cad.watch import changed_keys, watch


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
        return BuildResult(tmp_path / "out", [], 0.01, [{"stage": "part files", "status": "reused", "seconds": 0.0},
                                                         {"stage": "analyses", "status": "built", "seconds": 0.0}])

    stop = threading.Event()
    th = threading.Thread(target=watch, args=(params, None, lines.append),
                          kwargs={"stop": stop, "debounce_ms": 100, "build": build}, daemon=True)
    th.start()
    assert _wait(lambda: any(line.startswith("watching") for line in lines))
    params.write_text('name = "t"\n[vertebra]\nmaterial = "pvc"\n')
    assert _wait(lambda: len(calls) == 2)
    assert _wait(lambda: any("vertebra.material: 'nylon' -> 'pvc'" in line for line in lines))
    assert _wait(lambda: any("rebuilt: analyses; reused: part files" in line for line in lines))
    params.write_text('name = "t"\n[vertebra]\nmaterial = "oops"\n')
    assert _wait(lambda: any("the last good export stays" in line and "oops" in line for line in lines))
    params.write_text('name = "t"\n[vertebra]\nmaterial = "kernel"\n')
    assert _wait(lambda: any("the last good export stays" in line and "2 solids" in line for line in lines))
    stop.set()
    th.join(10)
    assert not th.is_alive() and lines[-1] == "stopped"

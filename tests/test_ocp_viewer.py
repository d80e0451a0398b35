"""`bvsr show`, `Tail.show` and `bvsr watch --show`: the tail in a running OCP CAD Viewer.

The viewer test starts the real standalone viewer (``python -m ocp_viewer``, headless: no browser is
opened) and registers a websocket client with it as its browser, so what the viewer received is what
it relays to that client; the expected names and colours come from the assembly's instances and the
colour table, not from the sending code.
"""

from __future__ import annotations

import importlib.util
import json
import math
import socket
import subprocess
import sys
import time

import pytest

from bvsr_cad.colors import ALPHA, rgb

from .conftest import PARAMS


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_show_without_a_viewer_exits_2_and_says_how_to_start_one(capsys):
    from bvsr_cad.cli import main

    port = _free_port()  # nothing listens on it
    assert main(["show", str(PARAMS / "bvsr.toml"), "--port", str(port)]) == 2
    err = capsys.readouterr().err
    assert "python -m ocp_viewer" in err and "bvsr_cad[viewer]" in err, err
    if importlib.util.find_spec("ocp_vscode") is not None:
        assert f"no OCP CAD Viewer listens on port {port}" in err
    assert (
        main(["watch", str(PARAMS / "bvsr.toml"), "--show", "--port", str(port)]) == 2
    )  # before any build


@pytest.fixture(scope="module")
def viewer():
    """The standalone viewer on a free port, and a client registered as its browser."""
    missing = [
        m for m in ("ocp_vscode", "ocp_viewer", "websockets") if importlib.util.find_spec(m) is None
    ]
    if missing:
        pytest.skip(
            f"the OCP CAD Viewer test needs {', '.join(missing)}: pip install 'bvsr_cad[viewer]'"
        )
    from websockets.sync.client import connect

    port = _free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "ocp_viewer", "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        end = time.time() + 60
        while True:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    break
            assert proc.poll() is None and time.time() < end, "the viewer did not start"
            time.sleep(0.2)
        with connect(f"ws://127.0.0.1:{port}", max_size=None, open_timeout=30) as browser:
            browser.send("L:{}")  # sockets.LISTEN: the viewer relays every model to this client
            yield port, browser
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def _next_model(browser) -> dict:
    """The next model the viewer relayed (it may relay configs and commands as well)."""
    end = time.time() + 120
    while time.time() < end:
        message = json.loads(browser.recv(timeout=end - time.time()))
        if message.get("type") == "data":
            return message["data"]
    raise AssertionError("the viewer relayed no model")


def test_the_standalone_viewer_receives_every_instance_named_and_coloured(viewer):
    import bvsr_cad

    port, browser = viewer
    tail = bvsr_cad.load(PARAMS / "bvsr.toml")
    asm = tail._assembly
    assert tail.show(port=port) == [i.name for i in asm.instances]
    parts = _next_model(browser)["shapes"]["parts"]
    assert [p["name"] for p in parts] == [i.name for i in asm.instances]
    for p, inst in zip(parts, asm.instances):
        kind = asm.part_of(inst).kind
        assert p["color"] == "#" + "".join(f"{round(255 * c):02x}" for c in rgb(kind)), inst.name
        assert p["alpha"] == pytest.approx(ALPHA.get(kind, 1.0))
        assert p["subtype"] == "solid"
    tip = f"panel{tail.spec.panels - 1}"
    assert next(p for p in parts if p["name"] == tip)["loc"][1] == pytest.approx(
        [0, 0, 0, 1], abs=1e-9
    )
    # Posed through the command line: the same instances; every joint bent 10 deg towards +Y (phi 90
    # deg) turns the tip panel by joints x 10 deg about -X (constant curvature: the angles add up),
    # the quaternion (x, y, z, w) = (-sin(a/2), 0, 0, cos(a/2)).
    from bvsr_cad.cli import main

    assert (
        main(
            ["show", str(PARAMS / "bvsr.toml"), "--theta", "10", "--phi", "90", "--port", str(port)]
        )
        == 0
    )
    posed = _next_model(browser)["shapes"]["parts"]
    assert [p["name"] for p in posed] == [i.name for i in asm.instances]
    half = math.radians(10 * tail.spec.joints) / 2
    quaternion = next(p for p in posed if p["name"] == tip)["loc"][1]
    assert quaternion == pytest.approx([-math.sin(half), 0, 0, math.cos(half)], abs=1e-9)


@pytest.mark.slow
def test_a_build_hands_on_its_assembly_before_it_writes_the_part_files(
    small_tail, tmp_path, monkeypatch
):
    """`bvsr watch --show`'s hook (build_export's on_assembly): called once per build with the
    tail's assembly, before any part file is written, with the instances the published manifest
    lists; an export the cache holds whole is published and its assembly still handed on. The
    CI-sized tail: a build from scratch stopped by the hook, then the session's cache of it."""
    from bvsr_cad.pipeline.stages import build_export

    class Seen(Exception):
        """Raised by the hook once it has looked: the rest of the build adds nothing here."""

    params = small_tail / "params" / "base.toml"
    listed = [
        i["name"]
        for i in json.loads((small_tail / "base" / "manifest.json").read_text())["assembly"][
            "instances"
        ]
    ]
    seen = []

    def on_assembly(asm):
        seen.append(
            {
                "names": [i.name for i in asm.instances],
                "part_files": sorted(p.name for p in tmp_path.rglob("*.stl")),
            }
        )
        if len(seen) == 1:
            raise Seen

    with pytest.raises(Seen):
        build_export(params, tmp_path / "fresh", use_cache=False, on_assembly=on_assembly)
    assert len(seen) == 1 and seen[0]["names"] == listed and seen[0]["part_files"] == []
    assert not (tmp_path / "fresh").exists()  # stopped: nothing published
    monkeypatch.setenv("BVSR_CACHE", str(small_tail / "cache"))
    again = build_export(params, tmp_path / "cached", on_assembly=on_assembly)
    assert [s["status"] for s in again.stages] == ["reused"]
    assert len(seen) == 2 and seen[1]["names"] == listed

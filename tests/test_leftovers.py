"""A build killed with SIGKILL leaves no process running, and the next build removes its
leftovers."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bvsr_cad.pipeline.cache import OWNER_FILE, ArtifactCache, process_start
from bvsr_cad.pipeline.publish import clean_leftovers

from .conftest import PARAMS


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_leftovers_of_dead_builds_are_removed_live_ones_kept(tmp_path):
    out = tmp_path / "bvsr"
    dead = tmp_path / ".bvsr.tmp-dead"
    live = tmp_path / ".bvsr.tmp-live"
    reused = (
        tmp_path / ".bvsr.tmp-reused"
    )  # a live PID that is another process now (start time differs)
    for folder in (dead, live, reused):
        folder.mkdir()
    (dead / OWNER_FILE).write_text(f"{_dead_pid()} 12345\n")
    (live / OWNER_FILE).write_text(f"{os.getpid()} {process_start(os.getpid())}\n")
    (reused / OWNER_FILE).write_text(f"{os.getpid()} 1\n")
    old_orphan = tmp_path / f".bvsr.old-{int((time.time() - 3600) * 1000)}"
    old_fresh = tmp_path / f".bvsr.old-{int(time.time() * 1000)}"
    other = tmp_path / ".other.tmp-x"  # another export's folder: not ours to judge
    for folder in (old_orphan, old_fresh, other):
        folder.mkdir()
    removed = clean_leftovers(out)
    assert sorted(p.name for p in removed) == sorted([dead.name, reused.name, old_orphan.name])
    assert live.is_dir() and old_fresh.is_dir() and other.is_dir() and not dead.exists()


@pytest.mark.second_processes
@pytest.mark.slow
def test_sigkill_leaves_no_second_process_and_the_next_build_cleans_up(tmp_path):
    out = tmp_path / "exp"
    bvsr = Path(sys.executable).with_name("bvsr")
    cmd = [str(bvsr)] if bvsr.exists() else [sys.executable, "-m", "bvsr_cad.cli"]
    build = subprocess.Popen(
        [*cmd, "build", str(PARAMS / "bvsr.toml"), "-o", str(out), "--no-cache"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    child = None
    deadline = time.time() + 120
    for line in build.stderr:  # wait until the second process reports progress
        if "(second process)" in line or time.time() > deadline:
            break
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            try:
                if (
                    f"{build.pid}"
                    == Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1]
                ):
                    cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
                    if b"bvsr_cad.pipeline.processes.analyses_process" in cmdline:
                        child = int(pid)
            except OSError:
                pass
    assert child is not None, "the second process did not start"
    leftovers = list(tmp_path.glob(".exp.tmp-*"))
    assert len(leftovers) == 1 and (leftovers[0] / OWNER_FILE).is_file()
    build.send_signal(signal.SIGKILL)
    build.wait()
    for _ in range(50):
        if process_start(child) is None:
            break
        time.sleep(0.1)
    assert process_start(child) is None, "the second process outlived its SIGKILLed parent"
    assert clean_leftovers(out) == leftovers and not leftovers[0].exists()


def test_cache_entries_a_dead_build_was_writing_are_removed_live_ones_kept(tmp_path):
    """A build SIGKILLed while it fills a cache entry leaves ``.<key>.tmp-*`` in the cache
    (megabytes of STEP and STL); the next build removes such folders, never a live writer's, and a
    finished entry carries no owner file."""
    cache = ArtifactCache(tmp_path / "artifacts")
    key = "ab" + "0" * 62
    entry = cache.put(key, lambda folder: (folder / "x.txt").write_text("x"))
    assert not (entry / OWNER_FILE).exists() and cache.get(key) == entry
    shard = tmp_path / "artifacts" / "cd"
    shard.mkdir()
    dead, live, reused, old, new = (
        shard / f".cd0000000000.tmp-{n}" for n in ("dead", "live", "reused", "old", "new")
    )
    for folder in (dead, live, reused, old, new):
        folder.mkdir()
        (folder / "part.stl").write_text("solid\n")
    (dead / OWNER_FILE).write_text(f"{_dead_pid()} 12345\n")
    (live / OWNER_FILE).write_text(f"{os.getpid()} {process_start(os.getpid())}\n")
    (reused / OWNER_FILE).write_text(f"{os.getpid()} 1\n")
    hour_ago = time.time() - 3600
    os.utime(old, (hour_ago, hour_ago))  # unclaimed (an older version's): orphaned once it is old
    removed = cache.clean_leftovers()
    assert sorted(p.name for p in removed) == sorted(p.name for p in (dead, reused, old))
    assert live.is_dir() and new.is_dir() and cache.get(key) == entry

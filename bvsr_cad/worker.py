"""Work in a second Python process, beside the main one (the machine's second core).

The child is a fresh interpreter started as ``python -m MODULE OUT ARGS...``;
the module's ``__main__`` block calls :func:`serve`, which runs one function
and pickles ``("ok", result)`` or ``("error", exception)`` into the file
``OUT``. A fresh interpreter rather than :mod:`multiprocessing`: a spawned
child would first re-run the caller's main script (a user's build script
without a ``__main__`` guard would build twice).

The parent starts it with :meth:`SecondProcess.start` (``None`` on one core
or when it cannot start: the caller then does the work itself), collects it
with :meth:`SecondProcess.result` and always :meth:`SecondProcess.close`\\ s it
(which stops a child still running, for instance after Ctrl-C).
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


class WorkerLost(RuntimeError):
    """The second process ended without a result (killed, crashed); the caller may do the work itself."""


def serve(out: str, fn: Callable[..., Any], *args: Any) -> int:
    """Run ``fn(*args)`` and pickle its result, or its exception, into ``out`` (the child's side)."""
    try:
        payload = ("ok", fn(*args))
    except BaseException as exc:  # noqa: BLE001 - handed to the parent, which raises it
        payload = ("error", exc)
    try:
        data = pickle.dumps(payload)
        pickle.loads(data)  # an exception class with its own __init__ may not come back
    except Exception:  # an exception or a result that does not pickle
        data = pickle.dumps(("error", RuntimeError(f"second process failed: {payload[1]}")))
    Path(out).write_bytes(data)
    return 0


class SecondProcess:
    def __init__(self, proc: subprocess.Popen, out: str):
        self.proc: subprocess.Popen | None = proc
        self.out = out
        self.t0 = time.perf_counter()

    @classmethod
    def start(cls, module: str, args: list[str], cwd: Path,
              progress: Callable[[str], None] | None = None) -> "SecondProcess | None":
        """``python -m module OUT *args`` in ``cwd``; each line of its stderr goes to ``progress``
        (from a reader thread) or, without it, nowhere."""
        if (os.cpu_count() or 1) < 2:
            return None
        fd, out = tempfile.mkstemp(prefix="bvsr-worker-", suffix=".pickle")
        os.close(fd)
        package_root = str(Path(__file__).resolve().parents[1])  # the bvsr_cad this process runs
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            [package_root] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])}
        try:
            proc = subprocess.Popen([sys.executable, "-m", module, out, *args], cwd=cwd, env=env,
                                    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL if progress is None else subprocess.PIPE,
                                    text=True, errors="replace")
        except OSError:
            os.unlink(out)
            return None
        if progress is not None:
            def relay() -> None:
                for line in proc.stderr:
                    if line.strip():
                        progress(line.rstrip())

            threading.Thread(target=relay, daemon=True).start()
        return cls(proc, out)

    @property
    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    @property
    def seconds(self) -> float:
        return time.perf_counter() - self.t0

    def result(self) -> Any:
        """Wait for the child; its result, or its exception raised here.

        Raises:
            WorkerLost: it ended without writing a result.
        """
        assert self.proc is not None, "result() after close()"
        code = self.proc.wait()
        try:
            status, payload = pickle.loads(Path(self.out).read_bytes())
        except (OSError, EOFError, pickle.UnpicklingError) as exc:
            raise WorkerLost(f"the second process ended (exit code {code}) without a result") from exc
        finally:
            self.close()
        if status == "error":
            raise payload
        return payload

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.terminate()
                self.proc.wait()
            self.proc = None
            try:
                os.unlink(self.out)
            except OSError:
                pass


def result_or(proc: SecondProcess | None, here: Callable[[], Any], say: Callable[[str], None], what: str) -> Any:
    """The second process's result, or ``here()`` run in this process when there is none or it was lost."""
    if proc is None:
        say(what)
        return here()
    if proc.running:
        say(f"{what}: waiting for the second process")
    try:
        out = proc.result()
    except WorkerLost as exc:
        say(f"{what}: {exc}; running them here")
        return here()
    say(f"{what}: done in the second process ({proc.seconds:.1f} s)")
    return out

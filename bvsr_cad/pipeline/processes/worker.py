"""Work in a second Python process, beside the main one (the machine's second core).

The child is a fresh interpreter started as ``python -m bvsr_cad.pipeline.processes.worker MODULE -
ARGS...`` (:func:`child_main`): it imports MODULE with Ctrl-C held back
(:func:`library_imports`) and calls :func:`serve` with the module's
``SECOND_PROCESS`` (its function and, for a standby child, what prepares it), which
runs that function and pickles ``("ok", result, cpu_s)`` or ``("error",
exception, cpu_s)`` onto its standard output (``cpu_s``: the CPU seconds the
child used, its threads and its imports included; anything else printed there
goes to stderr instead). Nothing is written to disk: the result travels in
memory through the pipe. A fresh interpreter rather than
:mod:`multiprocessing`: a spawned child would
first re-run the caller's main script (a user's build script without a
``__main__`` guard would build twice).

The parent starts it with :meth:`SecondProcess.start` (``None`` on one core
or when it cannot start: the caller then does the work itself), collects it
with :meth:`SecondProcess.result` and always :meth:`SecondProcess.close`\\ s it
(which stops a child still running, for instance after Ctrl-C).
The child runs in its own process group, so a terminal's Ctrl-C interrupts
the parent alone, at whatever instant it comes: the parent stops its children
and reports the interrupt once; the parent's death stops them too
(:func:`_die_with_parent`)."""

from __future__ import annotations

import importlib
import json
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...process import build_processes, library_imports, tune_process


class WorkerLost(RuntimeError):
    """The second process ended without a result (killed, crashed); the caller may do the work
    itself."""


#: The parent's PID, handed to the child so that it dies with the parent (even a SIGKILLed one).
PARENT_PID_ENV = "BVSR_PARENT_PID"


def _die_with_parent() -> None:
    """Linux: the kernel sends SIGKILL to this process when its parent dies (PR_SET_PDEATHSIG);
    elsewhere, or if that fails, a daemon thread polls the parent. Either way a build killed with
    SIGKILL leaves no second process running."""

    parent = int(os.environ.get(PARENT_PID_ENV, "0") or 0)
    if not parent:
        return
    try:
        import ctypes

        if (
            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL), 0, 0, 0) != 0
        ):  # 1 = PR_SET_PDEATHSIG
            raise OSError("prctl failed")
    except (OSError, AttributeError):

        def watch() -> None:
            while os.getppid() == parent:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watch, daemon=True).start()
    if os.getppid() != parent:  # the parent died before the request took effect
        os._exit(1)


#: The first argument of a child started by :meth:`SecondProcess.standby`: its work comes on stdin.
STANDBY = "--standby"


def child_main(argv: list[str]) -> int:
    """A child's entry, ``python -m bvsr_cad.pipeline.processes.worker MODULE OUT ARGS...``: it dies
    with its parent from the start, imports MODULE in :func:`library_imports` (Ctrl-C held: an
    interrupt during the imports ends it quietly with 130, its parent reports it; the collector
    paused, then what was imported frozen) and serves the module's ``SECOND_PROCESS``, ``(fn,
    prepare)`` (see :func:`serve`)."""
    _die_with_parent()
    tune_process()
    module, out, *args = argv
    try:
        with library_imports():
            fn, prepare = importlib.import_module(module).SECOND_PROCESS
    except KeyboardInterrupt:
        return 130
    return serve(out, fn, *args, prepare=prepare)


def serve(
    _out: str, fn: Callable[..., Any], *args: Any, prepare: Callable[..., None] | None = None
) -> int:
    """Run ``fn(*args)``, pickle its result, or its exception, onto stdout and end the process at
    once (the child's side; nothing after it runs).

    ``_out`` is the placeholder argument the parent passes (``-``), or :data:`STANDBY`: then the
    child, its modules imported, waits for one JSON line on stdin, ``{"args": [...], "cwd": ...}``,
    and exits quietly at end of input (the parent did not need it). A standby child's own ``args``
    are its hint (what the parent expects to ask of it): ``prepare(*args)`` runs first, while the
    parent is still deciding (a head start it may waste: the parent stops a child it gives no
    work)."""
    if _out == STANDBY:
        # Ctrl-C reaches this child too (it shares the terminal's process group) while it waits: the
        # parent reports the interrupt; the child leaves quietly, without a traceback among the
        # parent's lines.
        try:
            if prepare is not None and args:
                try:
                    prepare(*args)
                except Exception:  # noqa: BLE001 - only a head start: the work itself meets any problem again
                    pass
            line = sys.stdin.readline()
        except KeyboardInterrupt:
            return 130
        if not line.strip():
            return 0
        work = json.loads(line)
        os.chdir(work["cwd"])
        args = tuple(work["args"])
    result_fd = os.dup(1)
    os.dup2(2, 1)  # stray prints (a library's banner) must not corrupt the pickle
    sys.stdout = sys.stderr
    try:
        payload = ("ok", fn(*args))
    except BaseException as exc:  # noqa: BLE001 - handed to the parent, which raises it
        payload = ("error", exc)
    try:
        data = pickle.dumps((*payload, cpu_seconds()))
        pickle.loads(data)  # an exception class with its own __init__ may not come back
    except Exception:  # an exception or a result that does not pickle
        data = pickle.dumps(
            ("error", RuntimeError(f"second process failed: {payload[1]}"), cpu_seconds())
        )
    with os.fdopen(result_fd, "wb") as out:
        out.write(data)
    # Its work is handed over: leave without the interpreter's teardown, which frees every object of
    # the CAD kernel, MuJoCo and the rest one by one (the parent waits for this process's end, and
    # on a busy machine it is CPU taken from the build).
    sys.stderr.flush()
    os._exit(0)


def cpu_seconds() -> float:
    """CPU seconds (user and system, every thread) this process has used since it started."""
    t = os.times()
    return t.user + t.system


#: Environment variables that name a folder, taken from where the user stands: a child works
#: elsewhere.
PATH_VARIABLES = ("BVSR_CACHE",)


def child_env() -> dict[str, str]:
    """The environment of a child started as ``python -m bvsr_cad...``: it imports the bvsr_cad this
    process runs, knows its parent's PID (so that it dies with it: :func:`child_main`) and is given
    the folders of :data:`PATH_VARIABLES` as absolute paths (it starts in another working
    folder)."""
    package_root = str(Path(__file__).resolve().parents[3])  # bvsr_cad/pipeline/processes/worker.py
    folders = {k: str(Path(os.environ[k]).absolute()) for k in PATH_VARIABLES if os.environ.get(k)}
    return {
        **os.environ,
        **folders,
        PARENT_PID_ENV: str(os.getpid()),
        "PYTHONPATH": os.pathsep.join(
            [package_root] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
        ),
    }


class SecondProcess:
    def __init__(self, proc: subprocess.Popen):
        self.proc: subprocess.Popen | None = proc
        self.t0 = time.perf_counter()
        #: The CPU seconds the child used, once :meth:`result` has its answer (None before, or when
        #: it was lost).
        self.cpu_s: float | None = None
        self._chunks: list[bytes] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        for chunk in iter(lambda: self.proc.stdout.read(1 << 16), b""):
            self._chunks.append(chunk)

    @classmethod
    def start(
        cls,
        module: str,
        args: list[str],
        cwd: Path,
        progress: Callable[[str], None] | None = None,
        standby: bool = False,
    ) -> SecondProcess | None:
        """``python -m bvsr_cad.pipeline.processes.worker module - *args`` (:func:`child_main`) in
        ``cwd``; each line of its stderr goes to ``progress`` (from a reader thread) or, without it,
        nowhere. ``standby``: see :meth:`standby`."""
        if build_processes() < 2:
            return None
        try:
            cmd = [
                sys.executable,
                "-m",
                "bvsr_cad.pipeline.processes.worker",
                module,
                STANDBY if standby else "-",
                *args,
            ]
            proc = subprocess.Popen(
                cmd,
                cwd=cwd,
                env=child_env(),
                stdin=subprocess.PIPE if standby else subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL if progress is None else subprocess.PIPE,
                # Its own process group: a terminal's Ctrl-C (SIGINT to the foreground group)
                # reaches this process only, which stops the child (close) and says so once. In the
                # terminal's group, a child that was still starting (importing bvsr_cad, before it
                # can hold the interrupt) printed a traceback among the build's lines.
                process_group=0,
            )
        except OSError:
            return None
        if progress is not None:

            def relay() -> None:
                for raw in proc.stderr:
                    line = raw.decode("utf-8", "replace").rstrip()
                    if line.strip():
                        progress(line)

            threading.Thread(target=relay, daemon=True).start()
        return cls(proc)

    @classmethod
    def standby(
        cls,
        module: str,
        progress: Callable[[str], None] | None = None,
        hint: list[str] | None = None,
    ) -> SecondProcess | None:
        """``python -m bvsr_cad.pipeline.processes.worker module --standby [HINT...]``: a child that
        imports its modules now, while this process imports its own, prepares what ``hint`` lets it
        (see :func:`serve`) and waits for its work (:meth:`begin`); ``None`` where :meth:`start`
        would give none. A child never given work exits when it is :meth:`close`\\ d."""
        # It starts in the temporary folder (the caller's working folder may be gone) and moves into
        # the one :meth:`begin` names.
        return cls.start(
            module, list(hint or []), Path(tempfile.gettempdir()), progress, standby=True
        )

    def begin(self, args: list[str], cwd: Path) -> bool:
        """Hand a standby child its arguments and working folder; False if it is gone (then start
        another). A relative ``cwd`` is this process's (the child started elsewhere:
        :meth:`standby`)."""
        if not self.running or self.proc is None or self.proc.stdin is None:
            return False
        try:
            self.proc.stdin.write(
                (json.dumps({"args": list(args), "cwd": str(Path(cwd).resolve())}) + "\n").encode()
            )
            self.proc.stdin.close()
        except OSError:
            return False
        self.t0 = time.perf_counter()
        return True

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
        self._reader.join()
        try:
            status, payload, self.cpu_s = pickle.loads(b"".join(self._chunks))
        except (EOFError, pickle.UnpicklingError) as exc:
            raise WorkerLost(
                f"the second process ended (exit code {code}) without a result"
            ) from exc
        finally:
            self.close()
        if status == "error":
            raise payload
        return payload

    def result_or(self, here: Callable[[], Any], say: Callable[[str], None], what: str) -> Any:
        """Its result, or ``here()`` run in this process where it was lost (:func:`result_or`)."""
        return result_or(self, here, say, what)

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.terminate()
                self.proc.wait()
            if self.proc.stdin is not None and not self.proc.stdin.closed:
                self.proc.stdin.close()
            self.proc = None


def result_or(
    proc: SecondProcess | None, here: Callable[[], Any], say: Callable[[str], None], what: str
) -> Any:
    """The second process's result, or ``here()`` run in this process when there is none or it was
    lost."""
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


if __name__ == "__main__":
    from bvsr_cad.pipeline.processes.worker import (
        child_main as _child_main,
    )  # the module by its real name, not __main__

    sys.exit(_child_main(sys.argv[1:]))

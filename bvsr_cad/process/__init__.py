"""Every setting bvsr_cad makes to a process, in one place: nothing outside this package sets an
environment variable, the allocator, the garbage collector, the import system or the CAD kernel's
thread pool.

Two kinds:

* What a ``bvsr`` process sets at its start (:func:`tune_process`): the command and each of its
  second processes call it before their imports; ``import bvsr_cad`` changes nothing in the
  importing process, so a library call in someone else's process leaves it as it was.
* What library code sets for a block and gives back: :func:`library_imports` (Ctrl-C held and the
  collector paused while the libraries import) and :func:`kernel_threads` (OCCT's thread pool).

Each setting stays because a quiet, alternated measurement showed it worth its place
(benchmarks/RESULTS.md, the rebuild benchmark's process settings off against on).
"""

from __future__ import annotations

import gc
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from ..errors import BadInput

#: glibc's allocator settings of a ``bvsr`` process (:func:`tune_allocator`): (mallopt parameter,
#: value). M_MMAP_THRESHOLD (-3) 64 MiB, M_TRIM_THRESHOLD (-1) 256 MiB, M_TOP_PAD (-2) 64 MiB.
ALLOCATOR_SETTINGS = ((-3, 64 << 20), (-1, 256 << 20), (-2, 64 << 20))


def tune_allocator() -> bool:
    """Keep freed memory in the process for the next allocation instead of handing it back to the
    kernel (glibc's ``mallopt``; elsewhere nothing changes, False). With the defaults, the many
    large numpy temporaries of a build (meshes, pose batches) are each mapped fresh and unmapped
    when freed, and the kernel zeroes every page again on first touch: a fifth of a build's minor
    page faults and system CPU, for a few per cent more peak memory. Called by the entry points only
    (the ``bvsr`` command, a second process), never by a library call in someone else's process."""
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    return all(mallopt(param, value) == 1 for param, value in ALLOCATOR_SETTINGS)


def no_mujoco_rendering() -> None:
    """MuJoCo's OpenGL contexts off (``MUJOCO_GL=disable``) unless the environment names one:
    nothing of bvsr_cad draws through MuJoCo (its pictures are pyvista's), and ``import mujoco``
    otherwise loads GLFW, whose Python binding starts a Python interpreter to read the library's
    version, in each of a build's three processes. Called by the entry points only (the ``bvsr``
    command, a second process, which inherits it), as :func:`tune_allocator`."""
    os.environ.setdefault("MUJOCO_GL", "disable")


#: The variables OpenBLAS reads its number of threads from.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")


def one_blas_thread() -> None:
    """numpy's and scipy's OpenBLAS on one thread (``OPENBLAS_NUM_THREADS=1``) unless the
    environment sets a number OpenBLAS reads (:data:`BLAS_THREAD_VARIABLES`); before they are
    imported. A build keeps both cores busy with its own processes: OpenBLAS's second thread only
    takes CPU from them (figures: benchmarks/RESULTS.md) and the export is the same (every file, the
    manifest's volatile section aside). Called by the entry points only (the ``bvsr`` command, a
    second process, which inherits it), as :func:`tune_allocator`."""
    if not any(os.environ.get(name) for name in BLAS_THREAD_VARIABLES):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"


@contextmanager
def interrupts_held() -> Iterator[None]:
    """Ctrl-C (SIGINT) held back while the block runs and raised as KeyboardInterrupt when it ends:
    for imports of the libraries. trimesh's optional imports catch ``BaseException``, so an
    interrupt that lands in one is swallowed (a Ctrl-C during the pipeline's imports let the build
    run on to the end), and pybind11 turns one into OCP's
    ``ImportError: initialization failed``. An interrupt that came wins over an error the block
    raised. Off the main thread, or where SIGINT is not Python's own handler (ignored, or the
    caller's), the block runs as it is."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    came: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, _frame: came.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if (
            came
        ):  # before any error the block raised (the user asked to stop): that one is its context
            raise KeyboardInterrupt


#: Entry points (:func:`tune_collector`) freeze what the libraries' imports made
#: (:func:`library_imports`).
_FREEZE_IMPORTS = False


def tune_collector() -> None:
    """This process's libraries, once :func:`library_imports` has imported them, are frozen out of
    Python's cyclic garbage collector (``gc.freeze``: a full collection no longer walks their
    million objects, again and again in a build that allocates as much as this one). Called by the
    entry points only (the ``bvsr`` command, a second process), as
    :func:`tune_allocator`: frozen objects are never freed (what the imports left in cycles stays
    until the process ends), which a library call in someone else's process must not decide."""
    global _FREEZE_IMPORTS
    _FREEZE_IMPORTS = True


@contextmanager
def library_imports() -> Iterator[None]:
    """The block that imports the libraries (the CAD kernel, MuJoCo, scipy, trimesh, ...): Ctrl-C
    held back (:func:`interrupts_held`) and Python's cyclic garbage collector paused. Imports make
    about a million objects and almost no garbage, yet the collector would run hundreds of times
    over them in each process. It resumes when the block ends, if it ran before; in an entry point's
    process (:func:`tune_collector`) what the block imported is frozen first."""
    was = gc.isenabled()
    gc.disable()
    try:
        with interrupts_held():
            yield
    finally:
        if was:
            if _FREEZE_IMPORTS:
                gc.freeze()
            gc.enable()


def tune_process() -> None:
    """What a ``bvsr`` process sets at its start, before its imports: :func:`tune_allocator`,
    :func:`tune_collector`, :func:`no_mujoco_rendering`, :func:`one_blas_thread` and scikit-learn's
    clustering loaded when used (:func:`bvsr_cad.process.deferred.defer_sklearn_cluster`).
    Called by the entry points only (the command, a second process, the rebuild benchmark's own
    process), in one place so that they stay alike: ``import bvsr_cad`` changes nothing in the
    importing process. They stay as two groups, each measured to save over a second of a cold build
    (benchmarks/RESULTS.md): what the libraries' imports cost every process (the collector paused
    and frozen, no GLFW, scikit-learn deferred) and the allocator's and OpenBLAS's settings; one by
    one their savings are within a run's noise."""
    from .deferred import defer_sklearn_cluster

    tune_allocator()
    tune_collector()
    no_mujoco_rendering()
    one_blas_thread()
    defer_sklearn_cluster()


#: The environment variable that caps the processes one build runs at once (a whole number, 1 or
#: more; unset: the cores, :func:`build_processes`).
PROCESSES_VARIABLE = "BVSR_PROCESSES"


def build_processes() -> int:
    """How many processes one build runs at once: the cores this process may run on
    (``os.sched_getaffinity``: ``taskset`` and container limits count; else ``os.cpu_count``), at
    most ``BVSR_PROCESSES`` where it is set. Below two a build runs its analyses and checks in its
    own process: on a machine already busy with other builds (a test suite's workers, a study's) a
    second process takes no core of its own and adds only its imports, the same work costs less
    CPU in one process (benchmarks/RESULTS.md, the test suite).

    Raises:
        BadInput: ``BVSR_PROCESSES`` is not a whole number of 1 or more.
    """
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    text = os.environ.get(PROCESSES_VARIABLE, "").strip()
    if not text:
        return cores
    try:
        cap = int(text)
    except ValueError:
        cap = 0
    if cap < 1:
        raise BadInput(
            f"{PROCESSES_VARIABLE}={text!r}: the most processes a build runs at once must be a "
            "whole number, 1 or more (unset: one a core)"
        )
    return min(cores, cap)


def kernel_threads(n: int) -> int:
    """Run OCCT's parallel algorithms (the booleans and the meshing build123d and the exporters ask
    to run in parallel) on ``n`` threads, the calling one included (1: on it alone); the number
    before is returned, to give back. A build whose second process keeps the other core busy asks
    for 1: on the default tail its booleans then take less CPU than on two threads for the same
    solids, and the meshing as much for the same STL bytes (figures: benchmarks/RESULTS.md). OCCT
    refuses while its threads are at work: the pool is then left as it was."""
    from OCP.OSD import OSD_ThreadPool

    pool = OSD_ThreadPool.DefaultPool_s()
    before = pool.NbThreads()
    try:
        pool.Init(max(1, int(n)))
    except Exception:  # noqa: BLE001 - "active ThreadPool is reinitialized": another thread is using it
        pass
    return before

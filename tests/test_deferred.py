"""scikit-learn's clustering is loaded when used, not when the CAD kernel is imported
(bvsr_cad.process.deferred)."""

import os
import subprocess
import sys

from .conftest import ROOT

CHILD = r"""
import sys, time
import numpy as np
from bvsr_cad.process import tune_process
tune_process()  # as every bvsr process does at its start
import bvsr_cad.pipeline.stages  # every layer, build123d with it
assert "sklearn" not in sys.modules, "scikit-learn was imported with the pipeline"
assert "sklearn.cluster" not in sys.modules and "build123d" in sys.modules  # the stand-in is gone
import build123d.brep_from_stl as b
points = np.array([[0.0, 0.0], [0.1, 0.0], [5.0, 5.0], [5.1, 5.0]])
est = b.DBSCAN(eps=0.5, min_samples=2).fit(points)
import sklearn.cluster
assert type(est) is sklearn.cluster.DBSCAN and est.labels_.tolist() == [0, 0, 1, 1], est
assert type(sys.modules["sklearn.cluster"]).__name__ == "module"
import sklearn.cluster._kmeans
from sklearn.cluster import KMeans, DBSCAN
assert KMeans is sklearn.cluster._kmeans.KMeans and DBSCAN is sklearn.cluster.DBSCAN
print("ok")
"""

BEFORE = r"""
import sys
import sklearn.cluster  # the user's own, before bvsr_cad: left as it is
from bvsr_cad.process import tune_process
tune_process()
import bvsr_cad.pipeline.stages
assert sys.modules["sklearn.cluster"] is sklearn.cluster
print("ok")
"""


def test_sklearn_cluster_loads_when_used_and_is_the_real_one():
    """A new interpreter imports the whole pipeline without scikit-learn (0.7 s of each build
    process); build123d's DBSCAN, when called, is scikit-learn's own estimator (the same clusters),
    and later imports of ``sklearn.cluster`` and its submodules get the real package; one imported
    before bvsr_cad is left as it is."""
    for child in (CHILD, BEFORE):
        out = subprocess.run(
            [sys.executable, "-c", child],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-3000:]


LIBRARY = r"""
import gc, os, sys
finders, gc_on, env = list(sys.meta_path), gc.isenabled(), dict(os.environ)
import bvsr_cad, bvsr_cad.api
assert sys.meta_path == finders, sys.meta_path
assert gc.isenabled() == gc_on and gc.get_freeze_count() == 0
# what tune_process sets (libraries set their own: OpenMP's KMP_*)
ours = ("OPENBLAS_NUM_THREADS", "MUJOCO_GL")
assert [os.environ.get(k) for k in ours] == [env.get(k) for k in ours]
print("ok")
"""


def test_importing_the_library_changes_nothing_in_the_process():
    """``import bvsr_cad`` (and its API) installs no import hook, leaves the collector and the
    environment variables of :func:`bvsr_cad.process.tune_process` as they were: only the ``bvsr``
    command and its own processes set process settings."""
    out = subprocess.run(
        [sys.executable, "-c", LIBRARY],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-3000:]

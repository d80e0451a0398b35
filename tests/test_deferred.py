"""scikit-learn's clustering is loaded when used, not when the CAD kernel is imported (bvsr_cad._deferred)."""

import os
import subprocess
import sys

from .conftest import ROOT

CHILD = r"""
import sys, time
import numpy as np
import bvsr_cad.pipeline  # every layer, build123d with it
assert "sklearn" not in sys.modules, "scikit-learn was imported with the pipeline"
assert "sklearn.cluster" not in sys.modules and "build123d" in sys.modules  # the stand-in is gone
import build123d.brep_from_stl as b
est = b.DBSCAN(eps=0.5, min_samples=2).fit(np.array([[0.0, 0.0], [0.1, 0.0], [5.0, 5.0], [5.1, 5.0]]))
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
import bvsr_cad.pipeline
assert sys.modules["sklearn.cluster"] is sklearn.cluster
print("ok")
"""


def test_sklearn_cluster_loads_when_used_and_is_the_real_one():
    """A new interpreter imports the whole pipeline without scikit-learn (0.7 s of each build process);
    build123d's DBSCAN, when called, is scikit-learn's own estimator (the same clusters), and later
    imports of ``sklearn.cluster`` and its submodules get the real package; one imported before
    bvsr_cad is left as it is."""
    for child in (CHILD, BEFORE):
        out = subprocess.run([sys.executable, "-c", child], cwd=ROOT, capture_output=True, text=True, timeout=300,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
        assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-3000:]

"""scikit-learn's clustering, loaded when it is used rather than when build123d is imported.

build123d 0.12 imports ``sklearn.cluster.DBSCAN`` at its own import, for one function
(``build123d.detect_primitives``: primitives recognised in an STL) that bvsr_cad never calls. That
import is 0.7 s of every process that loads the CAD kernel (a build's own, its analyses' process, a
sweep's variants): a third of build123d's import, on the critical path of every build.

:func:`defer_sklearn_cluster` puts a stand-in for ``sklearn.cluster`` in ``sys.modules`` (only when
the real one is not loaded yet). Its ``DBSCAN`` loads the real module when called and returns the
real estimator; any other name asked of it loads the real module and answers from it, and the real
module takes its place in ``sys.modules`` from then on. So ``detect_primitives``, and any code that
imports ``sklearn.cluster`` after bvsr_cad, gets scikit-learn's own objects.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any

_NAME = "sklearn.cluster"


class _StandIn(types.ModuleType):
    """``sklearn.cluster`` until something uses it (see the module's docstring)."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):  # the import system's probes (__path__, __spec__ details): not a use
            raise AttributeError(name)
        return getattr(_real(), name)


def _real() -> types.ModuleType:
    """The real ``sklearn.cluster``, loaded now if it is not yet (the stand-in leaves ``sys.modules``)."""
    if isinstance(sys.modules.get(_NAME), _StandIn):
        del sys.modules[_NAME]
    real = importlib.import_module(_NAME)
    _STAND_IN.DBSCAN = real.DBSCAN  # code that kept the stand-in sees the real class from now on
    return real


def _dbscan(*args: Any, **kwargs: Any) -> Any:
    """``sklearn.cluster.DBSCAN(*args, **kwargs)``, the real estimator."""
    return _real().DBSCAN(*args, **kwargs)


_STAND_IN = _StandIn(_NAME, __doc__)
_STAND_IN.DBSCAN = _dbscan


def defer_sklearn_cluster() -> None:
    """Put the stand-in in place, unless ``sklearn.cluster`` is loaded already (then nothing changes)."""
    if _NAME not in sys.modules:
        sys.modules[_NAME] = _STAND_IN

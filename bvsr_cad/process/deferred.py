"""scikit-learn's clustering, loaded when it is used rather than when build123d is imported.

build123d 0.12 imports ``sklearn.cluster.DBSCAN`` at its own import, for one function
(``build123d.detect_primitives``: primitives recognised in an STL) that bvsr_cad never calls. That
import is a third of build123d's, in every process that loads the CAD kernel (a build's own, its
analyses' process, a sweep's variants): on the critical path of every build.

:func:`defer_sklearn_cluster` adds an import hook that acts once, on the import of ``build123d``:
while build123d's modules run, ``sklearn.cluster`` is a stand-in whose ``DBSCAN`` loads the real
module when called and returns the real estimator; when build123d's import ends the stand-in leaves
``sys.modules``. So ``detect_primitives`` gets scikit-learn's own estimator, and anything that
imports ``sklearn.cluster`` (or its submodules) gets the real package, at any time.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
from typing import Any

_NAME = "sklearn.cluster"


def _real() -> types.ModuleType:
    """The real ``sklearn.cluster``, loaded now if it is not yet."""
    if isinstance(sys.modules.get(_NAME), _StandIn):
        del sys.modules[_NAME]
    return importlib.import_module(_NAME)


class _StandIn(types.ModuleType):
    """``sklearn.cluster`` while build123d imports (see the module's docstring)."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):  # the import system's probes (``__path__``): not a use
            raise AttributeError(name)
        return getattr(_real(), name)


def _dbscan(*args: Any, **kwargs: Any) -> Any:
    """``sklearn.cluster.DBSCAN(*args, **kwargs)``, the real estimator."""
    return _real().DBSCAN(*args, **kwargs)


class _Build123dImport(importlib.abc.MetaPathFinder):
    """Finds ``build123d`` as the other finders do, and runs its import with the stand-in in
    place."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if name != "build123d":
            return None
        sys.meta_path.remove(self)  # once, and not for the lookup just below
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module

        def exec_module(module: types.ModuleType) -> None:
            placed = _NAME not in sys.modules
            if placed:
                stand_in = _StandIn(_NAME, __doc__)
                stand_in.DBSCAN = _dbscan
                sys.modules[_NAME] = stand_in
            try:
                run(module)
            finally:
                if placed and isinstance(sys.modules.get(_NAME), _StandIn):
                    del sys.modules[_NAME]

        spec.loader.exec_module = exec_module  # type: ignore[method-assign]  # this spec's loader only
        return spec


def defer_sklearn_cluster() -> None:
    """Install the hook, unless build123d or ``sklearn.cluster`` is loaded already (then nothing
    changes)."""
    if "build123d" in sys.modules or _NAME in sys.modules:
        return
    if not any(isinstance(f, _Build123dImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _Build123dImport())

"""Studies: variants of a parameter file built, checked and compared (``bvsr sweep``, on Dask); the
study file itself is read by :mod:`bvsr_cad.parameters.study`."""

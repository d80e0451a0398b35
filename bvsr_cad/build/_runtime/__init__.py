"""The build's second processes (:mod:`~bvsr_cad.build._runtime.worker`, the analyses' and the
checks') and the settings the ``bvsr`` command's processes start with
(:func:`~bvsr_cad.build._runtime.worker.tune_process`): nowhere else does bvsr_cad start or tune a
process."""

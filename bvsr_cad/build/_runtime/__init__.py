"""The build's second processes (:mod:`~bvsr_cad.build._runtime.worker`, the analyses' and the
checks'), the part solids they share and the process settings of the ``bvsr`` command's own
processes: nowhere else does bvsr_cad start a process or change one."""

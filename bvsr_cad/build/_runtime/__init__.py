"""The build's second processes (:mod:`~bvsr_cad.build._runtime.worker`, the analyses' and the
checks') and the part solids they share: nowhere else does bvsr_cad start a process."""

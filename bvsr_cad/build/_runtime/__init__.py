"""The build's second processes (:mod:`~bvsr_cad.build._runtime.worker`, the analyses' and the
checks'): nowhere else does bvsr_cad start a process."""

"""The build's second processes (:mod:`~bvsr_cad.pipeline.processes.worker`, the analyses' and the
checks'): nowhere else does bvsr_cad start a process. What a process sets at its start is
:mod:`bvsr_cad.process`'s."""

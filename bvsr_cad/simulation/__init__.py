"""MuJoCo runs of the exported models: on the CPU (:mod:`~bvsr_cad.simulation.sim`) and batched on a
GPU (:mod:`~bvsr_cad.simulation.sim_gpu`), the workspace protocol among them."""

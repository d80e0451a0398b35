"""The build's machinery: the stage list (:mod:`~bvsr_cad.build.pipeline`), the stage runner
(:mod:`~bvsr_cad.build.stages`), the one artifact cache, publishing and ``bvsr watch``;
``_runtime/`` holds the second processes and their settings, and nothing outside ``build/`` starts
a process.
"""

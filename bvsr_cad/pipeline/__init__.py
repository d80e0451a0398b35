"""The build's machinery: the stage list and ``build_export`` (:mod:`~bvsr_cad.pipeline.stages`),
the stage runner (:mod:`~bvsr_cad.pipeline.runner`), the one artifact cache, publishing and
``bvsr watch``; ``processes/`` holds the second processes, and nothing outside ``pipeline/`` starts
a process (what a process sets at its start is :mod:`bvsr_cad.process`'s).
"""

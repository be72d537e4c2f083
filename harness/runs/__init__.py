"""Running work: sweeps in one or two parameters (:mod:`.sweeps`) made of tasks (:mod:`.tasks`)
executed serially, on a process pool or on Dask (:mod:`.backends`), checkpointed and resumed
(:mod:`.checkpoint`), bounded before they start (:mod:`.budget`), experiments bound to their FMU
(:mod:`.experiment`), basin scans over a grid of starts (:mod:`.basins`), and the micro-benchmark
(:mod:`.benchmark`).

Layer: above :mod:`harness.dynamics`; may import ``dynamics``, ``fmu``, ``io`` and the ground;
nothing from ``cli`` or ``reproduce``.
"""

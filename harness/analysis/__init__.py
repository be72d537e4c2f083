"""Analyses of the oscillator for any parameter set, beyond the paper's figures, one folder per
question: the windows of the ODE against the maps' (:mod:`.windows`, ``impact-harness windows``),
where the windows close over two parameters (:mod:`.chart`, ``impact-harness chart``), the
quantifiers of a basin scan (:mod:`.basins`).  :mod:`.context` is what one run needs and how its
results are written.

Layer: above :mod:`harness.runs` and beside nothing: may import every layer below and
:mod:`mapcheck`; :mod:`harness.reproduce` (the paper's figures) and :mod:`harness.cli` use it,
never the reverse.
"""

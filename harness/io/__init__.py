"""Files, figures and the process's own resources: NetCDF results with provenance
(:mod:`.results`), atomic writes and output checks (:mod:`.outputs`), plots (:mod:`.plots`,
:mod:`.sweep_plots`, :mod:`.basin_plot`; one colour per class with a legend: :mod:`.class_map`),
the ``__main__``-guard check before worker processes start (:mod:`.main_guard`),
progress bars (:mod:`.progress`), per-process temporary folders (:mod:`.tempdirs`) and child
processes that go with their parent (:mod:`.children`).

Layer: the bottom, beside the ground (:mod:`harness.config`, :mod:`harness.errors`); imports
nothing else from ``harness``.
"""

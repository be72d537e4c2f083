"""Analyses of the oscillator for any parameter set, beyond the paper's figures: the windows of
the ODE against the maps' (:mod:`.windows`, ``impact-harness windows``; the parameter set in
:mod:`.window_problem`, the ODE's side in :mod:`.ode_windows`, the plots and report in
:mod:`.windows_plots` and :mod:`.windows_report`), and where the windows close over two
parameters (:mod:`.chart`, ``impact-harness chart``; the continued edge curves in
:mod:`.chart_curves`, the plot and report in :mod:`.chart_output`).  :mod:`.context` is what one
run needs and how its results are written.

Layer: above :mod:`harness.runs` and beside nothing: may import every layer below and
:mod:`mapcheck`; :mod:`harness.reproduce` (the paper's figures) and :mod:`harness.cli` use it,
never the reverse.
"""

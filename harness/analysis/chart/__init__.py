"""Where the windows close over sigma and a second parameter (``impact-harness chart``): the
public entry :func:`.chart.chart` (outputs in the same module), the run over the values of the second
parameter (:mod:`.run`), the window edges continued as curves in two parameters (:mod:`.edge_curves`),
a window as a region with its closing confirmed (:mod:`.window_region`), the wall-free window
(:mod:`.wall_free`), the contradictions between routes (:mod:`.contradictions`) and the chord error of
a continued edge read between its points (:mod:`.curve_interpolation`)."""

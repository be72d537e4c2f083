"""Continuation of periodic orbits in one parameter: the pseudo-arclength corrector (:mod:`.arclength`),
the continuation and its branch switching at flips (:mod:`.continue_orbit`), one walk with its located
events (:mod:`.orbit_walk`), step control (:mod:`.step_control`), a branch as a Dataset
(:mod:`.branch`), a window's branch to its first edge (:mod:`.window_branch`), grazes on their defining
equation (:mod:`.graze_location`)."""

"""Periodic attractors: found by scans of the ODE (:mod:`.scans`), told apart by their stroboscopic
points (:mod:`.identity`), confirmed by Newton shooting (:mod:`.check`)."""

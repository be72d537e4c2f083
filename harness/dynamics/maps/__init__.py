"""The stroboscopic map and the questions asked of it: sampling (:mod:`.sampling`), classification
(:mod:`.classify`), Jacobians (:mod:`.jacobian`) and their singularity near grazing
(:mod:`.singularity_fit`), the map of one simulator (:mod:`.stroboscopic_map`) and of M periods in any
parameter (:mod:`.periodic_map`), Lyapunov exponents (:mod:`.lyapunov`), Newton shooting
(:mod:`.shooting`) and its search over a sigma grid (:mod:`.sigma_search`)."""

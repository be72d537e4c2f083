"""The oscillator as a dynamical system: stroboscopic sampling (:mod:`.sampling`), orbit and
dynamics classification (:mod:`.classify`), map Jacobians (:mod:`.jacobian`) and the exponent of
their singularity near grazing (:mod:`.singularity_fit`), Newton shooting of
periodic orbits and window edges (:mod:`.shooting`), Lyapunov exponents (:mod:`.lyapunov`),
periodic attractors from the ODE alone (:mod:`.attractors`), pseudo-arclength continuation of
periodic orbits with located bifurcations and grazings (:mod:`.continuation`, :mod:`.arclength`,
:mod:`.branch`, :mod:`.periodic_map`).

Layer: above :mod:`harness.fmu` and :mod:`harness.io`; may import those, the ground
(:mod:`harness.config`, :mod:`harness.errors`) and :mod:`mapcheck`;
nothing from ``runs``, ``cli`` or ``reproduce``.
"""

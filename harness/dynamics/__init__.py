"""The oscillator as a dynamical system, by feature: the stroboscopic map and the questions asked
of it -- sampling, classification, Jacobians, Lyapunov exponents, Newton shooting (:mod:`.maps`);
periodic attractors found by scans, told apart and confirmed (:mod:`.attractors`); continuation
of periodic orbits in one parameter with located bifurcations and grazings (:mod:`.continuation`);
event curves in two parameters (:mod:`.curves`).

Layer: above :mod:`harness.fmu` and :mod:`harness.io`; may import those, the ground
(:mod:`harness.config`, :mod:`harness.errors`) and :mod:`mapcheck`;
nothing from ``runs``, ``cli`` or ``reproduce``.
"""

"""Driving the FMU: read and check an archive (:mod:`.fmi`), one reusable FMI 2.0/3.0
Co-Simulation instance per thread (:mod:`.slaves`, :mod:`.simulator`), the FMI 2 logger
that stays valid for every instance (:mod:`.fmi2_logging`), the batch kernel
(:mod:`.batch_kernel`) and the bare fmpy loop the harness is benchmarked against
(:mod:`.bare_loop`).

Layer: above :mod:`harness.io` and the ground (:mod:`harness.config`, :mod:`harness.errors`);
imports nothing from ``dynamics``, ``runs``, ``analysis``, ``reproduce`` or ``cli``.
This is the only subpackage that knows about fmpy.
"""

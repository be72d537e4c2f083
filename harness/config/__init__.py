"""The configuration of a run, in one place: the built-in defaults (:mod:`.defaults`), TOML
experiment files and CLI flags layered with the origin of every value (:mod:`.layers`), the
checks of single values (:mod:`.checks`) and the validated specs of sampling, sweeps and runs
(:mod:`.specs`).  Import from here: ``from harness.config import SamplingSpec, Layered``.

An experiment file holds every parameter of a run::

    [fmu]
    path = "build/fmu/ImpactOscillator.fmu"

    [model]            # any settable FMU variable, by name
    sigma = 0.2
    Gamma = 10.0
    wall = "compliant" # or 0/1/2

    [initial]
    u0 = -1.0
    v0 = 0.0

    [sampling]
    theta = 0.5        # section phase in [0, 1) (SECTION_PHASE: every command's default)
    transient = 300    # periods discarded
    samples = 40       # periods sampled
    tol = 1e-5         # periodicity tolerance (relative)
    extend = 0         # extra periods for points not yet periodic (slow near window edges)
    lyapunov = 0       # periods of Lyapunov exponents after the samples (0: none)

    [sweep]
    param = "sigma"
    start = 1.0
    stop = 0.1
    num = 91           # or: values = [...]
    mode = "both"      # fresh | up | down | both
    scan_param = "Gamma"        # optional second axis (2D scan)
    scan_values = [10.0, 100.0]

    [jacobian]
    theta = 0.0        # phase of the coordinates J is expressed in
    x_start = 1e-6
    x_stop = 1e-2
    x_num = 25

    [simulate]
    t0 = 0.0
    t_end = 20.0
    dt = 0.01

    [run]
    backend = "processes"   # serial | processes | dask
    workers = 2
    scheduler = ""          # tcp://host:port -> dask
    out = "results/sweep.nc"
    plot = "results/sweep.png"
    progress = true

Values come from three layers, later ones winning: built-in defaults (and the FMU's own
start values for ``[model]``), the TOML file, the CLI flags.  Each value remembers where it
came from so an error names the flag (``--theta``) or the file key
(``exp.toml: sampling.theta``) the user actually wrote.

What binds these settings to an FMU (parameters of the right type, the initial state) is
:class:`harness.runs.experiment.Experiment`, in the runs layer because it opens the FMU.

Layer: the ground (with :mod:`harness.errors`); imports nothing from the subpackages.
"""
from .checks import _count, _number, check_count, check_theta
from .defaults import (BACKENDS, CLI_FLAGS, DEFAULT_SOLVER, DEFAULTS, MODEL_SHORTCUTS, SECTION_PHASE, SOLVERS,
                       SWEEP_MODES, WALLS, default_fmu_path, default_workers, project_root, solver_name,
                       wall_name)
from .layers import Layered, load_toml
from .specs import RunSpec, SamplingSpec, SweepSpec, parameter_values, parse_modes, sweep_directions

__all__ = [
    "BACKENDS", "CLI_FLAGS", "DEFAULTS", "DEFAULT_SOLVER", "MODEL_SHORTCUTS", "SECTION_PHASE", "SOLVERS",
    "SWEEP_MODES", "WALLS", "Layered", "RunSpec", "SamplingSpec", "SweepSpec",
    "check_count", "check_theta", "default_fmu_path", "default_workers", "load_toml", "parameter_values",
    "parse_modes", "project_root", "solver_name", "sweep_directions", "wall_name",
]

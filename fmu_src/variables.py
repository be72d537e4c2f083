"""The FMU's variables: the one source every declaration of them is generated from.

``fmu_src/generate_variables.py`` writes, from ``VARIABLES`` below, the C value-reference enum
(``variables.h``), the rows of the C variable table (``variables_table.inc``, included by
``VARS[]`` in ``fmu_vars.c``), the C defaults (``model_defaults.inc``, included by
``model_set_defaults`` in ``model.c``), the settable values by name (``model_params.inc``,
included by the basins' batch kernel ``batch.c``), both modelDescription files, the variable and
valid-range tables of ``docs/fmu.md`` and the Python twin's declarations
(``pytwin/twin_variables.py``).  Edit this file, then run
``python fmu_src/generate_variables.py``; ``tests/fmu/test_generated.py`` fails while a
generated file is stale.

A Python module rather than TOML: the project's Python (3.11) reads it without a dependency,
a dataclass checks the fields' names, and the long descriptions shared by the six sensitivity
outputs are written once.  Values that end up in XML or C (start, min, max) are kept as the
strings written there, so that a generated file spells them as the hand-written ones did.
"""
from __future__ import annotations

from dataclasses import dataclass

#: FMI 2.0 and 3.0 causalities the table uses
CAUSALITIES = ("parameter", "calculatedParameter", "input", "output", "local", "independent")


@dataclass(frozen=True)
class Variable:
    """One FMU variable, as every interface declares it.

    Parameters
    ----------
    name : str
        The FMI name (the interface).
    vr : int
        Value reference (the implementation: the C enum ``VR_<enum>``).
    enum : str
        Suffix of the C enum constant (``VR_NU``: ``"NU"``).
    type : str
        ``"Real"``, ``"Integer"`` or ``"Boolean"`` (FMI 2.0 spelling; FMI 3.0 writes Float64,
        Int32, Boolean).
    causality, variability : str
        FMI causality and variability.
    initial : str or None
        FMI 2.0 ``initial`` (the FMI 3.0 file omits the default ``exact`` of parameters).
    description : str
        FMI 2.0 description (also FMI 3.0's and the twin's unless overridden).
    start, min, max : str or None
        Declared start and range, spelt as in the XML; min/max are also the C table's valid
        range (a Boolean's C range is [0, 1], undeclared).
    min_open : bool
        The lower bound itself is refused (an XML min cannot say so; docs and C table do).
    field : str or None
        The ``ModelData`` member holding the value (C ``offsetof``).
    getter : str or None
        The C function (static, in ``fmu_vars.c``) computing the value read back.
    c_start : str or None
        The C expression of the default in ``model_set_defaults`` when ``start`` is not it
        literally (an enum constant); ``None``: ``start``.
    fmi2 : bool
        Declared in the FMI 2.0 modelDescription.
    fmi3_only : bool
        The FMI 2.0 interface refuses its value reference (C table).
    description_fmi3 : str or None
        FMI 3.0 description, where it differs.
    unit : str or None
        Declared unit.
    derivative_of : str or None
        Name of the state this variable is the derivative of.
    dependencies : tuple of str or None
        Output dependencies, FMI 2.0 ModelStructure (None: not an output).
    dependencies_fmi3 : tuple of str or None
        Output dependencies written in the FMI 3.0 file (None: the attribute is omitted, which
        FMI 3.0 reads as "depends on everything").  Derivatives and the event indicator write
        ``dependencies`` in both files.
    dependencies_kind : tuple of str or None
        The ``dependenciesKind`` of each entry of ``dependencies`` (same order), written in both
        files: ``constant`` (a fixed factor), ``discrete`` (a factor that changes only at events:
        with the contact mode), ``dependent`` (changes with the state: the Hertz laws).
        tests/fmu/test_directional_derivatives.py measures the pattern against the FMU's own
        partial derivatives.
    initial_dependencies : tuple of str or None
        FMI 2.0 InitialUnknowns dependencies (None: the attribute is omitted).
    event_indicator : bool
        An FMI 3.0 event indicator.
    twin : bool
        Declared by the Python twin too.
    description_twin : str or None
        The twin's description, where it differs.
    doc_kind, doc_meaning : str
        The ``kind`` and ``meaning`` columns of the docs' variable table.
    doc_valid_note : str
        Appended to the valid range in the docs' valid-range table.
    """

    name: str
    vr: int
    enum: str
    type: str
    causality: str
    variability: str
    initial: str | None
    description: str
    start: str | None = None
    min: str | None = None
    max: str | None = None
    min_open: bool = False
    field: str | None = None
    getter: str | None = None
    c_start: str | None = None
    fmi2: bool = True
    fmi3_only: bool = False
    description_fmi3: str | None = None
    unit: str | None = None
    derivative_of: str | None = None
    dependencies: tuple[str, ...] | None = None
    dependencies_fmi3: tuple[str, ...] | None = None
    dependencies_kind: tuple[str, ...] | None = None
    initial_dependencies: tuple[str, ...] | None = None
    event_indicator: bool = False
    twin: bool = False
    description_twin: str | None = None
    doc_kind: str = ""
    doc_meaning: str = ""
    doc_valid_note: str = ""


def _parameter(name: str, vr: int, enum: str, type_: str, description: str, start: str,
               lo: str | None, hi: str | None, **more) -> Variable:
    """A fixed parameter stored in ModelData under its own name."""
    return Variable(name, vr, enum, type_, "parameter", more.pop("variability", "fixed"),
                    "exact", description, start=start, min=lo, max=hi, field=name, **more)


def _calculated(name: str, vr: int, description: str, deps: tuple[str, ...], **more) -> Variable:
    """A calculated parameter stored in ModelData (model_update_derived)."""
    return Variable(name, vr, name.upper(), "Real", "calculatedParameter", "fixed", "calculated",
                    description, field=name, initial_dependencies=deps, twin=True,
                    doc_kind="calculated parameter", **more)


def _output(name: str, vr: int, enum: str, type_: str, variability: str, description: str,
            **more) -> Variable:
    """An output, an initial unknown without dependencies unless given."""
    more.setdefault("dependencies", ())
    more.setdefault("dependencies_fmi3", more["dependencies"])
    more.setdefault("initial_dependencies", ())
    return Variable(name, vr, enum, type_, "output", variability, "calculated", description,
                    **more)


_SENS = ("derivative of the state at the end t1 of the last doStep w.r.t. its start t0 (the "
         "variational equations with the saltation matrix at every wall event); computed only "
         "with sensitivities = true in Co-Simulation, else J = identity, S = 0")
_SENS_DOC = "{d}: t0, t1 the start and end of the last doStep"
_WORK_BOUND = ("bound on {what} one communication step, per unit of time advanced (at least "
               "one unit)")

#: What decides the contact mode at the start (model_initialize_state): in_contact's dependence.
#: (der(u) is v0, or 0 sticking, which needs v0 = 0: it depends on v0 alone.)
_MODE_DECIDERS = ("nu", "Omega", "sigma", "wall", "u0", "v0", "F_ext", "u_wall", "v_wall")
#: ... and of the contact law's force: F_contact and der(v) at the start.
_CONTACT_DEPS = ("nu", "Omega", "sigma", "Gamma", "wall", "u0", "v0", "contact", "alpha_hc",
                 "F_ext", "u_wall", "v_wall")
#: der(v) and F_contact on (u, v, F_ext, u_wall, v_wall): the Hertz laws make u, v, u_wall's
#: factors change with the state, and v_wall's (Hunt-Crossley's damping of the velocity relative
#: to the wall; the holding force's -nu v_wall while sticking); F_ext's is 1 or 0 (sticking) per
#: contact mode.
_RHS_DEPS = ("u", "v", "F_ext", "u_wall", "v_wall")
_RHS_KINDS = ("dependent", "dependent", "discrete", "dependent", "dependent")

#: Every variable, in value-reference order.
VARIABLES: tuple[Variable, ...] = (
    # The defaults are the paper's Figure 9 case: (alpha, gamma) = (0.99, 0.01), r = 0.9,
    # Gamma = 10.
    _parameter("nu", 0, "NU", "Real", "damping nu = 2 pi c/(m omega), eq (3)",
               "4.605170185988091", "0", "1e6", twin=True, doc_kind="parameter",
               doc_meaning="damping"),
    _parameter("Omega", 1, "OMEGA", "Real",
               "natural frequency over drive frequency, times 2 pi "
               "(Omega^2 = 4 pi^2 k/(m omega^2))",
               "0.3059238689620112", "1e-6", "1e4",
               description_fmi3="natural frequency over drive frequency, times 2 pi",
               twin=True, doc_kind="parameter",
               doc_meaning="natural frequency (the defaults are Figure 9's (alpha, gamma) = "
                           "(0.99, 0.01))"),
    _parameter("sigma", 2, "SIGMA", "Real",
               "bifurcation parameter sigma = (F - F_g)/F_g, eq (5); tunable between steps",
               "0.2", "-1", "1e6", min_open=True, variability="tunable", twin=True,
               doc_kind="parameter, **tunable**",
               doc_meaning="bifurcation parameter (F - F_g)/F_g; a change between steps acts "
                           "from that time on, the state is carried (quasi-static scans)"),
    _parameter("r", 3, "R", "Real",
               "restitution coefficient: rigid v -> -r v; compliant linear wall v -> r v on "
               "entering (footnote 2); not used by the Hertz and Hunt-Crossley laws (no "
               "velocity jump)",
               "0.9", "0", "1", twin=True,
               description_twin="restitution coefficient: rigid v -> -r v; compliant v -> r v "
                                "on entering (footnote 2)",
               doc_kind="parameter", doc_meaning="restitution, in [0, 1]"),
    _parameter("Gamma", 4, "GAMMA", "Real",
               "wall stiffness ratio Gamma = kappa^2/Omega^2 (compliant wall)",
               "10", "0", "1e16", twin=True, doc_kind="parameter",
               doc_meaning="wall stiffness ratio kappa^2/Omega^2",
               doc_valid_note=" (> 0 with the compliant wall), and kappa = sqrt(Gamma) Omega "
                              "<= 1e8"),
    _parameter("wall", 5, "WALL", "Integer", "wall model: 0 none, 1 compliant, 2 rigid",
               "1", "0", "2", c_start="WALL_COMPLIANT", twin=True,
               doc_kind="Integer parameter", doc_meaning="0 none, 1 compliant, 2 rigid"),
    # Start at rest, u = -1: valid for every wall model.
    _parameter("u0", 6, "U0", "Real", "position at the start time (rest position -1, wall at 0)",
               "-1", "-1e6", "1e6", twin=True, doc_kind="parameter",
               doc_meaning="position at the start time"),
    _parameter("v0", 7, "V0", "Real", "velocity at the start time", "0", "-1e6", "1e6",
               twin=True, doc_kind="parameter", doc_meaning="velocity at the start time"),
    _parameter("rtol", 8, "RTOL", "Real", "CVODE relative tolerance", "1e-12", "1e-15", "0.1",
               description_fmi3="CVODE relative tolerance (Co-Simulation)", twin=True,
               doc_kind="parameter",
               doc_meaning="CVODE relative tolerance (the importer's tolerance, if given, can "
                           "only tighten it)"),
    _parameter("atol", 9, "ATOL", "Real", "CVODE absolute tolerance", "1e-14", "1e-30", "0.01",
               description_fmi3="CVODE absolute tolerance (Co-Simulation)", twin=True,
               doc_kind="parameter", doc_meaning="CVODE absolute tolerance"),
    _calculated("F_g", 10, "grazing forcing amplitude, eq (5)", ("nu", "Omega"),
                doc_meaning="grazing forcing amplitude, eq (5)"),
    _calculated("phi", 11, "forcing phase, eq (5)", ("nu", "Omega"), unit="rad",
                doc_meaning="forcing phase, eq (5)"),
    _calculated("kappa", 12, "wall frequency kappa = sqrt(Gamma) Omega, eq (40)",
                ("Omega", "Gamma"), doc_meaning="wall frequency sqrt(Gamma) Omega, eq (40)"),
    _output("u", 13, "U", "Real", "continuous", "position (wall at u = 0)", field="u",
            dependencies=("u",), dependencies_fmi3=("u",), dependencies_kind=("constant",),
            initial_dependencies=("u0",),
            twin=True, doc_kind="output", doc_meaning="position (wall at u = 0)"),
    _output("v", 14, "V", "Real", "continuous", "velocity", field="v",
            dependencies=("v",), dependencies_fmi3=("v",), dependencies_kind=("constant",),
            initial_dependencies=("v0",),
            twin=True, doc_kind="output", doc_meaning="velocity"),
    _output("impacts", 15, "IMPACTS", "Integer", "discrete",
            "wall entries (impacts) since the start time", field="impacts", twin=True,
            doc_kind="Integer output", doc_meaning="wall entries since the start time"),
    _output("in_contact", 16, "IN_CONTACT", "Boolean", "discrete",
            "true while inside the compliant wall or sticking on the rigid one",
            getter="get_in_contact",
            initial_dependencies=_MODE_DECIDERS,
            twin=True, doc_kind="Boolean output",
            doc_meaning="inside the compliant wall, or sticking on the rigid one"),
    _parameter("contact", 17, "CONTACT", "Integer",
               "contact law of the compliant wall: 0 linear kappa^2 u with entry jump v -> r v "
               "(the paper), 1 Hertz kappa^2 u^(3/2), 2 Hunt-Crossley kappa^2 u^(3/2) (1 + "
               "alpha_hc v); 1 and 2 enter without a velocity jump (r unused)",
               "0", "0", "2", c_start="CONTACT_LINEAR", doc_kind="Integer parameter",
               doc_meaning="contact law of the compliant wall: 0 linear, 1 Hertz, "
                           "2 Hunt-Crossley"),
    # Hunt-Crossley: an impact at speed v_in leaves roughly r ~ 1 - (2/3) alpha v_in, so 0.15
    # gives r ~ 0.9 at v_in ~ 1.
    _parameter("alpha_hc", 18, "HC_ALPHA", "Real",
               "Hunt-Crossley damping factor: dissipative force kappa^2 alpha_hc u^(3/2) v "
               "(contact = 2)",
               "0.15", "0", "1e6", doc_kind="parameter",
               doc_meaning="Hunt-Crossley damping factor"),
    Variable("der(u)", 19, "DER_U", "Real", "local", "continuous", "calculated",
             "du/dt (Model Exchange)", getter="get_der_u", derivative_of="u",
             dependencies=("v", "v_wall"), dependencies_kind=("discrete", "discrete"),
             # v0, or v_wall sticking, which needs v0 = v_wall: v0 alone
             initial_dependencies=("v0",),
             doc_kind="local (Model Exchange)", doc_meaning="du/dt"),
    Variable("der(v)", 20, "DER_V", "Real", "local", "continuous", "calculated",
             "dv/dt (Model Exchange)", getter="get_der_v", derivative_of="v",
             dependencies=_RHS_DEPS, dependencies_kind=_RHS_KINDS,
             initial_dependencies=_CONTACT_DEPS,
             doc_kind="local (Model Exchange)", doc_meaning="dv/dt"),
    Variable("wall_indicator", 21, "WALL_INDICATOR", "Real", "local", "continuous", "calculated",
             "event indicator: u (the wall), or the net wall force while sticking on the rigid "
             "wall", getter="get_indicator", fmi2=False, event_indicator=True,
             dependencies=("u", "F_ext", "u_wall", "v_wall"),
             dependencies_kind=("discrete", "discrete", "discrete", "discrete"),
             doc_kind="local (FMI 3.0 Model Exchange)",
             doc_meaning="the event indicator g0: u, or the net wall force while sticking"),
    Variable("time", 22, "TIME", "Real", "independent", "continuous", None,
             "time (forcing period 1)", getter="get_time", fmi2=False, fmi3_only=True,
             doc_kind="independent (FMI 3.0)", doc_meaning="time (forcing period 1)"),
    Variable("F_ext", 23, "F_EXT", "Real", "input", "continuous", None,
             "external force added to the right-hand side: u'' + nu u' + Omega^2 (u + 1) "
             "[+ contact] = forcing + F_ext; held over a step unless given input derivatives "
             "(order 1: a linear ramp); |F_ext| <= 1e12",
             start="0", min="-1e12", max="1e12", field="F_ext", getter="get_F_ext",
             description_fmi3="external force added to the right-hand side; held over a "
                              "Co-Simulation step",
             doc_kind="**input**", doc_meaning="external force added to the right-hand side",
             doc_valid_note="; its derivative \\|.\\| <= 1e12"),
    Variable("u_wall", 24, "U_WALL", "Real", "input", "continuous", None,
             "wall position (contact when u > u_wall): the compliant spring acts on u - u_wall, "
             "restitution on the velocity relative to the wall (du_wall/dt: the input v_wall, or "
             "this input's derivative where one is given); a wall that jumps into the mass "
             "between steps: compliant - the mass is inside (contact, no jump); rigid - the mass "
             "is placed on the wall and the impact law applied to its relative velocity; "
             "|u_wall| <= 1e6",
             start="0", min="-1e6", max="1e6", field="u_wall", getter="get_u_wall",
             description_fmi3="wall position (contact when u > u_wall): the compliant spring "
                              "acts on u - u_wall, restitution on the velocity relative to the "
                              "wall (its velocity v_wall); a wall that jumps into the mass "
                              "between steps: compliant - the mass is inside (contact, no "
                              "jump); rigid - the mass is placed on the wall and the impact law "
                              "applied to its relative velocity",
             doc_kind="**input**", doc_meaning="wall position: contact when u > u_wall",
             doc_valid_note="; its derivative \\|.\\| <= 1e6"),
    _output("F_contact", 25, "F_CONTACT", "Real", "continuous",
            "the wall's force on the mass, repulsive positive (the mass feels -F_contact): the "
            "contact law's force in the compliant wall, the holding force while sticking on the "
            "rigid wall, 0 in flight (rigid impacts are impulses: see v_impact)",
            getter="get_contact_force",
            dependencies=_RHS_DEPS,
            dependencies_fmi3=_RHS_DEPS,
            dependencies_kind=_RHS_KINDS,
            initial_dependencies=_CONTACT_DEPS,
            description_fmi3="the wall's force on the mass, repulsive positive: the contact "
                             "law's force in the compliant wall, the holding force while "
                             "sticking on the rigid wall, 0 in flight",
            doc_kind="output",
            doc_meaning="the wall's force on the mass, repulsive positive (the mass feels "
                        "-F_contact): the contact law's force in the compliant wall, the "
                        "holding force while sticking on the rigid wall, 0 in flight"),
    _output("v_impact", 26, "V_IMPACT", "Real", "discrete",
            "velocity relative to the wall at the last wall entry, before the jump (0 before "
            "the first)", field="v_impact", doc_kind="output",
            doc_meaning="velocity relative to the wall at the last wall entry, before the jump "
                        "(0 before the first)"),
    _output("t_impact", 27, "T_IMPACT", "Real", "discrete",
            "time of the last wall entry (0 before the first; see impacts)", field="t_impact",
            doc_kind="output", doc_meaning="time of the last wall entry (0 before the first)"),
    # CVODE needs >= 20 steps per unit time (its maximal step 0.05) and ~100-1000 at the
    # defaults; chatter ends in sticking after ~100 impacts.
    _parameter("max_events_per_time", 28, "MAX_EVENTS", "Real",
               _WORK_BOUND.format(what="the wall events of") + "; exceeding it is an error naming "
               "this limit", "1e5", "1", "1e9",
               description_fmi3=_WORK_BOUND.format(what="the wall events of"),
               doc_kind="parameter",
               doc_meaning="bound on the wall events of one step, per unit of time advanced"),
    _parameter("max_steps_per_time", 29, "MAX_STEPS", "Real",
               _WORK_BOUND.format(what="CVODE's steps in") + "; exceeding it is an error naming "
               "this limit", "2e5", "1", "1e9",
               description_fmi3=_WORK_BOUND.format(what="CVODE's steps in"),
               doc_kind="parameter",
               doc_meaning="bound on CVODE's steps in one step, per unit of time advanced"),
    _parameter("sensitivities", 30, "SENSITIVITIES", "Boolean",
               "integrate the derivatives J_uu ... S_v of (u, v) at the end of each doStep "
               "w.r.t. (u, v) at its start and w.r.t. sigma, alongside the state (no cost when "
               "false)", "false", None, None, c_start="0", doc_kind="Boolean parameter",
               doc_meaning="integrate the derivatives J, S below (no cost when false)"),
    _parameter("solver", 31, "SOLVER", "Integer",
               "0: CVODE (any contact law); 1: the closed-form solution of the piecewise-linear "
               "ODE (exact propagation on each side of the wall, certified crossing search; "
               "linear contact law only: contact = 1, 2 with solver = 1 is an error)",
               "0", "0", "1", c_start="SOLVER_CVODE", doc_kind="Integer parameter",
               doc_meaning="0 CVODE; 1 the closed form (linear contact law only)"),
    _output("J_uu", 32, "J_UU", "Real", "discrete", "du(t1)/du(t0): " + _SENS,
            getter="get_J_uu", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="du(t1)/du(t0)")),
    _output("J_uv", 33, "J_UV", "Real", "discrete", "du(t1)/dv(t0): " + _SENS,
            getter="get_J_uv", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="du(t1)/dv(t0)")),
    _output("J_vu", 34, "J_VU", "Real", "discrete", "dv(t1)/du(t0): " + _SENS,
            getter="get_J_vu", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="dv(t1)/du(t0)")),
    _output("J_vv", 35, "J_VV", "Real", "discrete", "dv(t1)/dv(t0): " + _SENS,
            getter="get_J_vv", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="dv(t1)/dv(t0)")),
    _output("S_u", 36, "S_U", "Real", "discrete", "du(t1)/dsigma: " + _SENS,
            getter="get_S_u", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="du(t1)/dsigma")),
    _output("S_v", 37, "S_V", "Real", "discrete", "dv(t1)/dsigma: " + _SENS,
            getter="get_S_v", doc_kind="output",
            doc_meaning=_SENS_DOC.format(d="dv(t1)/dsigma")),
    Variable("v_wall", 38, "V_WALL", "Real", "input", "continuous", None,
             "wall velocity du_wall/dt: restitution, the contact laws and sticking act on the "
             "velocity relative to the wall; in Co-Simulation the wall moves over a step as "
             "u_wall + v_wall (t - t0) from its value u_wall at the step's start t0 (an FMI 2.0 "
             "input derivative of u_wall, where one is given, takes its place); in Model "
             "Exchange the importer sets u_wall and v_wall together; |v_wall| <= 1e6",
             start="0", min="-1e6", max="1e6", field="v_wall", getter="get_v_wall",
             description_fmi3="wall velocity du_wall/dt: restitution, the contact laws and "
                              "sticking act on the velocity relative to the wall; in "
                              "Co-Simulation the wall moves over a step as u_wall + v_wall "
                              "(t - t0) from its value u_wall at the step's start t0; in Model "
                              "Exchange the importer sets u_wall and v_wall together",
             doc_kind="**input**",
             doc_meaning="wall velocity: the impact law and the contact laws act on v - v_wall; "
                         "in Co-Simulation the wall moves as u_wall + v_wall (t - t0) over a "
                         "step"),
)

#: Limits the FMU checks that belong to no variable (fmu_core.h: CORE_MAX_TIME,
#: CORE_MAX_STATE): the last rows of the docs' valid-range table.
OTHER_LIMITS: tuple[tuple[str, str], ...] = (
    ("times (start, t + h, ME time)",
     "\\|t\\| <= 1e9 (beyond, a period is below a double's resolution of t)"),
    ("Model Exchange states", "\\|u\\|, \\|v\\| <= 1e15"),
)

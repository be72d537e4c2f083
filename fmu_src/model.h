/*
 * ImpactOscillator: the physics interface.
 *
 * The model is the non-dimensional driven oscillator of Molenaar, de Weger & van de Water (2001),
 * eqs (3), (5), (40), (53):
 *
 *     u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 u in contact] = (1 + sigma) F_g cos(2 pi t + phi)
 *
 * with F_g, phi from (5) so that the wall-free periodic orbit grazes u = 0 at t = n for sigma = 0.
 *
 * Everything the model knows lives in model.c: parameters and derived quantities, derivatives,
 * Jacobian, event indicators, the jumps at the wall and after input jumps, and what the FMI core
 * asks of it (the checks of a parameter set or a restored state, the input ramps, the computed
 * outputs: the last block below). The steppers (stepper.h: solver_cvode.c, closed_form.c)
 * integrate it and sens.c carries its derivatives; the FMI core (fmu_core.h) calls the model
 * for everything physical and holds no physics itself; fmi2.c and fmi3.c are type glue.
 * The value references (the variable table's side) are in fmu_vars.h.
 * Time inside the model is *local*: tau = t - origin with an integer origin, so the forcing
 * phase cos(2 pi tau + phi) keeps full precision after 10^6 periods.
 */
#ifndef IMPACT_MODEL_H
#define IMPACT_MODEL_H

#include <stddef.h>

#define MODEL_IDENTIFIER ImpactOscillator
#define MODEL_GUID "{6c1f8a52-3d0e-4b8e-9a57-1e0f0b7c2a11}"

typedef enum { WALL_NONE = 0, WALL_COMPLIANT = 1, WALL_RIGID = 2 } WallKind;

/* Contact law of the compliant wall (force on the mass at depth u > 0, velocity v):
 * LINEAR kappa^2 u (the paper's (40)), HERTZ kappa^2 u^{3/2}, HUNT_CROSSLEY
 * kappa^2 u^{3/2} (1 + alpha_hc v). The entry jump v -> r v belongs to the linear law only. */
typedef enum { CONTACT_LINEAR = 0, CONTACT_HERTZ = 1, CONTACT_HUNT_CROSSLEY = 2 } ContactLaw;

/* The discrete state. CONTACT: inside the compliant wall. STICK: resting on the rigid wall after
 * chatter, held there while the net force pushes into it. */
typedef enum { MODE_FREE = 0, MODE_CONTACT = 1, MODE_STICK = 2 } ContactMode;

/* Number of event indicators: g[0] the wall (or, when sticking, the net wall force), g[1] the
 * velocity (turning points: the grazing guard). */
#define MODEL_N_EVENTS 2

typedef struct {
    /* parameters */
    double nu, Omega, sigma, r, Gamma;
    int wall;
    double u0, v0, rtol, atol;
    int contact;      /* ContactLaw */
    double alpha_hc;  /* Hunt-Crossley damping factor */
    /* calculated parameters, kept consistent by model_update_derived() */
    double F_g, phi, kappa, Omega2, kappa2;
    /* continuous state at the current local time */
    double u, v;
    /* discrete state */
    int mode;
    int impacts;
    /* Inputs (ports): F_ext and u_wall are the values at local time in_tau; dF_ext and du_wall
     * their ramps' slopes over a Co-Simulation step (FMI 2.0 input derivatives, or v_wall: 0 =
     * held over the step): F(tau) = F_ext + dF_ext (tau - in_tau), w(tau) = u_wall + du_wall
     * (tau - in_tau). v_wall: the input wall velocity (model_wall_velocity). */
    double F_ext, u_wall, dF_ext, du_wall, in_tau;
    double v_wall;
    /* The last wall entry: velocity relative to the wall before the jump, and absolute time. */
    double v_impact, t_impact;
    /* Integer origin of local time (absolute t = origin + tau), kept equal to the stepper's
     * clock's (stepper.h). */
    double origin;
    /* Bounds on the work of one doStep, per unit of time advanced (counted as at least one
     * unit, so a doStep shorter than a period gets a whole unit's budget); the solver also caps
     * a doStep at SOLVER_MAX_STEPS_PER_CALL steps (solver_cvode.h). */
    double max_events_per_time, max_steps_per_time;
    /* Sensitivities (sens.h) and the solver (stepper.h): parameters, and the
     * derivatives of the state w.r.t. the state at the start of the current doStep (sJ) and
     * w.r.t. sigma (sS). Part of the FMU state. */
    int sensitivities; /* Boolean: integrate sJ, sS */
    int solver;        /* SOLVER_CVODE or SOLVER_CLOSED_FORM */
    double sJ[2][2], sS[2];
} ModelData;

typedef enum { SOLVER_CVODE = 0, SOLVER_CLOSED_FORM = 1 } SolverKind;

/* What an event did, so that the solver knows whether to re-initialise. */
typedef enum { EVENT_NONE = 0, EVENT_JUMP = 1 } EventResult;

void model_set_defaults(ModelData *m);
void model_update_derived(ModelData *m);

/* Checks the parameters together (e.g. Gamma with a compliant wall), at the end of
 * initialisation; returns NULL if fine. */
const char *model_check_consistency(const ModelData *m, char *buf, size_t n);

/* Sets the discrete state from (u0, v0) at the start time tau0. */
void model_initialize_state(ModelData *m, double tau0);

/* Net force pushing into the wall at u = v = 0 (positive: pushes into the wall). */
double model_wall_force(const ModelData *m, double tau);

void model_derivatives(const ModelData *m, double tau, const double y[2], double dy[2]);
void model_jacobian(const ModelData *m, double tau, const double y[2], double J[2][2]);
void model_event_indicators(const ModelData *m, double tau, const double y[2],
                            double g[MODEL_N_EVENTS]);
void model_root_directions(const ModelData *m, int dir[MODEL_N_EVENTS]);

/* Applies the event of indicator `which` found at tau with state y (updated in place). */
EventResult model_event_update(ModelData *m, double tau, double y[2], int which);

/* True when, at a turning point (g[1] = 0) reached at state y, the wall indicator has the sign
 * of the other side: a crossing pair was stepped over and must be located. */
int model_missed_crossing(const ModelData *m, double tau, const double y[2]);

/* True where the mode must change at once, without a crossing (a sticking mass whose
 * holding force has vanished, e.g. after sigma was changed). */
int model_release_now(ModelData *m, double tau);

/* Model Exchange: the importer integrates (u, v) and watches MODEL_N_ME_EVENTS indicators (the
 * wall indicator g0 only: the grazing guard g1 is the importer's business in ME). At an event
 * (importer found a sign change of g0, state y at local time tau), applies what the mode's
 * sign of g0 calls for: the wall's jump for a state within the event tolerance of the wall; for
 * any other state the mode it is in, its values kept (never a silent move). */
#define MODEL_N_ME_EVENTS 1
/* Model Exchange's continuous states: (u, v). */
#define MODEL_N_STATES 2
void model_get_states(const ModelData *m, double x[MODEL_N_STATES]);
void model_set_states(ModelData *m, const double x[MODEL_N_STATES]);
/* The event tolerance of Model Exchange: a state within this distance of the wall (|u - w|, and
 * |v - w'| for a sticking mass) is one the importer located at the wall, and the event's jump
 * places it there; 1e-6 of the model's unit of length (rest at -1, wall at 0), of |u_wall| for a
 * wall beyond 1 (docs/fmu.md, "Model Exchange keeps the importer's state"). */
#define MODEL_ME_EVENT_TOL 1e-6
double model_me_event_tolerance(const ModelData *m, double tau);
/* What model_me_event_update did. */
typedef enum {
    ME_EVENT_NONE = 0,   /* nothing: the state is on its mode's side of the wall */
    ME_EVENT_JUMP = 1,   /* the wall event within the tolerance: placed on the wall, jump applied */
    ME_EVENT_KEPT = 2,   /* a state far from the wall: kept, the mode it is in taken */
    ME_EVENT_INSIDE_RIGID = -1 /* a state far inside the rigid wall: no mode has it (refused) */
} MeEventResult;
MeEventResult model_me_event_update(ModelData *m, double tau, double y[2]);
/* Contact force of the compliant wall at depth d = u - w (> 0) and velocity d' relative to the
 * wall (0 for d <= 0 with the Hertz laws). */
double model_contact_force(const ModelData *m, double d, double dv);

/* Ports. The wall position w(tau), its velocity w' (the ramp's slope while one runs, else the
 * input v_wall), and the external force at local time tau. */
double model_wall_position(const ModelData *m, double tau);
double model_wall_velocity(const ModelData *m);
double model_external_force(const ModelData *m, double tau);
/* The wall's force on the mass (output F_contact), repulsive positive: the spring (contact law)
 * inside the compliant wall, the holding force while sticking on the rigid wall, 0 in flight. */
double model_contact_output(const ModelData *m, double tau);
/* Moves the local-time origin by k (an integer): the stepper's clock calls this when it
 * re-origins (stepper.c, clock_reorigin). */
void model_shift_time(ModelData *m, double k);
/* Applies the documented rule after the inputs jumped between steps (state y at local time tau,
 * updated in place): see model.c. Returns 1 if the mode or the state changed. */
int model_input_jump(ModelData *m, double tau, double y[2]);

/* -- exact partial derivatives (fmu_derivatives.c: fmi2/fmi3GetDirectionalDerivative,
 * fmi3GetAdjointDerivative) -- The knowns (columns) are the continuous states and the inputs; the
 * unknowns (rows) the right-hand side, the wall's force and the wall indicator. Each entry is the
 * partial derivative at the instance's contact mode and state now: the piecewise right-hand side
 * of that mode, differentiated (the mode itself changes only at events, so it has no partial). */
typedef enum {
    PK_U = 0, PK_V = 1, PK_F_EXT = 2, PK_U_WALL = 3, PK_V_WALL = 4, MODEL_N_KNOWNS = 5
} PartialKnown;
typedef enum {
    PU_DER_U = 0, PU_DER_V = 1, PU_F_CONTACT = 2, PU_WALL_INDICATOR = 3, MODEL_N_UNKNOWNS = 4
} PartialUnknown;
void model_partials(const ModelData *m, double tau, double P[MODEL_N_UNKNOWNS][MODEL_N_KNOWNS]);

/* -- the initial unknowns' partial derivatives (Initialization Mode) -- The knowns (columns) are
 * the Real parameters and inputs the InitialUnknowns depend on, the unknowns (rows) the Real
 * initial unknowns that depend on any (the others' rows are 0). m holds the state the start
 * values give at the start time tau0 (model_initialize_state): each entry is the partial of the
 * value read in Initialization Mode, with the contact mode that start decides (a start exactly on
 * a mode's boundary, e.g. at rest on the rigid wall, takes that mode's partials). */
typedef enum {
    IK_NU = 0, IK_OMEGA, IK_SIGMA, IK_GAMMA, IK_U0, IK_V0, IK_ALPHA_HC, IK_F_EXT, IK_U_WALL,
    IK_V_WALL, MODEL_N_INIT_KNOWNS
} InitKnown;
typedef enum {
    IU_F_G = 0, IU_PHI, IU_KAPPA, IU_U, IU_V, IU_DER_U, IU_DER_V, IU_F_CONTACT,
    MODEL_N_INIT_UNKNOWNS
} InitUnknown;
void model_initial_partials(const ModelData *m, double tau0,
                            double P[MODEL_N_INIT_UNKNOWNS][MODEL_N_INIT_KNOWNS]);

/* -- what the FMI core asks of the model (fmu_vars.c, fmu_snapshot.c, fmu_cs.c, fmu_core.c) -- */
/* Bounds on the input derivatives (slopes per unit time). */
#define MODEL_MAX_DF_EXT 1e12
#define MODEL_MAX_DU_WALL 1e6
/* Checks the quantities derived from several parameters (kappa, the forcing amplitude) of a
 * parameter set that is in use (after initialisation); returns NULL if fine, else buf. */
const char *model_check_derived(const ModelData *m, char *buf, size_t n);
/* Why a restored model state cannot be used (NULL: it can): contact mode against the wall
 * model, counters, finite and bounded states (|u|, |v| <= max_state), sensitivities, ramps and
 * impact record (times within 2 max_time); is_me: a Model Exchange state (no ramps). */
const char *model_check_restored(const ModelData *m, int is_me, double max_state,
                                 double max_time);
/* Folds the input ramps into the input values at local time tau (the reference point moves
 * to tau; the values there are unchanged). */
void model_rebase_inputs(ModelData *m, double tau);
/* 1 while an input is ramped (a nonzero input derivative). */
int model_has_ramps(const ModelData *m);
/* Co-Simulation, at a step's start (local time tau): a wall with velocity v_wall and no input
 * derivative of u_wall moves over the step as u_wall + v_wall (tau' - tau), the ramp an input
 * derivative v_wall would give. Returns 1 if a ramp began (the right-hand side changed). */
int model_begin_wall_ramp(ModelData *m, double tau);
/* After a step: the ramps end at tau (the inputs hold their values there until set again);
 * returns 1 if there were any (the right-hand side changed). */
int model_end_ramps(ModelData *m, double tau);
/* Computed outputs at local time tau: in_contact, the sensitivities (0..5: J_uu, J_uv, J_vu,
 * J_vv, S_u, S_v), der(u) and der(v) (i = 0, 1), the wall indicator g0, and F_contact -- with
 * inputs_jumped, that of the state the input-jump rule gives now (F_contact feeds through from
 * u_wall). */
double model_in_contact(const ModelData *m);
double model_sensitivity(const ModelData *m, int i);
double model_derivative(const ModelData *m, double tau, int i);
double model_wall_indicator(const ModelData *m, double tau);
double model_contact_output_now(const ModelData *m, double tau, int inputs_jumped);
/* The state and the outputs after a step are finite (|u|, |v| <= max_state). */
int model_outputs_finite(const ModelData *m, double tau, int inputs_jumped, double max_state);

#endif

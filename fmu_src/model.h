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
 * Everything the model knows lives in model.c (parameters, derivatives, Jacobian, event
 * indicators, event update, get/set); solver_cvode.c integrates it and fmi2_cs.c is the FMI glue.
 * Time inside the model is *local*: tau = t - origin with an integer origin, so the forcing
 * phase cos(2 pi tau + phi) keeps full precision after 10^6 periods.
 */
#ifndef IMPACT_MODEL_H
#define IMPACT_MODEL_H

#include <stddef.h>

#define MODEL_IDENTIFIER ImpactOscillator
#define MODEL_GUID "{6c1f8a52-3d0e-4b8e-9a57-1e0f0b7c2a11}"

/* The value references (enum ValueReference, VR_*), generated from fmu_src/variables.py. */
#include "variables.h"

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
     * their time derivatives (FMI 2.0 Co-Simulation input derivatives, 0 = held over the step):
     * F(tau) = F_ext + dF_ext (tau - in_tau), w(tau) = u_wall + du_wall (tau - in_tau). */
    double F_ext, u_wall, dF_ext, du_wall, in_tau;
    /* The last wall entry: velocity relative to the wall before the jump, and absolute time. */
    double v_impact, t_impact;
    /* Integer origin of local time (absolute t = origin + tau), kept equal to the solver's. */
    double origin;
    /* Bounds on the work of one doStep, per unit of time advanced (at least one unit; issue
     * 13.3); the solver also caps a doStep at SOLVER_MAX_STEPS_PER_CALL steps (solver.h). */
    double max_events_per_time, max_steps_per_time;
    /* Sensitivities (sens.h) and the solver (closed_form.h), issue 11: parameters, and the
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
 * sign of g0 calls for; returns 1 if the mode or the state changed. */
#define MODEL_N_ME_EVENTS 1
int model_me_event_update(ModelData *m, double tau, double y[2]);
/* Contact force of the compliant wall at depth d = u - w (> 0) and velocity d' relative to the
 * wall (0 for d <= 0 with the Hertz laws). */
double model_contact_force(const ModelData *m, double d, double dv);

/* Ports. The wall position w(tau), its velocity, and the external force at local time tau. */
double model_wall_position(const ModelData *m, double tau);
double model_wall_velocity(const ModelData *m);
double model_external_force(const ModelData *m, double tau);
/* The wall's force on the mass (output F_contact), repulsive positive: the spring (contact law)
 * inside the compliant wall, the holding force while sticking on the rigid wall, 0 in flight. */
double model_contact_output(const ModelData *m, double tau);
/* Moves the local-time origin by k (an integer): the solver calls this when it re-origins. */
void model_shift_time(ModelData *m, double k);
/* Applies the documented rule after the inputs jumped between steps (state y at local time tau,
 * updated in place): see model.c. Returns 1 if the mode or the state changed. */
int model_input_jump(ModelData *m, double tau, double y[2]);

#endif

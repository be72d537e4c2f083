#!/usr/bin/env python3
"""Mutation run: plant one realistic bug at a time and see whether the test suite notices.

Each mutant replaces one exact snippet of one file (C or Python) by a plausible wrong version --
a sign, a factor, a dropped term, a wrong branch, a missing re-initialisation -- the kind of bug
a careful person still writes.  For each mutant the working tree is copied to a temporary folder,
the snippet replaced, the FMU rebuilt there when a C file changed, and the mutant's tests run
against the copy.  A mutant is *killed* when a test fails, *survives* when all pass; a C mutant
that does not compile is *stillborn* (not counted).

On demand, not in CI (all 63: about 6 minutes one at a time, 3 with --jobs 2, on 2 cores):

    .venv/bin/python scripts/mutants.py                      # every mutant, 1 at a time
    .venv/bin/python scripts/mutants.py --only M03,M17       # some
    .venv/bin/python scripts/mutants.py --list               # the list
    .venv/bin/python scripts/mutants.py --markdown out.md    # also write the result table
    .venv/bin/python scripts/mutants.py --jobs 2             # two mutants at a time

The last result, with every survivor explained, is in TESTING.md.  ``tests/project/test_mutants_list.py``
(in CI) checks that every mutant's snippet still occurs exactly once, so the list cannot rot
silently when the code changes.
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutant:
    """One planted bug: ``find`` (exactly once in ``path``) becomes ``replace``."""

    id: str
    path: str
    find: str
    replace: str
    tests: tuple[str, ...]
    what: str

    @property
    def is_c(self) -> bool:
        return self.path.endswith((".c", ".h"))


def _m(id: str, path: str, find: str, replace: str, tests: str, what: str) -> Mutant:
    return Mutant(id, path, find, replace, tuple(ALSO_RUN.get(id, "").split() + tests.split()), what)


FMU_PORTS = ("tests/fmu/test_ports.py tests/fmu/test_ports_ramps.py "
             "tests/fmu/test_ports_wall_jumps.py")
EVENTS = "tests/fmu/test_events_total.py"
PHYS = "tests/fmu/test_physics.py"
SENS = "tests/fmu/test_sensitivities.py tests/harness/test_sensitivities.py"
CF = "tests/fmu/test_closed_form.py"
TRUTH = "tests/fmu/test_inputs_truth.py"
GUARD = "tests/fmu/test_grazing_guard.py"
DERIV = "tests/fmu/test_directional_derivatives.py"
INIT_DERIV = "tests/fmu/test_initial_derivatives.py"
ME_WALL = "tests/fmu/test_me_wall_memory.py"
WALL_VELOCITY = "tests/fmu/test_wall_velocity.py"
BASINS = "tests/harness/test_basins_kernel.py"
MEASURES = "tests/analysis/test_basin_measures.py"
CHART_RULES = "tests/analysis/test_chart_rules.py"
# mutants that only the independent-truth tests kill: those tests run first for them
ALSO_RUN = {i: TRUTH for i in ("M04", "M05", "M10", "M11", "M12", "M17", "M20", "M21", "M27", "M28",
                                "M52")}

MUTANTS: tuple[Mutant, ...] = (
    # -- fmu_src/model.c: the physics ------------------------------------------------------------
    _m("M01", "fmu_src/model.c", "y[1] = dw == 0.0 ? y[1] * m->r : dw + m->r * (y[1] - dw);",
       "y[1] = dw == 0.0 ? y[1] * m->r : dw + m->r * y[1];", FMU_PORTS,
       "compliant entry on a moving wall: restitution on the absolute, not the relative velocity"),
    _m("M02", "fmu_src/model.c", "y[1] = dw == 0.0 ? -m->r * vc : dw - m->r * vc; /* (11) */",
       "y[1] = dw == 0.0 ? -m->r * vc : -m->r * vc; /* (11) */", FMU_PORTS,
       "rigid impact on a moving wall: rebound not in the wall's frame"),
    _m("M03", "fmu_src/model.c", "static const double STICK_VELOCITY = 1e-9;",
       "static const double STICK_VELOCITY = 1e-3;", f"{EVENTS} {PHYS}",
       "chatter ends in sticking far too early"),
    _m("M04", "fmu_src/model.c", "    case MODE_STICK:\n        y[0] = beside_wall(w, -1.0);\n        y[1] = dw;",
       "    case MODE_STICK:\n        y[0] = beside_wall(w, -1.0);\n        y[1] = 0.0;", f"{FMU_PORTS} {EVENTS}",
       "release from sticking on a moving rigid wall at rest instead of with the wall's velocity"),
    _m("M05", "fmu_src/model.c", "return forcing(m, tau) + model_external_force(m, tau) - m->nu * model_wall_velocity(m) -",
       "return forcing(m, tau) + model_external_force(m, tau) -", FMU_PORTS,
       "net wall force without the damper on a moving wall (sticking/release decided wrongly)"),
    _m("M06", "fmu_src/model.c", "return (1.0 + m->sigma) * m->F_g * cos(2.0 * M_PI * tau + m->phi);",
       "return (1.0 + m->sigma) * m->F_g * cos(2.0 * M_PI * tau - m->phi);", PHYS,
       "forcing phase of (5) with the wrong sign"),
    _m("M07", "fmu_src/model.c", "m->phi = (m->F_g > 0.0) ? acos((m->Omega2 - w2) / m->F_g) : 0.0;",
       "m->phi = (m->F_g > 0.0) ? asin((m->Omega2 - w2) / m->F_g) : 0.0;", PHYS,
       "phase of (5) from the wrong inverse function"),
    _m("M08", "fmu_src/model.c", "m->kappa2 = m->Gamma * m->Omega2;", "m->kappa2 = m->Gamma * m->Omega;", PHYS,
       "wall stiffness kappa^2 = Gamma Omega (not Omega^2)"),
    _m("M09", "fmu_src/model.c", "        m->impacts += 1;", "        m->impacts += (m->wall == WALL_RIGID) + 1;",
       f"{PHYS} {EVENTS}", "rigid impacts counted twice"),
    _m("M10", "fmu_src/model.c", "m->v_impact = y[1] - dw;", "m->v_impact = y[1];", FMU_PORTS,
       "v_impact absolute instead of relative to the wall"),
    _m("M11", "fmu_src/model.c", "m->mode = MODE_FREE; /* the wall went away: y[1] is kept */",
       "y[1] = dw; m->mode = MODE_FREE; /* the wall went away: y[1] is kept */", FMU_PORTS,
       "a sticking mass left by a wall that jumps away takes the wall's new velocity"),
    _m("M52", "fmu_src/model.c", "m->mode = MODE_FREE; /* the wall went away: y[1] is kept */",
       "y[1] = 0.0; m->mode = MODE_FREE; /* the wall went away: y[1] is kept */", FMU_PORTS,
       "a sticking mass left by a wall that jumps away is left at rest"),
    _m("M12", "fmu_src/model.c", "if (y[1] - dw > 0.0) model_event_update(m, tau, y, 0); /* an impact */",
       "if (y[1] > 0.0) model_event_update(m, tau, y, 0); /* an impact */", FMU_PORTS,
       "wall jumping into the mass: impact decided on the absolute velocity"),
    _m("M13", "fmu_src/model.c", "const double h = m->kappa2 * d * sqrt(d); /* kappa^2 d^{3/2} */",
       "const double h = m->kappa2 * d; /* kappa^2 d^{3/2} */", "tests/fmu/test_contact_laws.py",
       "Hertz law linear"),
    _m("M14", "fmu_src/model.c", "return m->contact == CONTACT_HERTZ ? h : h * (1.0 + m->alpha_hc * dv);",
       "return m->contact == CONTACT_HERTZ ? h : h * (1.0 - m->alpha_hc * dv);", "tests/fmu/test_contact_laws.py",
       "Hunt-Crossley damping with the wrong sign (energy gain)"),
    _m("M15", "fmu_src/model.c", "    J[1][1] = -m->nu;", "    J[1][1] = m->nu;", f"{PHYS} {EVENTS}",
       "the analytic Jacobian CVODE's Newton iteration uses has the damping's sign wrong"),
    # -- fmu_src/sens.c: derivatives -------------------------------------------------------------
    _m("M16", "fmu_src/sens.c", "DR = -before->r; /* rigid impact */", "DR = before->r; /* rigid impact */", SENS,
       "saltation of a rigid impact without the sign of v -> -r v"),
    _m("M17", "fmu_src/sens.c", "if (after->mode == MODE_STICK) DR = 0.0;", "if (after->mode == MODE_STICK) DR = 1.0;",
       SENS, "a period that sticks does not forget the start state (J must be 0)"),
    _m("M18", "fmu_src/sens.c", "X[1][0] += (fp[1] - DR * fm[1]) / hdot;", "X[1][0] += (fp[1] - fm[1]) / hdot;",
       SENS, "saltation matrix without the jump's factor on the pre-event field"),
    _m("M19", "fmu_src/sens.c", "dy[7] = A[1][0] * y[6] + A[1][1] * y[7] + dforce_dsigma(m, tau);",
       "dy[7] = A[1][0] * y[6] + A[1][1] * y[7];", SENS, "d/dsigma without the forcing's own derivative"),
    _m("M20", "fmu_src/sens.c", "    if (m->mode == MODE_STICK) return 0.0;\n    return m->F_g",
       "    return m->F_g", SENS, "d/dsigma of the forcing acts while the wall holds the mass"),
    # -- fmu_src/closed_form.c: the exact solver -------------------------------------------------
    _m("M21", "fmu_src/closed_form.c",
       "            mode_init(&modes[0], m, 0); /* tref moves with the origin (the ports) */\n"
       "            mode_init(&modes[1], m, 1);\n", "", f"{FMU_PORTS} {CF}",
       "contact modes not re-initialised after the re-origin (ramped ports then use a stale reference time)"),
    _m("M22", "fmu_src/closed_form.c", "md->b = 0.5 * m->nu;", "md->b = m->nu;", CF, "damping rate nu instead of nu/2"),
    _m("M23", "fmu_src/closed_form.c", "md->amp = 1.0 + m->sigma;", "md->amp = m->sigma;", CF,
       "forcing amplitude sigma F_g instead of (1 + sigma) F_g"),
    _m("M24", "fmu_src/closed_form.c", "if (dL * dR < 0.0 && monotone_rate) { /* one turning point: split there */",
       "if (dL * dR > 0.0 && monotone_rate) { /* one turning point: split there */", f"{CF} {EVENTS}",
       "certified crossing search splits where there is no turning point"),
    # -- fmu_src/solver_cvode.c: CVODE driver ----------------------------------------------------
    _m("M25", "fmu_src/solver_cvode.c", "return (g != 0.0 && fabs(g) < ROOT_FLOOR) ? copysign(ROOT_FLOOR, g) : g;",
       "return g;", f"{GUARD} {EVENTS}", "root values not floored (SUNDIALS' glo*ghi underflow loses shallow crossings)"),
    _m("M26", "fmu_src/solver_cvode.c", "return dir[0] > 0 ? g[0] > 0.0 : g[0] < 0.0;", "return 0;",
       f"{GUARD} {EVENTS} {PHYS}", "a step ending on the wrong side of the wall is never rescued"),
    _m("M27", "fmu_src/solver_cvode.c", "if (model_release_now(m, k->tau)) k->events++;",
       "if (0) k->events++;", f"{EVENTS} {FMU_PORTS}", "a sticking mass is not released at a restart"),
    # -- fmu_src/model.c: the core's bookkeeping of the inputs (model_end_ramps, after each doStep) --
    _m("M28", "fmu_src/model.c",
       "    if (m->dF_ext == 0.0 && m->du_wall == 0.0) return 0;\n    model_rebase_inputs(m, tau);\n",
       "    if (m->dF_ext == 0.0 && m->du_wall == 0.0) return 0;\n", FMU_PORTS,
       "after a ramp the inputs snap back to their start-of-step values instead of holding the end values"),
    # -- harness: classification, Lyapunov exponents, sampling, sweeps ---------------------------
    _m("M29", "harness/dynamics/maps/classify.py", "    threshold = tol * (1.0 + amplitude)\n", "    threshold = tol\n",
       "tests/harness/test_classify.py", "periodicity threshold not scaled with the orbit's size"),
    _m("M30", "harness/dynamics/maps/classify.py", "return OrbitClass(m, int(imp[n - m :].sum()), residual)",
       "return OrbitClass(m, int(imp[n - 1]), residual)", "tests/harness/test_classify.py",
       "impacts per orbit period taken from the last forcing period only"),
    _m("M31", "harness/dynamics/maps/classify.py", "if residual <= threshold and np.array_equal(imp[m:], imp[:-m]):",
       "if residual <= threshold:", "tests/harness/test_classify.py",
       "period accepted although the impact sequence does not repeat"),
    _m("M32", "harness/dynamics/maps/classify.py", "    threshold = tol * (1.0 + max(np.ptp(u), np.ptp(v)))\n",
       "    threshold = tol\n", "tests/harness/test_classify.py tests/harness/test_sweeps.py",
       "still-settling test not scaled with the orbit's size"),
    _m("M33", "harness/dynamics/maps/lyapunov.py", "Q, R = np.linalg.qr(J @ Q)", "Q, R = np.linalg.qr(Q @ J)",
       "tests/harness/test_lyapunov.py", "QR accumulation with the product transposed"),
    _m("M34", "harness/dynamics/maps/lyapunov.py", "err = means.std(axis=0, ddof=1) / math.sqrt(b)",
       "err = means.std(axis=0, ddof=1)", "tests/harness/test_lyapunov.py",
       "standard error of the exponents without the 1/sqrt(blocks)"),
    _m("M35", "harness/dynamics/maps/sampling.py", "sim.start(params, start_period + theta, state0)",
       "sim.start(params, start_period, state0)", "tests/harness/test_oracle.py tests/harness/test_fmi.py",
       "the section phase theta ignored at the start"),
    _m("M36", "harness/dynamics/maps/jacobian.py",
       "return (one_period(sim, params, state + dx, t0) - one_period(sim, params, state - dx, t0)) / (2.0 * step)",
       "return (one_period(sim, params, state + dx, t0) - one_period(sim, params, state - dx, t0)) / step",
       "tests/harness/test_jacobian.py", "central difference divided by h, not 2h"),
    _m("M37", "harness/runs/tasks.py",
       "state0 = (value, state0[1]) if task.param == INITIAL_STATE[0] else (state0[0], value)",
       "state0 = (state0[0], value) if task.param == INITIAL_STATE[0] else (value, state0[1])",
       "tests/harness/test_basins.py tests/harness/test_sweeps.py", "a basin scan's u0 and v0 swapped"),
    _m("M38", "harness/runs/sweeps.py", "start = (float(second), state0[1]) if spec.scan_param == INITIAL_STATE[0] "
       "else (state0[0], float(second))", "start = state0", "tests/harness/test_basins.py",
       "a scan over v0 runs every row from the first v0"),
    _m("M39", "harness/dynamics/attractors/identity.py", "return float(max(d.min(axis=1).max(), d.min(axis=0).max()))",
       "return float(d.min(axis=1).max())", "tests/harness/test_basins.py",
       "orbit distance one-sided (a sub-orbit matches a larger one)"),
    _m("M40", "harness/runs/tasks.py", "    return state[0] > u_wall or (state[0] == u_wall and state[1] > 0.0)",
       "    return state[0] > u_wall", "tests/harness/test_basins.py",
       "a start on the rigid wall moving into it is not an invalid start"),
    # -- mapcheck: the paper's maps and the closed form ------------------------------------------
    _m("M41", "mapcheck/coeffs.py", "c3 = (1.0 + 2.0 * re) * gamma - one ** 2 * P22 ** 3",
       "c3 = (1.0 + 2.0 * re) * gamma + one ** 2 * P22 ** 3", "tests/mapcheck/test_maps.py tests/mapcheck/test_orbits.py",
       "c3 of (38) with the corrected sign undone"),
    _m("M42", "mapcheck/windows.py", "hi = np.inf if M == 1 else 1.0 / M ** 2", "hi = np.inf if M == 1 else 1.0 / M",
       "tests/mapcheck/test_windows.py", "upper window edge of (64) 1/M instead of 1/M^2"),
    _m("M43", "mapcheck/maps.py",
       "return nu * Omega ** 2 * np.asarray(sigma, dtype=float) / (2.0 * np.abs(A) * (1.0 + r_eff) ** 2)",
       "return nu * Omega ** 2 * np.asarray(sigma, dtype=float) / (2.0 * np.abs(A) * (1.0 + r_eff))",
       "tests/mapcheck/test_maps.py tests/mapcheck/test_windows.py", "rho(sigma) with (1 + r), not (1 + r)^2"),
    _m("M44", "mapcheck/maps.py", "    vt = v - one * (sq - 2.0 * nu * u)\n", "    vt = v - one * (sq - nu * u)\n",
       "tests/mapcheck/test_maps.py tests/analysis/test_direct.py", "(27) with nu instead of 2 nu"),
    _m("M45", "mapcheck/exact.py", "        vr = -self.r * st.v", "        vr = -self.r * st.v * (1.0 - 1e-6)",
       f"tests/mapcheck/test_exact.py {PHYS}", "the closed form's rigid impact law off by 1e-6 relative"),
    _m("M46", "mapcheck/linear.py", "disc = np.sqrt(complex(nu * nu - 4.0 * Omega * Omega))",
       "disc = np.sqrt(complex(nu * nu - 2.0 * Omega * Omega))", "tests/mapcheck/test_linear.py",
       "free-flight eigenvalues from the wrong discriminant"),
    # -- found by tests/fmu/test_inputs_truth.py: CVODE on a moving wall ---------------
    _m("M47", "fmu_src/solver_cvode.c", "        m->u = model_wall_position(m, s->k->tau);\n        m->v = model_wall_velocity(m);\n",
       "", TRUTH, "a sticking mass integrated by CVODE drifts an ulp off the moving wall (released at rest, "
       "an impact counted every other step)"),
    _m("M48", "fmu_src/model.c", "if (m->wall == WALL_RIGID && y[1] - dw <= 0.0 && model_wall_force(m, tau) <= 0.0) {",
       "if (0) {", TRUTH, "a mass leaving the wall after a release, put an ulp beyond it by the integrator, "
       "counts an impact"),
    _m("M49", "fmu_src/model.c", "if (y[0] >= w - wall_resolution(w)) {", "if (y[0] >= w) {", TRUTH,
       "a sticking mass is released when the master writes the wall's position rounded differently"),
    _m("M50", "fmu_src/sens.c", "        return; /* a leaving mass placed back beside the wall (model_event_update): no jump */",
       "        ; /* a leaving mass placed back beside the wall (model_event_update): no jump */", f"{TRUTH} {SENS}",
       "a placement without impact treated as a rigid impact in the saltation matrix"),
    _m("M51", "fmu_src/solver_cvode.c", "if (locate_crossing(s, m, last_good_before(s, t), t) != 0) {",
       "if (0) {", f"{GUARD} {EVENTS}", "a stepped-over crossing counted by the rescue but never located"),
    # -- fmu_src/model.c: the partial derivatives behind fmi2/fmi3GetDirectionalDerivative ----------
    _m("M53", "fmu_src/model.c", "P[PU_DER_V][PK_U_WALL] = Fd;", "P[PU_DER_V][PK_U_WALL] = -Fd;",
       DERIV, "d der(v) / d u_wall inside the wall with the wrong sign"),
    _m("M54", "fmu_src/model.c", "*Fdv = m->kappa2 * d * s * damp;", "*Fdv = m->kappa2 * s * damp;",
       DERIV, "Hunt-Crossley: the damper's partial on v without the depth factor d"),
    _m("M55", "fmu_src/model.c",
       "P[PU_F_CONTACT][PK_U_WALL] = P[PU_WALL_INDICATOR][PK_U_WALL] = -m->Omega2;",
       "P[PU_F_CONTACT][PK_U_WALL] = P[PU_WALL_INDICATOR][PK_U_WALL] = -1.0;", DERIV,
       "sticking: the holding force's partial on u_wall without the spring's Omega^2"),
    # -- basins: the batch kernel's early stop, the labels of slow regions, the quantifiers --------
    _m("M56", "fmu_src/batch.c", "if (cand >= 0 && run >= (known->confirm[cand] < 1 ? 1 : known->confirm[cand])) {",
       "if (cand >= 0) {", BASINS,
       "early stop at the first point near any attractor, its balls' verdict ignored"),
    _m("M57", "harness/runs/basins/tiles.py", "if np.any(stuck) or int(np.max(imp)) >= CHATTER_ENTRIES:",
       "if np.any(stuck):", BASINS, "a start chattering at its samples not labelled sticking/chatter"),
    _m("M58", "harness/analysis/basins/measures.py",
       "return float(entropy.mean()), float(entropy[on_boundary].mean()) if n_b else 0.0, nu * nv, n_b",
       "return float(entropy.mean()), float(entropy.mean()) if n_b else 0.0, nu * nv, n_b", MEASURES,
       "boundary basin entropy averaged over all boxes, not the boundary's"),
    _m("M59", "harness/analysis/basins/measures.py", "        diff |= (c != lab[m - j: nu - m - j, m: nv - m])",
       "        diff = (c != lab[m - j: nu - m - j, m: nv - m])", MEASURES,
       "eps-uncertain: only the neighbours at eps (the last axis direction), not within eps"),
    _m("M60", "harness/runs/basins/ball.py", '"inside": bool(bad.size == 0)', '"inside": True', BASINS,
       "every attractor's tolerance balls pass: one period labels starts also where a boundary is within tol"),
    # -- Initialization Mode's derivatives, Model Exchange's wall memory, the wall's velocity -------
    _m("M61", "fmu_src/fmu_derivatives.c", "    const CoreInstance *start = core_view(c, &buf);",
       "    const CoreInstance *start = c;\n    (void)buf;", INIT_DERIV,
       "Initialization Mode: partials at the instance's stale state (the defaults' free flight), not "
       "at the start values (a mass starting in contact gets F_contact's partials 0)"),
    _m("M62", "fmu_src/fmu_me.c", "        c->me_wall = w;\n", "", ME_WALL,
       "Model Exchange never updates the wall seen at the last event: a state handed over inside a "
       "rigid wall the importer moved before that event is taken for the wall's jump"),
    _m("M63", "fmu_src/fmu_cs.c", "if (model_begin_wall_ramp(&c->m, c->st.clk.tau)) c->st.clk.restart = 1;",
       "", WALL_VELOCITY,
       "Co-Simulation ignores v_wall for the wall's motion over a step (it jumps at each communication "
       "point)"),
    # -- chart: its second routes' rules ----------------------------------------------------------
    _m("M64", "harness/analysis/chart/wall_free.py",
       'rows["error"].append(float(abs(a["gap"] + s1) + abs(b["gap"] + s2)))',
       'rows["error"].append(float(abs(a["gap"] - s1) + abs(b["gap"] - s2)))', CHART_RULES,
       "the wall-free graze's error measured against gap = +sigma, not the exact -sigma"),
    _m("M65", "harness/analysis/chart/contradictions.py",
       'wider = ("scans" if s_s < s_c else "continuation") if side == "lower" else \\',
       'wider = ("scans" if s_s > s_c else "continuation") if side == "lower" else \\', CHART_RULES,
       "a lower-edge contradiction settled for the route with the narrower window where shooting finds the orbit"),
    # -- found by a random search over oscillators: the closed form's certified crossing search -----
    _m("M66", "fmu_src/closed_form.c", "(dL > 0.0 && dR > 0.0 && dL + dR > sg->M[2] * hh) ||\n"
       "                                  (dL < 0.0 && dR < 0.0 && -(dL + dR) > sg->M[2] * hh);",
       "(dL > 0.0 && dR > 0.0) ||\n                                  (dL < 0.0 && dR < 0.0);",
       "tests/fmu/test_random_solvers.py",
       "the certified monotone step without its curvature margin: g taken as monotone between two rates of "
       "one sign, a crossing and its return missed or doubled (spurious chatter)"),
)


def tree_files(root: Path) -> list[str]:
    """Tracked and untracked-but-not-ignored files of the working tree."""
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=root, check=True,
                         capture_output=True).stdout.decode()
    return [f for f in out.split("\0") if f and (root / f).is_file()]


def check_list(root: Path = ROOT) -> list[str]:
    """Problems with the list: ids repeated, snippets not found exactly once, no-op mutants."""
    problems = []
    ids = [m.id for m in MUTANTS]
    problems += [f"{i}: id repeated" for i in sorted({i for i in ids if ids.count(i) > 1})]
    for m in MUTANTS:
        text = (root / m.path).read_text()
        n = text.count(m.find)
        if n != 1:
            problems.append(f"{m.id}: snippet found {n} times in {m.path}")
        if m.find == m.replace:
            problems.append(f"{m.id}: replacement equals the original")
        for t in m.tests:
            if not (root / t.split("::")[0]).is_file():
                problems.append(f"{m.id}: test file {t} missing")
    return problems


def run_one(m: Mutant, timeout: float) -> tuple[str, str, float]:
    """Apply ``m`` to a copy of the tree and run its tests: (status, detail, seconds)."""
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix=f"mutant-{m.id}-") as tmp:
        copy = Path(tmp)
        for f in tree_files(ROOT):
            dst = copy / f
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, dst)
        target = copy / m.path
        target.write_text(target.read_text().replace(m.find, m.replace, 1))
        if m.is_c:
            build = copy / "build" / "fmu"
            cfg = subprocess.run(["cmake", "-S", str(copy / "fmu_src"), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release"],
                                 capture_output=True, text=True)
            mk = cfg if cfg.returncode else subprocess.run(["cmake", "--build", str(build), "-j", "2"],
                                                           capture_output=True, text=True)
            if mk.returncode:
                return "stillborn", (mk.stderr or mk.stdout).strip().splitlines()[-1:][0], time.monotonic() - t0
            # the rest of build/ (the twin, the controller) is not rebuilt: link it (not the
            # tests-only build without the root floor, which its test builds from the copy)
            for item in (ROOT / "build").iterdir():
                if item.name not in ("fmu", "nofloor") and not (copy / "build" / item.name).exists():
                    (copy / "build" / item.name).symlink_to(item)
        else:
            (copy / "build").symlink_to(ROOT / "build")
        env = {**os.environ, "PYTHONPATH": str(copy), "PYTHONDONTWRITEBYTECODE": "1"}
        try:
            # -n 0: the mutant's few tests in this process; under pytest-xdist, -x ends a failing
            # run with exit status 2 (interrupted) instead of 1, which would read as an error
            res = subprocess.run([sys.executable, "-m", "pytest", "-n", "0", "-x", "-q", "-rf", "-p",
                                  "no:cacheprovider", *m.tests], cwd=copy, env=env, capture_output=True,
                                 text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return "killed", "timeout (the tests hung)", time.monotonic() - t0
        failed = re.findall(r"^FAILED (\S+)", res.stdout, re.M)
        if res.returncode == 0:
            return "survived", "", time.monotonic() - t0
        if res.returncode == 1:
            return "killed", failed[0] if failed else "a test failed", time.monotonic() - t0
        return "error", f"pytest exit {res.returncode}: {res.stdout.strip().splitlines()[-1:]}", time.monotonic() - t0


def markdown(rows: list[tuple[Mutant, str, str, float]]) -> str:
    counted = [r for r in rows if r[1] in ("killed", "survived")]
    killed = sum(r[1] == "killed" for r in counted)
    lines = [f"{killed} of {len(counted)} mutants killed ({100.0 * killed / max(1, len(counted)):.0f} %)"
             + (f"; {len(rows) - len(counted)} stillborn or in error" if len(rows) != len(counted) else "") + ".", "",
             "| mutant | file | bug | result | first failing test |", "|---|---|---|---|---|"]
    for m, status, detail, _ in rows:
        lines.append(f"| {m.id} | `{m.path}` | {m.what} | {status} | {detail.replace('|', '/')} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", help="comma-separated mutant ids")
    ap.add_argument("--list", action="store_true", help="print the mutants and exit")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per mutant's tests (default 1800)")
    ap.add_argument("--markdown", metavar="FILE", help="write the result table as Markdown")
    ap.add_argument("--jobs", type=int, default=1,
                    help="mutants run at once, each in its own copy of the tree (default 1)")
    args = ap.parse_args(argv)
    problems = check_list()
    if problems:
        print("the mutant list does not match the code:\n  " + "\n  ".join(problems), file=sys.stderr)
        return 2
    chosen = [m for m in MUTANTS if not args.only or m.id in set(args.only.split(","))]
    if args.list:
        for m in chosen:
            print(f"{m.id}  {m.path:32s} {m.what}  [{' '.join(m.tests)}]")
        return 0
    def run(m: Mutant) -> tuple[Mutant, str, str, float]:
        status, detail, secs = run_one(m, args.timeout)
        print(f"{m.id} {status:9s} {secs:6.0f} s  {m.path}: {m.what}" + (f"  <- {detail}" if detail else ""), flush=True)
        return m, status, detail, secs

    # threads suffice: each mutant's work is in its own child processes (cmake, pytest)
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(run, chosen))  # in the list's order, whatever order they finish in
    table = markdown(rows)
    print("\n" + table)
    if args.markdown:
        Path(args.markdown).write_text(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``impact-harness strobe``: stroboscopic samples at t = n + theta, classified (NetCDF + Poincare
section)."""
from __future__ import annotations

import argparse
import time
from typing import Any

from ..dynamics.maps.classify import classify_orbit
from ..io.progress import progress_bar
from ..runs.budget import Budget, strobe_estimate
from .experiment_args import command_line, experiment_of, output_paths

__all__ = ["register", "cmd_strobe"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``strobe`` to the CLI."""
    common, sampling = parents["common"], parents["sampling"]
    p = sub.add_parser("strobe", parents=[common, sampling], help="stroboscopic samples at t = n + theta",
                       description="Sample (u, v) at t = n + theta after a transient, count impacts per period and "
                       "classify the orbit (period, impacts per period). Draws the Poincare section.")
    p.set_defaults(func=cmd_strobe)


def cmd_strobe(args: argparse.Namespace) -> int:
    """``strobe``: samples at t = n + theta, classified; NetCDF + Poincare section."""
    from ..io.plots import poincare_section
    from ..io.results import provenance, strobe_dataset, write_netcdf
    from ..dynamics.maps.sampling import strobe
    from ..fmu.simulator import FmuSimulator

    exp = experiment_of(args)
    s = exp.sampling
    out, plot = output_paths(args, exp, "strobe")
    L = exp.layers
    blame = L.arg("sampling", "transient") if s.n_transient > s.n_samples else L.arg("sampling", "samples")
    # a Lyapunov period costs up to 5 runs (differences when the FMU has no derivatives)
    Budget.from_args(args).check(strobe_estimate(s.n_transient, s.n_samples + 5 * s.lyapunov, blame))
    t_start = time.perf_counter()
    sim = FmuSimulator(exp.model.source())
    exact = bool(s.lyapunov) and sim.derivatives_available
    sim.track_derivatives(exact)
    with progress_bar(total=s.n_transient + s.n_samples, desc="strobe", unit="period", disable=not exp.run.progress) as bar:
        r = strobe(sim, exp.params, exp.state0, s.theta, s.n_transient, s.n_samples, progress=bar)
    orbit = classify_orbit(r.u, r.v, r.impacts, s.tol, s.max_period)
    ly = None
    if s.lyapunov:
        from ..dynamics.maps.classify import (
            DECIDED,
            DYNAMICS_NAMES,
            REASON_NAMES,
            explain_dynamics,
            still_settling,
        )
        from ..dynamics.maps.lyapunov import lyapunov_continued

        ly = lyapunov_continued(sim, exp.params, s.lyapunov, exact)
        settling = orbit.periodic and still_settling(r.u, r.v, orbit.period, s.tol)
        code, reason = explain_dynamics(orbit.period, settling, ly.largest, ly.largest_uncertainty)
        dynamics = DYNAMICS_NAMES[code] + ("" if reason == DECIDED else f" ({REASON_NAMES[reason]})")
    attrs = provenance(exp.as_attrs(), exp.model, "serial", time.perf_counter() - t_start, command_line(args))
    ds = strobe_dataset(r, orbit, attrs)
    if ly is not None:
        ds = ds.assign_coords(exponent=[1, 2])
        ds["lyapunov"] = ("exponent", ly.exponents, {"long_name": "Lyapunov exponents of the stroboscopic map",
                                                     "units": "1/forcing period", "method": ly.method,
                                                     "comment": f"QR method over {ly.periods} periods after the samples"})
        ds["lyapunov_err"] = ("exponent", ly.uncertainty, {"long_name": "standard error (batch means of 10 blocks)"})
        ds.attrs["dynamics"] = dynamics
    write_netcdf(ds, out)
    print(f"{orbit.label} (residual {orbit.residual:.2e})"
          + ("" if ly is None else f"; Lyapunov exponents {ly} per period ({ly.method}): {dynamics}")
          + f"; wrote {out}")
    if plot:
        print(f"plot: {poincare_section(ds, plot)}")
    return 0

"""``impact-harness jacobian``: the Jacobian of the stroboscopic map at a state, or J(x) along the
grazing family with the exponent of J11 - P11 (NetCDF + plot)."""
from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from ..errors import HarnessInputError
from ..io.progress import progress_bar
from ..runs.budget import Budget, jacobian_estimate
from .experiment_args import command_line, experiment_of, output_paths
from .options import count

__all__ = ["register", "cmd_jacobian"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``jacobian`` to the CLI."""
    common = parents["common"]
    p = sub.add_parser("jacobian", parents=[common], help="Jacobian of the stroboscopic map (at a state, or J(x) near grazing)",
                       description="Jacobian J of the one-period map: exact by default (the FMU's variational "
                       "equations with saltation matrices at impacts) when the FMU reports derivatives, else central "
                       "differences by restarts from perturbed states (--method). With --state: J at that state and its "
                       "eigenvalues (the Floquet multipliers of a fixed point). Without: J against x along the grazing "
                       "family (wall-free state (x, 0) at t = n), in the coordinates of phase --theta (0: the paper's "
                       "t = n, where J11, not J12, is singular), and the exponent q of |J11 - P11| ~ x^q with its "
                       "standard error and fitted x range (a compliant wall: soft and hard contacts fitted apart).")
    g = p.add_argument_group("jacobian")
    g.add_argument("--theta", dest="jacobian__theta", type=float, metavar="PHASE",
                   help="section phase of the coordinates, in [0, 1) (default 0)")
    g.add_argument("--measure-theta", dest="jacobian__measure_theta", type=float, metavar="PHASE",
                   help="phase where J is measured, away from the impact (default 0.5)")
    g.add_argument("--x-start", dest="jacobian__x_start", type=float, metavar="X", help="smallest x (default 1e-6)")
    g.add_argument("--x-stop", dest="jacobian__x_stop", type=float, metavar="X", help="largest x (default 1e-2)")
    g.add_argument("--x-num", dest="jacobian__x_num", type=count, metavar="N", help="number of x values, log-spaced (default 25)")
    g.add_argument("--state", dest="jacobian__state", metavar="U,V",
                   help="J and its eigenvalues (multipliers) at this state at t = theta, instead of a scan")
    g.add_argument("--method", dest="jacobian__method", choices=("auto", "exact", "fd"),
                   help="exact: the FMU's own derivatives (variational equations); fd: central differences; "
                   "auto (default): exact when the FMU reports them")
    p.set_defaults(func=cmd_jacobian)


def cmd_jacobian(args: argparse.Namespace) -> int:
    """``jacobian``: J at --state, or J(x) along the grazing family; NetCDF + plot."""
    from ..dynamics.maps.jacobian import jacobian_vs_x, map_jacobian
    from ..io.plots import jacobian_plot
    from ..dynamics.maps.singularity_fit import describe, fits_dataset, grazing_fits
    from ..io.results import jacobian_dataset, provenance, state_jacobian_dataset, write_netcdf
    from ..dynamics.maps.sampling import check_count, check_theta
    from ..fmu.simulator import FmuSimulator

    exp = experiment_of(args)
    L = exp.layers
    params = dict(exp.params)
    # [jacobian] rtol/atol, when given, override the model's tolerances for these runs only
    # (differences of maps need tight tolerances; the FMU's defaults are tight already).
    for key in ("rtol", "atol"):
        if L.get("jacobian", key) is not None and key in params:
            params[key] = float(L.get("jacobian", key))
    theta = check_theta(L.get("jacobian", "theta"), L.arg("jacobian", "theta"))
    sim = FmuSimulator(exp.model.source())
    t_start = time.perf_counter()
    state = L.get("jacobian", "state")
    if state is not None:
        try:
            u, v = (float(s) for s in str(state).replace(" ", "").split(","))
        except ValueError:
            raise HarnessInputError(L.arg("jacobian", "state"), f"expected U,V, got {state!r}") from None
        out, _ = output_paths(args, exp, "jacobian")
        res = map_jacobian(sim, params, (u, v), theta=theta, method=str(L.get("jacobian", "method")))
        mu = np.linalg.eigvals(res.J)
        print(f"J at (u, v) = ({u}, {v}), t = {theta}:")
        print(np.array2string(res.J, precision=8))
        print("eigenvalues of J (multipliers): " + ", ".join(f"{m:.8g} (|mu| = {abs(m):.6g})" for m in mu)
              + f"; det J = {np.linalg.det(res.J):.8g}")
        print(f"image {res.image}; " + ("exact (the FMU's derivatives)" if res.method == "exact" else
                                         f"central differences, step {res.step:.2e}, estimated error {res.error:.1e}"))
        settings = {**exp.as_attrs(), **{f"model.{k}": v for k, v in params.items()},
                    **{f"jacobian.{k}": v for k, v in L.values["jacobian"].items()}}
        ds = state_jacobian_dataset(res, (u, v), theta, provenance(settings, exp.model, "serial",
                                                                   time.perf_counter() - t_start, command_line(args)))
        write_netcdf(ds, out)
        print(f"wrote {out}")
        return 0
    n = check_count(L.get("jacobian", "x_num"), L.arg("jacobian", "x_num"), minimum=1)
    Budget.from_args(args).check(jacobian_estimate(n, L.arg("jacobian", "x_num")))
    lo, hi = float(L.get("jacobian", "x_start")), float(L.get("jacobian", "x_stop"))
    if not (0 < lo and 0 < hi):
        raise HarnessInputError(L.arg("jacobian", "x_start"), f"x values must be > 0 (log-spaced), got {lo}, {hi}")
    if n > 1 and lo == hi:
        raise HarnessInputError(L.arg("jacobian", "x_stop"), f"empty range: x_start = x_stop = {lo}")
    x = np.geomspace(lo, hi, n)
    out, plot = output_paths(args, exp, "jacobian")
    with progress_bar(total=n, desc="jacobian", unit="x", disable=not exp.run.progress) as bar:
        scan = jacobian_vs_x(sim, params, x, theta, float(L.get("jacobian", "measure_theta")), progress=bar,
                             method=str(L.get("jacobian", "method")))
    settings = {**exp.as_attrs(), **{f"model.{k}": v for k, v in params.items()},
                **{f"jacobian.{k}": v for k, v in L.values["jacobian"].items()}}
    ds = jacobian_dataset(scan, provenance(settings, exp.model, "serial", time.perf_counter() - t_start, command_line(args)))
    fits, beta = grazing_fits(scan, params)
    ds = ds.merge(fits_dataset(fits))
    if beta is not None:
        ds["beta"] = ("x", beta, {"long_name": "contact parameter beta = r kappa sqrt(8 pi^2 x) / |A~| "
                                               "(soft <= 0.1, hard >= 5; docs/theory.md section 5)"})
    write_netcdf(ds, out)
    print(f"exponent q of |J11 - P11| ~ x^q ({scan.method}; scanned x in [{lo:g}, {hi:g}]):")
    for regime, fit in fits.items():
        print("  " + describe(regime, fit))
    print(f"wrote {out}")
    if plot:
        print(f"plot: {jacobian_plot(ds, plot)}")
    return 0

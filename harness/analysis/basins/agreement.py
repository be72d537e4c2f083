"""A basin scan of the batch kernel checked against the FMU, start by start.

A random sample of the grid's starts is run through the FMU itself (fmpy, either solver) for the
scan's whole transient and samples, with no early stop, and labelled as the FMU scan labels
them: the samples' period and wall entries, then the scan's attractor whose points lie within
the scan's tolerance (Hausdorff distance), else not periodic (or sticking/chatter, as the
kernel's tiles decide it).  The fraction of equal labels, and the starts where they differ,
measure what early stopping and the kernel cost in correctness.
"""
from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ...config import SamplingSpec
from ...dynamics.attractors.identity import (
    CHATTER_ENTRIES,
    INVALID,
    NOT_PERIODIC,
    STICKING,
    hausdorff,
    orbit_points,
)
from ...dynamics.maps.classify import classify_orbit
from ...dynamics.maps.sampling import strobe
from ...fmu.simulator import FmuSimulator
from ...runs.tasks import inside_rigid_wall


def fmu_label(sim: FmuSimulator, ds: Any, params: Mapping[str, Any], s: SamplingSpec, start: tuple[float, float]) -> int:
    """The label the FMU gives one start, in the scan's attractors (``ds``)."""
    if inside_rigid_wall(dict(params), start):
        return INVALID
    r = strobe(sim, params, start, s.theta, s.n_transient, s.n_samples)
    orbit = classify_orbit(r.u, r.v, r.impacts, s.tol, s.max_period)
    if not orbit.periodic:
        return STICKING if int(np.max(r.impacts)) >= CHATTER_ENTRIES else NOT_PERIODIC
    pts = orbit_points(r.u, r.v, orbit.period)
    tol = float(ds.attrs["basins.match_tol"])
    for a in range(ds.sizes.get("attractor_index", 0)):
        p = int(ds["attractor_period"].values[a])
        if p == orbit.period and int(ds["attractor_impacts"].values[a]) == orbit.impacts \
                and hausdorff(pts, ds["attractor_points"].values[a, :p]) <= tol:
            return a
    return NOT_PERIODIC


def fmu_agreement(model: Any, ds: Any, params: Mapping[str, Any], sampling: SamplingSpec, n: int,
                  seed: int = 0) -> dict[str, Any]:
    """Labels of ``n`` random starts of the scan ``ds`` from the FMU, against the scan's.

    Parameters
    ----------
    model : FmuModel
        The FMU (its ``solver`` parameter from ``params``: closed form or CVODE).
    ds : xarray.Dataset
        A basin scan (``attractor`` on (u0, v0) and the ``attractor_*`` variables).
    params, sampling
        As the scan ran (``params`` may name another solver).
    n : int
        Starts drawn (without replacement; at most the grid's size).
    seed : int
        Of the random draw.

    Returns
    -------
    dict
        ``starts``, ``equal``, ``fraction`` (equal / starts) and ``differ``: a list of
        ``(u0, v0, scan label, FMU label)``.
    """
    labels = ds["attractor"].values
    rng = np.random.default_rng(seed)
    picks = rng.choice(labels.size, size=min(int(n), labels.size), replace=False)
    u0, v0 = ds["u0"].values, ds["v0"].values
    differ = []
    sim = FmuSimulator(model.source() if hasattr(model, "source") else model, instance_name="basins-check")
    try:
        for flat in picks:
            i, j = np.unravel_index(int(flat), labels.shape)
            got = fmu_label(sim, ds, params, sampling, (float(u0[i]), float(v0[j])))
            if got != int(labels[i, j]):
                differ.append((float(u0[i]), float(v0[j]), int(labels[i, j]), int(got)))
    finally:
        sim.close()
    k = len(picks)
    return {"starts": k, "equal": k - len(differ), "fraction": (k - len(differ)) / k if k else float("nan"),
            "differ": differ}

"""The uncertainty exponent from random pairs of starts, as Grebogi, McDonald, Ott & Yorke
(Phys. Lett. A 99, 415, 1983) measure it: for each eps, N random starts x in the scan's box and
their partners x + eps (cos phi, sin phi) (phi random, the displacement in units of the box's
sides); a pair is eps-uncertain when its two starts reach different classes.  The fraction
f(eps), with its binomial standard error, scales as eps^alpha; alpha is fitted as on the grid
(:func:`.basin_measures.power_law_fit`).  Unlike the grid's estimate it does not stop at the
grid's resolution: eps goes down to 2^-10 of the box (a thousandth) by default.

The pairs run on the batch kernel with the scan's attractors (early stop), so their labels mean
the scan's; a new attractor a pair finds is added for the rest of the pairs.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ...config import SamplingSpec
from ...errors import HarnessInputError
from ...fmu import batch_kernel as bk
from ...runs.basins.registry import Found, Registry
from ...runs.basins.tiles import label_result
from .measures import power_law_fit

#: The perturbations, as fractions of the box's sides: 2^-3 .. 2^-10.
DEFAULT_EPS = 2.0 ** -np.arange(3, 11)


@dataclass(frozen=True)
class PairsFit:
    """alpha (and its standard error) from the pairs; f(eps) with binomial errors; the fit range."""

    alpha: float
    alpha_err: float
    eps: np.ndarray
    fraction: np.ndarray
    fraction_err: np.ndarray
    pairs: int
    fit: tuple[float, float]


def _labels(reg: Registry, params: Mapping[str, Any], s: SamplingSpec, u: np.ndarray, v: np.ndarray,
            threads: int | None) -> np.ndarray:
    res = bk.run_batch(params, u, v, s.theta, s.n_transient, s.n_samples, reg.known(), threads)
    return reg.merge(label_result(res, s, reg.known()))


def pairs_fit(classify: Callable[[np.ndarray, np.ndarray], np.ndarray], box: tuple[float, float, float, float],
              pairs: int = 4000, eps: np.ndarray | None = None, seed: int = 0) -> PairsFit:
    """alpha of any classifier ``classify(u, v) -> labels`` over ``box`` (u1, u2, v1, v2) from
    ``pairs`` random pairs per eps (module docstring)."""
    eps = DEFAULT_EPS if eps is None else np.asarray(eps, dtype=float)
    lo, side = np.array([box[0], box[2]]), np.array([box[1] - box[0], box[3] - box[2]])
    rng = np.random.default_rng(seed)
    frac = np.empty(eps.size)
    for k, e in enumerate(eps):
        x = lo + rng.random((pairs, 2)) * side
        phi = rng.random(pairs) * 2.0 * np.pi
        y = x + e * side * np.column_stack([np.cos(phi), np.sin(phi)])
        both = np.asarray(classify(np.concatenate([x[:, 0], y[:, 0]]), np.concatenate([x[:, 1], y[:, 1]])))
        frac[k] = float(np.mean(both[:pairs] != both[pairs:]))
    alpha, err, use = power_law_fit(eps, frac, pairs)
    fit = (float(eps[use].min()), float(eps[use].max())) if use.any() else (0.0, 0.0)
    return PairsFit(alpha, err, eps, frac, np.sqrt(frac * (1 - frac) / pairs), pairs, fit)


def uncertainty_from_pairs(ds: Any, params: Mapping[str, Any], sampling: SamplingSpec, pairs: int = 4000,
                           eps: np.ndarray | None = None, seed: int = 0, threads: int | None = None) -> PairsFit:
    """alpha from ``pairs`` random pairs per eps in the box of the batch-kernel scan ``ds``, each
    start labelled by the kernel with the scan's attractors.

    Raises
    ------
    HarnessInputError
        When ``ds`` is not a batch-kernel scan (its attractors' wall entries are needed).
    """
    if "basins.registry" not in ds.attrs:
        raise HarnessInputError("uncertainty_pairs", "needs a scan of the batch kernel (--kernel batch)")
    reg = Registry(float(ds.attrs["basins.match_tol"]), None,
                   [Found(**f) for f in json.loads(ds.attrs["basins.registry"])])
    u0, v0 = ds["u0"].values, ds["v0"].values
    return pairs_fit(lambda u, v: _labels(reg, params, sampling, u, v, threads),
                     (float(u0[0]), float(u0[-1]), float(v0[0]), float(v0[-1])), pairs, eps, seed)


def with_pairs(ds: Any, fit: PairsFit) -> Any:
    """``ds`` with the pairs' f(eps) and exponent."""
    ds = ds.copy()
    ds = ds.assign_coords(pairs_eps=fit.eps)
    ds["pairs_uncertain_fraction"] = ("pairs_eps", fit.fraction,
                                      {"long_name": "share of eps-uncertain random pairs (eps: fraction of the box)"})
    ds["pairs_uncertain_fraction_err"] = ("pairs_eps", fit.fraction_err, {"long_name": "binomial standard error"})
    ds.attrs.update({"basins.pairs_uncertainty_exponent": fit.alpha, "basins.pairs_uncertainty_exponent_err":
                     fit.alpha_err, "basins.pairs_per_eps": fit.pairs, "basins.pairs_fit_eps": json.dumps(list(fit.fit))})
    return ds

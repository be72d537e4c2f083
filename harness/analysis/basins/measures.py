"""The quantifiers of a basin picture, from their papers' definitions, for any labelled grid.

- **Basin fractions** with standard errors: the share f_j of the starts in each class, with the
  binomial standard error sqrt(f_j (1 - f_j) / N) of a fraction estimated from N starts (as
  Attractors.jl reports them; for a grid this is the error of a random sample of that size).
- **Basin entropy** S_b and **boundary basin entropy** S_bb (Daza, Wagemakers, Georgeot,
  Guery-Odelin & Sanjuan, Sci. Rep. 6, 31416, 2016): the grid cut into boxes of eps x eps
  cells; in box i the classes have probabilities p_ij (their shares of the box's cells), the
  Gibbs entropy S_i = -sum_j p_ij log p_ij; S_b = sum_i S_i / N (all N boxes), S_bb =
  sum_i S_i / N_b (the N_b boxes with S_i > 0, on a boundary).  S_bb > log 2 is their
  sufficient condition for a fractal boundary.
- **Uncertainty exponent** alpha (Grebogi, McDonald, Ott & Yorke, Phys. Lett. A 99, 415,
  1983; McDonald, Grebogi, Ott & Yorke, Physica D 17, 125, 1985): the fraction f(eps) of
  eps-uncertain starts -- those whose class changes when the start is moved by up to eps --
  scales as eps^alpha, alpha = D - d with d the boundary's box-counting dimension in phase space
  of dimension D (a smooth boundary: alpha = 1).  From the grid: a start is eps-uncertain when
  a start at most k cells away along either axis (eps = k cells) is in another class (the
  eps-neighbourhood of the boundary, whose measure scales as eps^(D - d)); alpha is the
  least-squares slope of log f against log eps over the steps k = 1, 2, 4, ... where
  0 < f < 1/2, with its standard error from the fit's residuals.

Every class counts, the negative codes (not periodic, invalid, ...) included: a boundary with
the grey region of non-periodic starts is a boundary too.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


#: Fewest uncertain pairs that make a point of a pairs estimate's fit.
MIN_UNCERTAIN = 10


@dataclass(frozen=True)
class UncertaintyFit:
    """The uncertainty exponent and its fit.

    Attributes
    ----------
    alpha, alpha_err : float
        Slope of log f against log eps and its standard error (NaN with fewer than 3 points).
    steps : numpy.ndarray of int
        The perturbations eps tried, in grid cells.
    fraction : numpy.ndarray
        f(eps): the share of eps-uncertain starts (among those with neighbours k cells away).
    fit : tuple of int
        The smallest and largest eps (cells) of the fit.
    """

    alpha: float
    alpha_err: float
    steps: np.ndarray
    fraction: np.ndarray
    fit: tuple[int, int]


def basin_fractions(labels: np.ndarray) -> dict[int, tuple[float, float]]:
    """Each class's share of the starts and its standard error: ``{label: (f, se)}``."""
    flat = np.asarray(labels).ravel()
    n = flat.size
    values, counts = np.unique(flat, return_counts=True)
    out = {}
    for v, c in zip(values.tolist(), counts.tolist()):
        f = c / n
        out[int(v)] = (f, float(np.sqrt(f * (1.0 - f) / n)))
    return out


def basin_entropy(labels: np.ndarray, box: int = 5) -> tuple[float, float, int, int]:
    """S_b and S_bb over boxes of ``box`` x ``box`` cells (cells beyond the last whole box are
    left out).

    Returns
    -------
    (S_b, S_bb, boxes, boundary boxes)
        S_bb is 0 when no box lies on a boundary.
    """
    lab = np.asarray(labels)
    if lab.ndim != 2 or box < 1 or lab.shape[0] < box or lab.shape[1] < box:
        raise ValueError(f"need a 2D grid of at least {box} x {box} cells, got shape {lab.shape}")
    nu, nv = lab.shape[0] // box, lab.shape[1] // box
    blocks = lab[: nu * box, : nv * box].reshape(nu, box, nv, box).transpose(0, 2, 1, 3).reshape(nu * nv, box * box)
    entropy = np.zeros(nu * nv)
    for c in np.unique(blocks):
        p = np.mean(blocks == c, axis=1)
        nz = p > 0
        entropy[nz] -= p[nz] * np.log(p[nz])
    on_boundary = entropy > 1e-15
    n_b = int(on_boundary.sum())
    return float(entropy.mean()), float(entropy[on_boundary].mean()) if n_b else 0.0, nu * nv, n_b


def uncertain_fractions(labels: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """f(eps) for eps = k cells, k in ``steps`` (increasing): the share of starts whose class
    changes when the start moves by at most k cells along an axis, counted over one fixed set
    of starts (those at least max(steps) cells from the grid's edges), so that f is not biased
    by a shrinking interior.  NaN where the grid is too small."""
    lab = np.asarray(labels)
    nu, nv = lab.shape
    m = int(steps[-1])
    out = np.full(len(steps), np.nan)
    if 2 * m >= nu or 2 * m >= nv:
        return out
    c = lab[m: nu - m, m: nv - m]
    diff = np.zeros(c.shape, dtype=bool)
    want = {int(k): i for i, k in enumerate(steps)}
    for j in range(1, m + 1):
        diff |= (c != lab[m - j: nu - m - j, m: nv - m]) | (c != lab[m + j: nu - m + j, m: nv - m]) \
            | (c != lab[m: nu - m, m - j: nv - m - j]) | (c != lab[m: nu - m, m + j: nv - m + j])
        if j in want:
            out[want[j]] = diff.mean()
    return out


def uncertainty_exponent(labels: np.ndarray, max_step: int | None = None) -> UncertaintyFit:
    """The uncertainty exponent of a labelled grid (module docstring).

    Parameters
    ----------
    labels : numpy.ndarray, shape (nu, nv)
    max_step : int, optional
        Largest eps in cells (default an eighth of the smaller side: the neighbours stay in the
        grid for most starts).
    """
    lab = np.asarray(labels)
    top = max_step or max(1, min(lab.shape) // 8)
    steps = 2 ** np.arange(int(np.log2(top)) + 1)
    frac = uncertain_fractions(lab, steps)
    alpha, err, use = power_law_fit(steps.astype(float), frac)
    fit = (int(steps[use].min()), int(steps[use].max())) if use.any() else (0, 0)
    return UncertaintyFit(alpha, err, steps, frac, fit)


def power_law_fit(eps: np.ndarray, frac: np.ndarray, samples: int | None = None) -> tuple[float, float, np.ndarray]:
    """Slope of log f against log eps over the points with 0 < f < 1/2 (and, for f estimated from
    ``samples`` random pairs, at least MIN_UNCERTAIN of them uncertain: fewer are noise), its
    standard error from the residuals, and the points used; NaN slope with fewer than 3 points."""
    use = np.isfinite(frac) & (frac > 0) & (frac < 0.5)
    if samples is not None:
        use &= frac * samples >= MIN_UNCERTAIN
    if use.sum() < 3:
        return float("nan"), float("nan"), np.zeros_like(use)
    x, y = np.log(eps[use]), np.log(frac[use])
    A = np.column_stack([x, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = y - A @ coef
    dof = max(1, x.size - 2)
    var = float(resid @ resid) / dof / float(((x - x.mean()) ** 2).sum())
    return float(coef[0]), float(np.sqrt(var)), use

"""A basin scan's quantifiers stored with it (NetCDF variables and attributes) and written out
for the report: fractions with errors, basin entropy, boundary basin entropy, the uncertainty
exponent with its fit (:mod:`.basin_measures`), and the check against the FMU
(:mod:`.basin_agreement`) when one was run."""
from __future__ import annotations

import json
from typing import Any

import numpy as np

from ...dynamics.attractors.identity import LABEL_NAMES
from .measures import basin_entropy, basin_fractions, uncertainty_exponent

#: Side of Daza et al.'s boxes, in cells (their paper uses 5).
ENTROPY_BOX = 5


def with_measures(ds: Any, box: int = ENTROPY_BOX, suffix: str = "") -> Any:
    """``ds`` with the quantifiers of its ``attractor{suffix}`` grid (``suffix`` "_zoom": the zoom's)."""
    ds = ds.copy()
    labels = ds[f"attractor{suffix}"].values
    fr = basin_fractions(labels)
    codes = np.array(sorted(fr), dtype=np.int64)
    ds = ds.assign_coords({f"basin_class{suffix}": codes})
    ds[f"basin_fraction{suffix}"] = (f"basin_class{suffix}", np.array([fr[c][0] for c in codes]),
                                     {"long_name": "share of the starts in each class (attractor >= 0, codes < 0)"})
    ds[f"basin_fraction_err{suffix}"] = (f"basin_class{suffix}", np.array([fr[c][1] for c in codes]),
                                         {"long_name": "binomial standard error sqrt(f (1 - f) / N)"})
    pre = f"basins{suffix}."
    if min(labels.shape) >= box:
        sb, sbb, n, nb = basin_entropy(labels, box)
        ds.attrs.update({pre + "entropy": sb, pre + "boundary_entropy": sbb, pre + "entropy_box": box,
                         pre + "entropy_boxes": n, pre + "entropy_boundary_boxes": nb})
    fit = uncertainty_exponent(labels)
    ds[f"uncertainty_fraction{suffix}"] = (f"uncertainty_step{suffix}", fit.fraction,
                                           {"long_name": "share of eps-uncertain starts, eps in grid cells"})
    ds = ds.assign_coords({f"uncertainty_step{suffix}": fit.steps})
    ds.attrs.update({pre + "uncertainty_exponent": fit.alpha, pre + "uncertainty_exponent_err": fit.alpha_err,
                     pre + "uncertainty_fit_cells": json.dumps(list(fit.fit))})
    return ds


def with_agreement(ds: Any, check: dict[str, Any], solver: str) -> Any:
    """``ds`` with the result of :func:`harness.analysis.basins.agreement.fmu_agreement`."""
    ds = ds.copy()
    ds.attrs.update({"basins.fmu_check_solver": solver, "basins.fmu_check_starts": check["starts"],
                     "basins.fmu_check_equal": check["equal"],
                     "basins.fmu_check_differ": json.dumps(check["differ"])})
    return ds


def _class_name(ds: Any, code: int) -> str:
    if code < 0:
        return LABEL_NAMES.get(code, str(code))
    return json.loads(ds.attrs["basins.attractors"])[code] if code < ds.sizes.get("attractor_index", 0) else f"A{code}"


def measure_lines(ds: Any, suffix: str = "") -> list[str]:
    """The quantifiers as report lines."""
    pre = f"basins{suffix}."
    lines = []
    if f"basin_fraction{suffix}" in ds:
        parts = [f"{_class_name(ds, int(c))} {f:.4f} +- {e:.4f}" for c, f, e in zip(
            ds[f"basin_class{suffix}"].values, ds[f"basin_fraction{suffix}"].values,
            ds[f"basin_fraction_err{suffix}"].values)]
        lines.append("  basin fractions (binomial standard errors): " + "; ".join(parts))
    if pre + "entropy" in ds.attrs:
        lines.append(f"  basin entropy S_b = {ds.attrs[pre + 'entropy']:.4f}, boundary basin entropy S_bb = "
                     f"{ds.attrs[pre + 'boundary_entropy']:.4f} (boxes of {ds.attrs[pre + 'entropy_box']} x "
                     f"{ds.attrs[pre + 'entropy_box']} cells, {ds.attrs[pre + 'entropy_boundary_boxes']} of "
                     f"{ds.attrs[pre + 'entropy_boxes']} on a boundary; S_bb > log 2 = 0.693 means fractal)")
    if pre + "uncertainty_exponent" in ds.attrs:
        lo, hi = json.loads(ds.attrs[pre + "uncertainty_fit_cells"])
        alpha = ds.attrs[pre + "uncertainty_exponent"]
        lines.append(f"  uncertainty exponent alpha = {alpha:.3f} +- {ds.attrs[pre + 'uncertainty_exponent_err']:.3f} "
                     f"(fit over eps = {lo}..{hi} grid cells; a smooth boundary has 1, boundary dimension "
                     f"d = 2 - alpha = {2 - alpha:.3f})" if np.isfinite(alpha) else
                     "  uncertainty exponent: no boundary to fit (fewer than 3 steps with 0 < f < 1/2)")
    if not suffix and "basins.pairs_uncertainty_exponent" in ds.attrs:
        alpha, err = ds.attrs["basins.pairs_uncertainty_exponent"], ds.attrs["basins.pairs_uncertainty_exponent_err"]
        lo, hi = json.loads(ds.attrs["basins.pairs_fit_eps"])
        lines.append(f"  uncertainty exponent from {ds.attrs['basins.pairs_per_eps']} random pairs per eps: alpha = "
                     f"{alpha:.3f} +- {err:.3f} (fit over eps = {lo:.3g}..{hi:.3g} of the box)" if np.isfinite(alpha)
                     else "  uncertainty exponent from random pairs: too few uncertain pairs to fit")
    if not suffix and "basins.fmu_check_starts" in ds.attrs:
        n, eq = ds.attrs["basins.fmu_check_starts"], ds.attrs["basins.fmu_check_equal"]
        differ = json.loads(ds.attrs["basins.fmu_check_differ"])
        lines.append(f"  against the FMU ({ds.attrs['basins.fmu_check_solver']}, no early stop): {eq} of {n} random "
                     f"starts labelled alike ({eq / n:.1%})" + ("" if not differ else "; differ at " + "; ".join(
                         f"({u:.4g}, {v:.4g}): scan {_class_name(ds, a)}, FMU {_class_name(ds, b)}"
                         for u, v, a, b in differ[:5]) + (" ..." if len(differ) > 5 else "")))
    return lines

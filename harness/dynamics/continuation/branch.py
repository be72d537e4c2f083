"""A branch of periodic orbits with its located events: the result of :mod:`.continuation`.

Kinds of events (:data:`EVENT_KINDS`):

``flip``     a multiplier of D(F^M) through -1 (period doubling; the period-2M branch starts here)
``fold``     a multiplier through +1 (saddle-node: the branch turns back in the parameter)
``ns``       a complex pair through the unit circle (Neimark-Sacker: a torus)
``graze``    a non-impacting passage reaches the wall: the contact count per period changes
``stick``    on a rigid wall, the orbit's impact reaches zero speed and the mass starts to stick
             (the contact count jumps to a chatter/sticking sequence)
``end``      where and why the branch stopped (range end, point budget, Newton lost the orbit)
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from mapcheck.compare import equal_runs

__all__ = ["EVENT_KINDS", "Event", "Branch", "branches_dataset"]

EVENT_KINDS = ("flip", "fold", "ns", "graze", "stick", "end")


@dataclass
class Event:
    """A located event on a branch.

    Attributes
    ----------
    kind : str
        One of :data:`EVENT_KINDS`.
    value : float
        Parameter value where it lies: for flip/fold/ns the root of the test function; for a
        graze the zero of its defining quantity (``quantity``: the gap of a free passage or the
        entry velocity of a contact), extrapolated from the orbits on the old side; for a stick
        (or a graze that no such quantity describes, ``quantity`` "contacts") the last orbit with
        the old contact count, ``bracket`` from the first parameter without it.
    index : int
        Index of the branch point that is this event (located points are inserted in the branch;
        for a graze, the last orbit with the old contacts, at ``values[index]`` next to ``value``).
    multipliers : ndarray complex (2,)
        Of the orbit at ``value``.
    point : ndarray (2,)
        Stroboscopic state (u, v) of the orbit at ``value``.
    bracket : float
        Width, in the parameter, of the final bracket of the location (0 when the test function
        itself reached zero).
    note : str
        What happened there, e.g. "continued with 2 impacts per period" or the reason of an end.
    interval : (float, float) or None
        For a graze located on its defining equation: an interval of the parameter that contains
        the zero (``bracket`` is its width).
    quantity : str
        For a graze: "gap", "entry velocity" or "contacts" (located by the contact pattern only).
    """

    kind: str
    value: float
    index: int
    multipliers: np.ndarray
    point: np.ndarray
    bracket: float = 0.0
    note: str = ""
    interval: tuple[float, float] | None = None
    quantity: str = ""

    def as_dict(self) -> dict[str, Any]:
        out = {"kind": self.kind, "value": self.value, "index": self.index,
               "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
               "point": [float(x) for x in self.point], "bracket": self.bracket, "note": self.note}
        if self.kind in ("graze", "stick"):
            out["quantity"] = self.quantity
            out["interval"] = None if self.interval is None else [float(x) for x in self.interval]
        return out


@dataclass
class Branch:
    """Periodic orbits of the M-period stroboscopic map along a parameter.

    Attributes
    ----------
    param : str
        The continued parameter.
    M : int
        Period in forcing periods.
    params : dict
        The other FMU parameters.
    theta : float
        Section phase of the stroboscopic points.
    values : ndarray (N,)
        Parameter value of every point, in continuation order (not sorted: folds turn back).
    points : ndarray (N, M, 2)
        Stroboscopic states (u, v) at t = theta + k, k = 0..M-1.
    contacts : ndarray of int (N, M)
        Contacts in each period.
    multipliers : ndarray complex (N, 2)
        Eigenvalues of D(F^M).
    gaps : ndarray (N,)
        Smallest distance to the wall of the non-impacting periods (inf: every period impacts).
    labels : list of str (N,)
        Event kind at the located points, "" elsewhere.
    events : list of Event
    derivatives : str
        "exact" (the FMU's variational equations) or "fd".
    periods_run : int
        FMU periods integrated.
    """

    param: str
    M: int
    params: dict
    theta: float
    values: np.ndarray
    points: np.ndarray
    contacts: np.ndarray
    multipliers: np.ndarray
    gaps: np.ndarray
    labels: list[str]
    events: list[Event] = field(default_factory=list)
    derivatives: str = "exact"
    periods_run: int = 0

    @property
    def stable(self) -> np.ndarray:
        """All multipliers inside the unit circle, per point."""
        return np.all(np.abs(self.multipliers) < 1.0, axis=1)

    @property
    def impacts(self) -> np.ndarray:
        """Contacts per period M, per point."""
        return self.contacts.sum(axis=1)

    def __len__(self) -> int:
        return int(self.values.size)

    def stable_intervals(self) -> list[tuple[float, float, int]]:
        """Maximal runs of stable points as (first value, last value, impacts per period)."""
        imp = self.impacts
        return [(float(self.values[i]), float(self.values[j]), int(imp[i])) for i, j in equal_runs(self.stable, imp)]

    def to_dataset(self, attrs: Mapping[str, Any] | None = None) -> Any:
        """The branch as an xarray Dataset (dims point, k, mu) with the events as JSON in the
        attribute ``continuation.events`` and ``attrs`` (provenance) added."""
        import xarray as xr

        ds = xr.Dataset(
            {
                self.param: ("point", self.values),
                "u": (("point", "k"), self.points[:, :, 0]),
                "v": (("point", "k"), self.points[:, :, 1]),
                "contacts": (("point", "k"), self.contacts.astype(np.int32)),
                "impacts": ("point", self.impacts.astype(np.int32)),
                "multiplier_re": (("point", "mu"), self.multipliers.real),
                "multiplier_im": (("point", "mu"), self.multipliers.imag),
                "multiplier_abs": (("point", "mu"), np.abs(self.multipliers)),
                "stable": ("point", self.stable.astype(np.int8)),
                "gap": ("point", np.where(np.isfinite(self.gaps), self.gaps, np.nan)),
                "event": ("point", np.array(self.labels, dtype=str)),
            },
            coords={"point": np.arange(len(self)), "k": np.arange(self.M), "mu": [0, 1]},
        )
        ds[self.param].attrs["long_name"] = f"continuation parameter {self.param}"
        ds["u"].attrs["long_name"] = f"u at t = theta + k (theta = {self.theta:g})"
        ds["gap"].attrs["long_name"] = "smallest distance to the wall of the non-impacting periods (NaN: all impact)"
        ds["stable"].attrs["long_name"] = "1: all |multipliers| < 1"
        ds.attrs.update({
            "continuation.param": self.param, "continuation.M": self.M, "continuation.theta": self.theta,
            "continuation.derivatives": self.derivatives, "continuation.periods_run": self.periods_run,
            "continuation.events": json.dumps([e.as_dict() for e in self.events]),
            "continuation.params": json.dumps({k: (v if isinstance(v, (int, float, str)) else str(v))
                                               for k, v in self.params.items()}),
        })
        if attrs:
            from ...io.results import _attr_value

            ds.attrs.update({k: _attr_value(v) for k, v in attrs.items()})
        return ds


def branches_dataset(branches: list[Branch], kinds: list[str], attrs: Mapping[str, Any] | None = None) -> Any:
    """Several branches in one Dataset, concatenated along ``point``; ``branch`` (index) and
    ``period`` per point, states padded with NaN to the longest period; the events of all
    branches (each with its branch index) in ``continuation.events``."""
    import xarray as xr

    if not branches:
        raise ValueError("no branch to write")
    parts = []
    events = []
    for i, br in enumerate(branches):
        ds = br.to_dataset()
        ds["branch"] = ("point", np.full(len(br), i, dtype=np.int32))
        ds["period"] = ("point", np.full(len(br), br.M, dtype=np.int32))
        ds["contacts"] = ds["contacts"].astype(float)  # NaN-padded where k >= period
        events += [{**e.as_dict(), "branch": i, "index": e.index + sum(len(b) for b in branches[:i])}
                   for e in br.events]
        parts.append(ds.drop_vars("point"))
    out = xr.concat(parts, dim="point", join="outer", combine_attrs="override", fill_value=np.nan)
    out = out.assign_coords(point=np.arange(out.sizes["point"]))
    out["event"] = out["event"].astype(str)
    out.attrs["continuation.events"] = json.dumps(events)
    out.attrs["continuation.branches"] = json.dumps(kinds)
    out.attrs.pop("continuation.M", None)
    if attrs:
        from ...io.results import _attr_value

        out.attrs.update({k: _attr_value(v) for k, v in attrs.items()})
    return out

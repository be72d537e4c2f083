"""The attractor classes of an atlas and where each is stable.

A class is (period M, wall entries per orbit period) for periodic orbits, apart for orbits that
stick or chatter on the wall; then chaos (aperiodic starts with a positive exponent), aperiodic
(quasi-periodic or not settled in the periods allowed) and escape. A class is *stable at a pixel*
when at least one of the pixel's starts reached an attractor of it. Each pixel is drawn in its
*dominant* class, the one most of its starts reached (ties: the class listed first); a pixel is
*multistable* when its starts reached more than one attractor (two orbits of one class count
twice).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...runs.atlas.tiles import APERIODIC, CHAOTIC, ESCAPED, PERIODIC, STICKING


@dataclass(frozen=True)
class AtlasClass:
    """One class: ``kind`` periodic, sticking, chaotic, aperiodic or escaped; M and impacts for
    the two periodic kinds (0 otherwise)."""

    kind: str
    M: int = 0
    impacts: int = 0

    @property
    def name(self) -> str:
        if self.kind in ("periodic", "sticking"):
            s = "" if self.impacts == 1 else "s"
            return f"P{self.M}, {self.impacts} impact{s}" + (", sticks" if self.kind == "sticking" else "")
        return {"chaotic": "chaos", "aperiodic": "aperiodic (not settled / quasi-periodic)",
                "escaped": "escaped"}[self.kind]


@dataclass
class ClassMaps:
    """The classes found and, per start, pixel and class, what the figure and the summary need."""

    classes: list[AtlasClass]
    of_start: np.ndarray   # (p2, sigma, start): class index, -1 invalid or failed
    present: np.ndarray    # (class, p2, sigma): stable there
    dominant: np.ndarray   # (p2, sigma): the class most starts reached, -1 none
    n_attractors: np.ndarray  # (p2, sigma)


def classify(data: dict[str, np.ndarray]) -> ClassMaps:
    """The classes of an atlas's per-start arrays (:class:`harness.runs.atlas.scan.AtlasArrays`)."""
    kind, M, imp = data["kind"], data["period"], data["impacts"]
    orbit = (kind == PERIODIC) | (kind == STICKING)
    keys = sorted({(int(k == STICKING), int(m), int(i)) for k, m, i in zip(kind[orbit], M[orbit], imp[orbit])})
    classes = [AtlasClass("sticking" if s else "periodic", m, i) for s, m, i in keys]
    of = np.full(kind.shape, -1, dtype=np.int16)
    for c, (s, m, i) in enumerate(keys):
        of[(kind == (STICKING if s else PERIODIC)) & (M == m) & (imp == i)] = c
    for code, name in ((CHAOTIC, "chaotic"), (APERIODIC, "aperiodic"), (ESCAPED, "escaped")):
        if np.any(kind == code):
            of[kind == code] = len(classes)
            classes.append(AtlasClass(name))
    n = len(classes)
    counts = np.stack([(of == c).sum(axis=2) for c in range(n)]) if n else np.zeros((0, *kind.shape[:2]), int)
    present = counts > 0
    dominant = np.where(counts.sum(axis=0) > 0, np.argmax(counts, axis=0), -1) if n else \
        np.full(kind.shape[:2], -1)
    n_att = (data["label"].max(axis=2) + 1).astype(np.int16)
    return ClassMaps(classes, of, present, dominant.astype(np.int16), n_att)


def _range(x: np.ndarray) -> list[float] | None:
    return [float(x.min()), float(x.max())] if x.size else None


def class_summary(maps: ClassMaps, p2: np.ndarray, sigma: np.ndarray) -> list[dict[str, Any]]:
    """atlas.json's ``classes``: per class its M, impacts, the pixels where it is stable and their
    extent in p2 and in sigma, and how many of them it shares with another attractor."""
    P, S = np.meshgrid(p2, sigma, indexing="ij")
    multi = maps.n_attractors >= 2
    out = []
    for c, cl in enumerate(maps.classes):
        where = maps.present[c]
        out.append({"kind": cl.kind, "name": cl.name, "M": cl.M if cl.M else None,
                    "impacts": cl.impacts if cl.kind in ("periodic", "sticking") else None,
                    "pixels": int(where.sum()), "dominant_pixels": int((maps.dominant == c).sum()),
                    "multistable_pixels": int((where & multi).sum()), "starts": int((maps.of_start == c).sum()),
                    "p2_range": _range(P[where]), "sigma_range": _range(S[where])})
    return out


def window_class(maps: ClassMaps, M: int, impacts: int = 1) -> int:
    """The index of the periodic class (M, impacts), or -1."""
    for c, cl in enumerate(maps.classes):
        if cl.kind == "periodic" and cl.M == M and cl.impacts == impacts:
            return c
    return -1

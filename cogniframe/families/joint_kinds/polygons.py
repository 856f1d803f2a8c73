"""Convex polygons in plan for the core links' closed forms: one half-plane clip, a hull's area,
the intersection of two convex polygons and the area of a union of them. Pure numpy."""

from __future__ import annotations

from itertools import combinations

import numpy as np

from ...parts.joint_plan import hull_ccw
from ..base import polygon_area


def clip(poly, a: np.ndarray, b: float) -> list:
    """The part of a convex polygon where a . p <= b (Sutherland-Hodgman, one edge)."""
    out = []
    for i, p in enumerate(poly):
        q = poly[i - 1]
        fp, fq = float(a @ p) - b, float(a @ q) - b
        if fp <= 0:
            if fq > 0:
                out.append(q + (p - q) * fq / (fq - fp))
            out.append(p)
        elif fq <= 0:
            out.append(q + (p - q) * fq / (fq - fp))
    return out


def hull_area(pts: np.ndarray) -> float:
    """Area of the convex hull of 2-D points (`hull_ccw` + shoelace)."""
    hull = hull_ccw(pts)
    x, y = hull[:, 0], hull[:, 1]
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2)


def convex_clip(poly, other) -> list:
    """The intersection of two convex polygons (`other` counter-clockwise)."""
    out = list(poly)
    q = np.asarray(other, float)
    for i in range(len(q)):
        if len(out) < 3:
            return []
        e = q[(i + 1) % len(q)] - q[i]
        a = np.array([e[1], -e[0]])  # outward normal of a counter-clockwise edge
        out = clip(out, a, float(a @ q[i]))
    return out if len(out) >= 3 else []


def union_area(polys) -> float:
    """Area of the union of convex polygons (inclusion-exclusion over their intersections)."""
    total = 0.0
    for k in range(1, len(polys) + 1):
        for group in combinations(polys, k):
            inter = list(group[0])
            for q in group[1:]:
                inter = convex_clip(inter, hull_ccw(q)) if inter else []
            if len(inter) >= 3:
                total += (-1) ** (k + 1) * polygon_area(inter)
    return total

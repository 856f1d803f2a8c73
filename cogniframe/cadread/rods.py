"""Rod finder: a rod is a straight solid cylinder, much longer than thick.

A solid is a rod when its cylindrical faces are all coaxial and of one radius (a CAD program may
split the side into halves), its other faces are planes or small cones/tori (end caps, chamfers),
its volume is that of the cylinder over its length (within `VOLUME_TOL`: a hollow tube, a screw or
a standoff fails this) and its length is at least `MIN_ASPECT` diameters. The length and the end
points come from the solid's vertices projected on the axis (the end faces' centres); the diameter
from the cylindrical face. `rod_diameter` (optional) keeps only rods of that diameter (+-10 %).
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import cylinders, line_distance, vertices
from .found import Rod

MIN_ASPECT = 5.0
VOLUME_TOL = 0.03
AXIS_TOL = 1e-3  # rad / relative


def as_rod(name: str, solid, rod_diameter: float | None = None) -> Rod | None:
    """The rod this solid is, or None."""
    types = {f.geomType() for f in solid.Faces()}
    if "CYLINDER" not in types or not types <= {"CYLINDER", "PLANE", "CONE", "TORUS"}:
        return None
    cyl = cylinders(solid)
    big = max(cyl, key=lambda c: c.radius)
    r = big.radius
    for c in cyl:
        if abs(abs(np.dot(c.direction, big.direction)) - 1) > AXIS_TOL or line_distance(c.origin, big.origin, big.direction) > 1e-3 * max(r, 1):
            return None
        if c.hole:
            return None
    if rod_diameter is not None and abs(2 * r - rod_diameter) > 0.1 * rod_diameter:
        return None
    t = (vertices(solid) - big.origin) @ big.direction
    if t.size == 0:
        t = np.array([big.v0, big.v1])
    t0, t1 = min(t.min(), big.v0), max(t.max(), big.v1)
    length = float(t1 - t0)
    if length < MIN_ASPECT * 2 * r:
        return None
    vol = solid.Volume()
    if abs(vol - math.pi * r * r * length) > VOLUME_TOL * math.pi * r * r * length:
        return None
    a, b = big.at(t0), big.at(t1)
    return Rod(name, tuple(float(x) for x in a), tuple(float(x) for x in b), float(2 * r))


def find_rods(solids, rod_diameter: float | None = None) -> tuple[list[Rod], list]:
    """(rods, the other NamedSolids)."""
    rods, rest = [], []
    for ns in solids:
        rod = as_rod(ns.name, ns.solid, rod_diameter)
        (rest if rod is None else rods).append(ns if rod is None else rod)
    return rods, rest

"""The numpy helpers more than one family's plan uses (the part record they fill, `PartSpec` and
its pieces, is parts/record.py, where the CAD helpers read it too). Pure numpy, no CAD.
"""

from __future__ import annotations

import math

import numpy as np

from ..parts.record import Estimate, Vec
from ..spec import Spec

# Rotation about z taking the fl prototype to each corner (clockwise seen from above).
CORNER_ROTATION = {"fl": 0.0, "fr": -90.0, "rr": -180.0, "rl": 90.0}
# A corner's sockets coincide with the prototype's placed there when no port (mm) or direction
# (unit vector) differs by more than this; sockets are stored rounded to 1e-6.
FIT_TOL = 1e-5


def rot_z(v: np.ndarray, deg: float) -> np.ndarray:
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])


def rounded(v) -> Vec:
    return (round(float(v[0]), 6), round(float(v[1]), 6), round(float(v[2]), 6))


def link_hole(spec: Spec) -> float:
    """Plate-corner bolt position for the core links, along x and y from the centre (mm): near the
    corner, because under thrust the tab lifts off the plate between the seat and the bolt head
    (an M2 clearance hole 3.5 mm from both edges keeps 2.3 mm of plate to each)."""
    return spec.core.plate_size / 2 - max(3.5, spec.core.plate_thickness + 0.5)


def plate_estimate(a: float, b: float, t: float, holes: list[float]) -> Estimate:
    hole_area = sum(math.pi / 4 * d**2 for d in holes)
    return Estimate(a * b * t - hole_area * t, 2 * (a * b - hole_area), 2 * (a + b) * t + sum(math.pi * d * t for d in holes),
                    (a, b, t))


def hexagon_area(length: float, width: float) -> float:
    """A window `length` long with 45 deg pointed ends across `width`: its area (mm^2)."""
    return length * width - width * width / 2


def polygon_area(pts) -> float:
    x = np.array([p[0] for p in pts])
    y = np.array([p[1] for p in pts])
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2)


def polygon_perimeter(pts) -> float:
    p = np.asarray(pts, float)
    return float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).sum())

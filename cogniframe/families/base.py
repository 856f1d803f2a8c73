"""What every part family shares: the part record (`PartSpec`) and its pieces, and the numpy
helpers more than one family's plan uses. Pure numpy, no CAD.

Local frames: a joint's local origin is its node; the prototype is the front-left (`fl`)
instance and the others are the prototype rotated about z by `Placement.rotation_deg`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..spec import Spec

Vec = tuple[float, float, float]
# Rotation about z taking the fl prototype to each corner (clockwise seen from above).
CORNER_ROTATION = {"fl": 0.0, "fr": -90.0, "rr": -180.0, "rl": 90.0}
# A corner's sockets coincide with the prototype's placed there when no port (mm) or direction
# (unit vector) differs by more than this; sockets are stored rounded to 1e-6.
FIT_TOL = 1e-5
# Two socket directions count as parallel (an arm pair) when their dot product exceeds 1 - this;
# directions are stored rounded to 6 decimals, so 1e-6 is too tight (~0.8 deg here).
PARALLEL_TOL = 1e-4


@dataclass(frozen=True)
class Socket:
    """A blind rod hole in a part's local frame (mm)."""

    rod: str  # rod name in the prototype instance
    port: Vec  # point on the rod axis level with the joint centre
    direction: Vec  # unit vector out of the socket, along the rod
    seat: float  # port -> socket bottom (where the rod ends)
    depth: float  # socket bottom -> mouth (rod insertion)
    bore: float  # hole diameter = rod diameter + fit clearance

    def bottom(self) -> np.ndarray:
        return np.asarray(self.port) + np.asarray(self.direction) * self.seat

    def mouth(self) -> np.ndarray:
        return np.asarray(self.port) + np.asarray(self.direction) * (self.seat + self.depth)


@dataclass(frozen=True)
class Placement:
    """Where one copy of a part goes: rotate the local frame about z, then move its origin to `origin`."""

    instance: str  # node or motor name, e.g. knee_fr
    rotation_deg: float
    origin: Vec

    def matrix(self) -> np.ndarray:
        """4x4 world-from-local transform."""
        a = math.radians(self.rotation_deg)
        m = np.eye(4)
        m[:2, :2] = [[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
        m[:3, 3] = self.origin
        return m


@dataclass(frozen=True)
class Estimate:
    """Analytic geometry of a part: volume (mm^3), horizontal and vertical surface (mm^2), envelope (mm)."""

    volume: float
    area_h: float
    area_v: float
    envelope: Vec  # a bounding box that fits it in print orientation


@dataclass(frozen=True)
class HardwareLine:
    item: str
    qty: int  # per copy of the part
    mass_g: float  # each


@dataclass(frozen=True)
class PartSpec:
    name: str  # distinct part, e.g. "knee"
    family: str  # its family module (families/registry.py)
    group: str  # mass-budget group: exoskeleton | core
    material: str
    infill: float
    placements: tuple[Placement, ...]
    sockets: tuple[Socket, ...]
    wall: float
    estimate: Estimate
    params: tuple[tuple[str, object], ...] = ()  # family-specific inputs, all the CAD may read
    hardware: tuple[HardwareLine, ...] = ()
    digest: str = field(default="")  # hash of everything above: the part's CAD cache key

    @property
    def qty(self) -> int:
        return len(self.placements)

    def param(self, key: str):
        return dict(self.params)[key]


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

"""The part record: what a part family's plan hands every later stage (the CAD, the part files,
the mass model, the BOM), and its pieces. Plain frozen dataclasses and numpy; no CAD kernel.

Local frames: a joint's local origin is its node; the prototype is the front-left (`fl`)
instance and the others are the prototype rotated about z by `Placement.rotation_deg`.

It lives here, below the families, because the CAD helpers in this package read it too: the
families import parts/, never the other way round.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

Vec = tuple[float, float, float]


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

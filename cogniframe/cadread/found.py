"""What the CAD reader finds: rods, joints, sockets (frozen dataclasses, numpy-free tuples, mm).

Conventions (the same as `frame.Rod` / `parts.record.Socket`):
- a rod runs from end ``a`` to end ``b``; `Rod.axis` is the unit vector a -> b;
- a socket's `direction` is the unit vector out of the socket, along the rod (from the joint
  towards the rod's middle); its `bottom` is where the bore ends inside the joint (blind) or where
  the rod end sits (through), its `mouth` is where the rod enters the joint: mouth = bottom +
  direction * (gap + depth), and the rod end is at bottom + direction * gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

Vec = tuple[float, float, float]


def _sub(p: Vec, q: Vec) -> Vec:
    return (p[0] - q[0], p[1] - q[1], p[2] - q[2])


def _add(p: Vec, q: Vec, s: float = 1.0) -> Vec:
    return (p[0] + s * q[0], p[1] + s * q[1], p[2] + s * q[2])


@dataclass(frozen=True)
class Rod:
    """A straight cylindrical rod read from the CAD: its axis endpoints (the end faces' centres)."""

    name: str
    a: Vec
    b: Vec
    diameter: float

    @property
    def length(self) -> float:
        return math.dist(self.a, self.b)

    @property
    def axis(self) -> Vec:
        d = _sub(self.b, self.a)
        n = self.length
        return (d[0] / n, d[1] / n, d[2] / n)

    def end(self, tag: str) -> Vec:
        return self.a if tag == "a" else self.b

    def direction_from(self, tag: str) -> Vec:
        """Unit vector from end `tag` into the rod (out of the socket that holds that end)."""
        ax = self.axis
        return ax if tag == "a" else (-ax[0], -ax[1], -ax[2])


@dataclass(frozen=True)
class Socket:
    """A rod end in a joint (or, with ``end=None``, a rod passing through a sleeve of a joint).

    `bore`: the hole's diameter (its cylindrical face's radius x 2, measured across the hole's own
    axis); `depth`: how far the rod sits inside the joint, mouth to rod end, a coaxial mouth
    chamfer included (for a sleeve: the sleeve's length); `blind`: the hole has a bottom (material on the axis just beyond it);
    `gap`: rod end -> bottom of a blind hole (0 when the rod is home; negative = the CAD puts the rod
    deeper than the hole); `offset`: the hole axis' distance from the rod axis at the rod end;
    `tilt_deg`: the angle between the two axes."""

    joint: str
    rod: str
    end: str | None  # "a" | "b" | None (a sleeve the rod passes through)
    bottom: Vec
    direction: Vec
    bore: float
    depth: float
    blind: bool
    gap: float = 0.0
    offset: float = 0.0
    tilt_deg: float = 0.0
    station: float | None = None  # for a sleeve: its middle's distance from the rod's end a, mm

    @property
    def kind(self) -> str:
        return "sleeve" if self.end is None else ("blind" if self.blind else "through")

    @property
    def rod_end(self) -> Vec:
        return _add(self.bottom, self.direction, self.gap)

    @property
    def mouth(self) -> Vec:
        return _add(self.bottom, self.direction, self.gap + self.depth)


@dataclass(frozen=True)
class Joint:
    """A printed (or rigid) part: its name, material, centroid, volume (mm^3) and bounding box."""

    name: str
    material: str
    centroid: Vec
    volume: float
    bbox: tuple[Vec, Vec]
    material_from: str = "default"  # "name" (a name pattern), "file" (--materials), "default"


@dataclass(frozen=True)
class Contact:
    """Two parts that touch (a connector's peg in the base, a knee snapped to its support)."""

    a: str
    b: str
    distance: float  # a gap found between them within the tolerance, mm (the first, not always the least; 0 = touching)


@dataclass(frozen=True)
class Exoskeleton:
    """Everything the reader placed, and what it could not.

    `joints` are the non-rod solids that hold a rod (a socket or a sleeve); `attached` the other
    solids connected to a joint through `contacts` (a core plate the links peg into, a motor on its
    mount, its screws): the payload and the vitamins, with the material their name says or "";
    `unplaced` names solids it could not place (neither a rod nor connected to one), `loose_ends`
    the rod ends in no joint ("rod_x:a"), `warnings` says the same in sentences."""

    source: str
    rods: tuple[Rod, ...]
    joints: tuple[Joint, ...]
    sockets: tuple[Socket, ...]
    attached: tuple[Joint, ...] = ()
    contacts: tuple[Contact, ...] = ()
    unplaced: tuple[str, ...] = ()
    loose_ends: tuple[str, ...] = ()
    warnings: tuple[str, ...] = field(default=())

    def rod(self, name: str) -> Rod:
        return next(r for r in self.rods if r.name == name)

    def joint(self, name: str) -> Joint:
        return next(j for j in self.joints if j.name == name)

    def sockets_of(self, joint: str) -> tuple[Socket, ...]:
        return tuple(s for s in self.sockets if s.joint == joint)

    def socket_at(self, rod: str, end: str) -> Socket | None:
        return next((s for s in self.sockets if s.rod == rod and s.end == end), None)


def as_dict(exo: Exoskeleton) -> dict:
    """Plain data for `--json`: the fields, plus each rod's length and axis and each socket's kind,
    rod end and mouth (mm)."""
    from dataclasses import asdict

    d = asdict(exo)
    for r, rd in zip(exo.rods, d["rods"]):
        rd.update(length=r.length, axis=r.axis)
    for s, sd in zip(exo.sockets, d["sockets"]):
        sd.update(kind=s.kind, rod_end=s.rod_end, mouth=s.mouth)
    return d

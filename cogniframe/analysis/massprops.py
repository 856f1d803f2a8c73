"""Mass properties of the aircraft: mass, centre of gravity and the inertia tensor about it.

Every mass line of the budget becomes one or more rigid bodies (a point, a box, a cylinder, a rod,
a propeller or a closed mesh), each with its own mass, centroid and inertia about that centroid; the
parallel-axis theorem sums them about the common centre of gravity. Two sources:

- `estimate`: the part list's estimates (pure numpy, for `check`): printed core parts as solid
  boxes of their frame boxes, joints and mounts as points at their places;
- `from_solids`: the CAD solids of the printed parts (`build`: their STLs), each carrying its
  budget mass spread evenly over its volume.

Rods, vitamins (motors, battery, boards) and propellers are the same in both. Masses are the
budget's own lines, so the total is `check`'s all-up mass exactly. Body axes are the frame's
(x right, y front, z up); SI units (kg, m, kg m^2) in the result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..numfmt import norm

# The parts whose mass sits in a frame core box, and which box (the estimate spreads the part's
# mass over that box; a point mass would leave out most of its inertia).
CORE_BOX = {"core_plate": "plate", "battery_holder": "holder", "sensor_mount": "spacer", "camera_mount": "camera_base"}


@dataclass(frozen=True)
class Body:
    """One rigid body: mass (g), centroid (mm), inertia about the centroid (g mm^2, 3 x 3)."""

    name: str
    mass_g: float
    centroid: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]


@dataclass(frozen=True)
class MassProps:
    """The aircraft's mass properties, SI: mass (kg), centre of gravity (m, frame axes), inertia
    about the centre of gravity (kg m^2, frame axes x right, y front, z up)."""

    mass_kg: float
    cg_m: tuple[float, float, float]
    inertia_kg_m2: tuple[tuple[float, float, float], ...]
    source: str  # "estimate" | "cad"

    @property
    def cg_mm(self) -> tuple[float, float, float]:
        return tuple(1000.0 * c for c in self.cg_m)

    @property
    def inertia(self) -> np.ndarray:
        return np.asarray(self.inertia_kg_m2, float)

    def to_dict(self) -> dict:
        return {"mass_kg": round(self.mass_kg, 6), "cg_mm": [round(c, 3) + 0.0 for c in self.cg_mm],
                "inertia_kg_m2": [[float(f"{v:.6g}") for v in row] for row in self.inertia_kg_m2], "source": self.source}


def _t3(v) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _m3(a) -> tuple[tuple[float, float, float], ...]:
    return tuple(map(tuple, np.asarray(a, float).tolist()))


def point(name: str, mass_g: float, at) -> Body:
    return Body(name, mass_g, _t3(at), _m3(np.zeros((3, 3))))


def box(name: str, mass_g: float, centre, size, rot=np.eye(3)) -> Body:
    """A solid box of `size` (its own axes, turned by `rot` into the frame's)."""
    a, b, c = size
    local = mass_g / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    r = np.asarray(rot, float)
    return Body(name, mass_g, _t3(centre), _m3(r @ local @ r.T))


def _axis_tensor(axis, i_axial: float, i_trans: float) -> np.ndarray:
    a = np.asarray(axis, float)
    a = a / norm(a)
    return i_trans * _EYE3 + (i_axial - i_trans) * np.outer(a, a)


_EYE3 = np.eye(3)
_EYE3.flags.writeable = False


def cylinder(name: str, mass_g: float, base, axis, radius: float, length: float) -> Body:
    """A solid cylinder from `base` along `axis`."""
    a = np.asarray(axis, float)
    a = a / norm(a)
    centre = np.asarray(base, float) + a * length / 2
    i_ax = mass_g * radius * radius / 2
    i_tr = mass_g * (3 * radius * radius + length * length) / 12
    return Body(name, mass_g, _t3(centre), _m3(_axis_tensor(a, i_ax, i_tr)))


def rod(name: str, mass_g: float, start, end, diameter: float) -> Body:
    d = np.asarray(end, float) - np.asarray(start, float)
    return cylinder(name, mass_g, start, d, diameter / 2, norm(d))


def propeller(name: str, mass_g: float, centre, diameter: float) -> Body:
    """A two-blade propeller as a slender bar of its diameter, averaged over a turn: about the
    spin axis m D^2 / 12, about each axis in its plane half of that."""
    i_z = mass_g * diameter * diameter / 12
    return Body(name, mass_g, _t3(centre), _m3(np.diag([i_z / 2, i_z / 2, i_z])))


@dataclass(frozen=True)
class SolidProps:
    """A closed triangle mesh's volume (mm^3), centroid (mm) and second moment of volume about
    its centroid (mm^5, the inertia at unit density), in the mesh's own frame."""

    volume: float
    centroid: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]


def solid_props(triangles: np.ndarray) -> SolidProps:
    """Volume, centroid and inertia of a closed, outward-facing triangle mesh ((n, 3, 3) corners):
    the signed tetrahedra from the origin to each face. A tetrahedron (0, a, b, c) has volume
    det/6 (det = a . (b x c)) and second moment det/120 (S S^T + a a^T + b b^T + c c^T), S = a + b + c."""
    t = np.asarray(triangles, float)
    origin = t.reshape(-1, 3).mean(axis=0)  # near the solid: less cancellation than the print origin
    a, b, c = t[:, 0] - origin, t[:, 1] - origin, t[:, 2] - origin
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    vol = float(det.sum() / 6.0)
    ssum = a + b + c
    centroid = (det[:, None] * ssum).sum(axis=0) / 24.0 / vol
    cov = (np.einsum("i,ij,ik->jk", det, ssum, ssum) + sum(np.einsum("i,ij,ik->jk", det, v, v) for v in (a, b, c))) / 120.0
    cov_c = cov - vol * np.outer(centroid, centroid)  # about the centroid
    inertia = np.trace(cov_c) * np.eye(3) - cov_c
    return SolidProps(vol, _t3(centroid + origin), _m3(inertia))


def read_stl_triangles(path) -> np.ndarray:
    """A binary STL's triangles, (n, 3, 3) mm, with numpy only (the build writes binary STLs)."""
    data = open(path, "rb").read()
    n = int.from_bytes(data[80:84], "little")
    rec = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(data, rec, n, 84)["v"].astype(float)


def placed_body(name: str, mass_g: float, props: SolidProps, world_from_mesh) -> Body:
    """The solid `props` moved by the 4 x 4 `world_from_mesh`, carrying `mass_g` evenly."""
    m = np.asarray(world_from_mesh, float)
    r, t = m[:3, :3], m[:3, 3]
    centre = r @ np.asarray(props.centroid) + t
    inertia = r @ np.asarray(props.inertia) @ r.T * (mass_g / props.volume)
    return Body(name, mass_g, _t3(centre), _m3(inertia))


def combine(bodies, source: str) -> MassProps:
    """Mass, centre of gravity and inertia about it of rigid `bodies` (parallel-axis theorem)."""
    m = np.array([b.mass_g for b in bodies], float)
    c = np.array([b.centroid for b in bodies], float)
    total = float(m.sum())
    cg = (m[:, None] * c).sum(axis=0) / total
    inertia = np.zeros((3, 3))
    for b, mi, ci in zip(bodies, m, c):
        r = ci - cg
        inertia += np.asarray(b.inertia) + mi * (float(r @ r) * _EYE3 - np.outer(r, r))
    # g mm^2 -> kg m^2; products of inertia below 1e-6 of the largest term are round-off of
    # symmetric solids (a mesh's facets): exact zeros, so a symmetric frame writes symmetric files
    inertia = 1e-9 * inertia
    inertia[np.abs(inertia) < 1e-6 * np.abs(inertia).max()] = 0.0
    inertia = (inertia + inertia.T) / 2
    return MassProps(total / 1000.0, _t3(cg / 1000.0), _m3(inertia), source)


# -- the aircraft -----------------------------------------------------------------------------

def _vitamin_bodies(spec, frame, budget, parts, fasteners=None) -> tuple[list, set[str]]:
    """Bodies of the bought parts drawn in the assembly (vitamins.py): each vitamin carries its
    budget line's mass (spread over the vitamins that share the line by their volume), each
    primitive its share by volume. Propellers as spinning bars (`propeller`). Returns the bodies
    and the budget lines they used. `parts`: the design's part list (the screws sit in its holes);
    `fasteners`: its `fasteners.fasteners` when the caller has them."""
    from ..vitamins import vitamins

    lines = {i.name: i for i in budget.items}
    vits = [v for v in vitamins(spec, frame, parts, fasteners) if v.budget_line in lines]
    by_line: dict[str, list] = {}
    for v in vits:
        by_line.setdefault(v.budget_line, []).append(v)
    out = []
    for line, vs in by_line.items():
        total = lines[line].mass_g
        if vs[0].family == "propeller":
            for v in vs:
                centre, r, _ = v.disc
                out.append(propeller(v.name, total / len(vs), centre, 2 * r))
            continue
        vols = [[_prim_volume(p) for p in v.prims] for v in vs]
        all_vol = sum(sum(x) for x in vols)
        for v, vv in zip(vs, vols):
            for p, pv in zip(v.prims, vv):
                out.append(_prim_body(v.name, total * pv / all_vol, p))
    return out, set(by_line)


def _prim_volume(p) -> float:
    if p.kind == "box":
        return float(np.prod(p.size))
    return math.pi * p.radius**2 * p.length


def _prim_body(name: str, mass_g: float, p) -> Body:
    if p.kind == "box":
        return box(name, mass_g, p.centre, p.size, np.asarray(p.rot))
    return cylinder(name, mass_g, p.centre, p.axis, p.radius, p.length)


def _rod_bodies(frame, budget) -> list:
    """The frame's rods as solid cylinders between their cut ends; their total is the budget's
    rod lines (the cut list)."""
    rods = list(frame.rods.values())
    lengths = np.array([r.cut_length for r in rods])
    total = sum(i.mass_g for i in budget.items if i.name.startswith("rod "))
    scale = total / float(lengths.sum())
    return [rod(r.name, scale * L, r.start, r.end, r.diameter) for r, L in zip(rods, lengths)]


def _rest_bodies(frame, budget, used: set[str], printed: set[str]) -> list:
    """Budget lines with no solid of their own (screws, a receiver, wiring): points at the
    core-plate centre, where the stack and its leads sit."""
    at = frame.core.plate.centre
    return [point(i.name, i.mass_g, at) for i in budget.items
            if i.name not in used and i.name not in printed and not i.name.startswith("rod ")]


def estimate(spec, design, budget, fasteners=None) -> MassProps:
    """From the part list's estimates (no CAD): `check --json`'s `flight.cg_mm` and
    `flight.inertia_kg_m2`. `fasteners`: the design's `fasteners.fasteners` when the caller has them."""
    frame = design.frame

    def copies(p, each):
        core_box = getattr(frame.core, CORE_BOX.get(p.family, ""), None)
        if core_box is not None:
            return [box(p.name, each, core_box.centre, core_box.size) for _ in p.placements]
        return [point(p.name, each, pl.origin) for pl in p.placements]

    return _combined(spec, design, budget, copies, "estimate", fasteners)


def from_solids(spec, design, budget, solids) -> MassProps:
    """From the CAD solids: `solids` is {part name: (SolidProps of its mesh as printed, the 4 x 4
    print-from-local transform)}; each copy goes where its placement puts it."""

    def copies(p, each):
        props, pfl = solids[p.name]
        local_from_print = np.linalg.inv(np.asarray(pfl, float))
        return [placed_body(p.name, each, props, pl.matrix() @ local_from_print) for pl in p.placements]

    return _combined(spec, design, budget, copies, "cad")


def _combined(spec, design, budget, copies, source: str, fasteners=None) -> MassProps:
    """Rods, bought parts, every copy of every printed part (`copies(part, grams each)`) and the
    budget's remaining lines, combined: the two sources differ only in how a printed part's copies
    are modelled."""
    frame = design.frame
    bodies = _rod_bodies(frame, budget)
    vit, used = _vitamin_bodies(spec, frame, budget, design.parts, fasteners)
    bodies += vit
    items = {i.name: i for i in budget.items}
    for p in design.parts:
        bodies += copies(p, items[p.name].mass_g_each)
    bodies += _rest_bodies(frame, budget, used, {p.name for p in design.parts})
    return combine(bodies, source)

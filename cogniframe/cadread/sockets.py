"""Socket finder: where each rod sits in the joints around it.

For every rod and every other solid near it (bounding boxes within `NEAR` mm), the solid's hole
faces (concave cylinders) that are coaxial with the rod (axes within `TILT_DEG`, the hole's axis
within `OFFSET_TOL` x the rod's radius of the rod's axis) and of a bore between `BORE_MIN` and
`BORE_MAX` rod diameters are grouped into bores: faces of one radius whose extents along the rod
touch or overlap. Each bore is measured along the rod (t from end a):
- a bore over end a (it starts at or beyond the end, t0 <= `END_TOL`, and ends inside the rod,
  t1 > `END_TOL`) is that end's socket: depth = t1 (mouth -> rod end), gap = -t0 (rod end ->
  bottom); likewise end b;
- a bore wholly inside the rod's span is a sleeve the rod passes through (a motor mount's clip):
  depth = its length, station = its middle's t;
- blind or through: a point on the bore's axis just beyond its bottom (up to `PROBE` mm) is in the
  joint's material.
The bore is the face's own radius x 2, so a tilted hole reads true (a section across the world's
axes would read wide). A rod end with no socket in any solid is a loose end.
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import Cyl, bbox, cones, cylinders, inside, line_distance
from .found import Rod, Socket

NEAR = 1.0  # mm between a rod's and a solid's bounding boxes
TILT_DEG = 3.0
OFFSET_TOL = 0.35  # of the rod's radius
BORE_MIN, BORE_MAX = 0.7, 1.5  # of the rod's diameter
END_TOL = 0.6  # mm: a bore that starts this far past the rod's end still holds it (a CAD overlap)
JOIN_TOL = 0.05  # mm between two faces' extents that still make one bore
PROBE = (0.05, 0.2, 0.5, 1.0)  # mm beyond a bore's bottom where material means "blind"


def _t(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in v)


def _coaxial(c: Cyl, rod: Rod, a: np.ndarray, ax: np.ndarray, L: float) -> tuple[float, float] | None:
    """The face's extent along the rod (t from end a, sorted) if it is a hole coaxial with it."""
    r = rod.diameter / 2
    if not c.hole or not (BORE_MIN * r <= c.radius <= BORE_MAX * r):
        return None
    cosang = abs(float(np.dot(c.direction, ax)))
    if cosang < math.cos(math.radians(TILT_DEG)):
        return None
    p0, p1 = c.at(c.v0), c.at(c.v1)
    t0, t1 = sorted((float(np.dot(p0 - a, ax)), float(np.dot(p1 - a, ax))))
    if t1 < -L or t0 > 2 * L:
        return None
    for p in (p0, p1):  # the face's axis at both its ends near the rod's axis
        if line_distance(p, a, ax) > OFFSET_TOL * r:
            return None
    return t0, t1


def _bores(faces: list[tuple[float, float, Cyl]]) -> list[tuple[float, float, Cyl]]:
    """Faces of one radius whose extents touch, merged: (t0, t1, the longest face)."""
    out: list[list] = []
    for t0, t1, c in sorted(faces, key=lambda f: (round(f[2].radius, 3), f[0])):
        last = out[-1] if out else None
        if last and abs(last[2].radius - c.radius) < 1e-3 and t0 <= last[1] + JOIN_TOL:
            if t1 - t0 > last[1] - last[0]:
                last[2] = c
            last[1] = max(last[1], t1)
        else:
            out.append([t0, t1, c])
    return [tuple(b) for b in out]


def _measure(joint: str, solid, rod: Rod, end: str | None, t_bottom: float, t_mouth: float, t_end: float,
             c: Cyl, a: np.ndarray, ax: np.ndarray) -> Socket:
    """A socket whose bore runs from t_bottom (inside the joint) to t_mouth; t_end is the rod's end."""
    d = np.sign(t_mouth - t_bottom) * ax  # out of the socket, along the rod
    d = d / np.linalg.norm(d)
    hd = c.direction if np.dot(c.direction, d) > 0 else -c.direction

    def on_hole_axis(t: float) -> np.ndarray:
        p = a + ax * t
        return c.origin + c.direction * np.dot(p - c.origin, c.direction)

    bottom = on_hole_axis(t_bottom)
    blind = any(inside(solid, bottom - hd * s) for s in PROBE)
    tilt = math.degrees(math.acos(min(1.0, abs(float(np.dot(c.direction, ax))))))
    rod_end_pt = a + ax * t_end
    offset = line_distance(rod_end_pt, c.origin, c.direction)
    if end is None:
        mid = (t_bottom + t_mouth) / 2
        return Socket(joint, rod.name, None, _t(bottom), _t(d), 2 * c.radius, abs(t_mouth - t_bottom), blind,
                      0.0, offset, tilt, station=float(mid))
    gap = float(np.dot(rod_end_pt - bottom, d)) if blind else 0.0
    if not blind:
        bottom = on_hole_axis(t_end)
    depth = abs(t_mouth - t_end)
    return Socket(joint, rod.name, end, _t(bottom), _t(d), 2 * c.radius, depth, blind, gap, offset, tilt)


def _chamfers(solid, rod: Rod, a: np.ndarray, ax: np.ndarray) -> list[tuple[float, float]]:
    """The extents along the rod of the solid's conical faces coaxial with it (mouth chamfers)."""
    out = []
    for k in cones(solid):
        if abs(float(np.dot(k.direction, ax))) < math.cos(math.radians(TILT_DEG)):
            continue
        if line_distance(k.origin, a, ax) > OFFSET_TOL * rod.diameter / 2:
            continue
        out.append(tuple(sorted((float(np.dot(k.origin + k.direction * v - a, ax)) for v in (k.v0, k.v1)))))
    return out


def _through_chamfer(t_mouth: float, outward: float, chamfers: list[tuple[float, float]]) -> float:
    """The mouth moved out over a chamfer that starts where the bore ends (outward = +1: towards
    larger t)."""
    for c0, c1 in chamfers:
        if outward > 0 and abs(c0 - t_mouth) <= JOIN_TOL:
            return c1
        if outward < 0 and abs(c1 - t_mouth) <= JOIN_TOL:
            return c0
    return t_mouth


def sockets_of(rod: Rod, joint: str, solid, cyls: list[Cyl] | None = None) -> list[Socket]:
    """The sockets (rod ends) and sleeves of `rod` in one solid. A socket's depth runs to the outer
    end of a coaxial chamfer at its mouth (cogniframe's own sockets have a 0.5 mm one: their depth
    is bottom -> chamfer's outer edge)."""
    a, ax, L = np.asarray(rod.a), np.asarray(rod.axis), rod.length
    faces = []
    for c in cyls if cyls is not None else cylinders(solid):
        ext = _coaxial(c, rod, a, ax, L)
        if ext is not None:
            faces.append((*ext, c))
    out = []
    cham = _chamfers(solid, rod, a, ax) if faces else []
    for t0, t1, c in _bores(faces):
        if t0 <= END_TOL and t1 > END_TOL:  # over end a: the bottom at t0
            out.append(_measure(joint, solid, rod, "a", t0, _through_chamfer(t1, 1, cham), 0.0, c, a, ax))
        elif t1 >= L - END_TOL and t0 < L - END_TOL:  # over end b: the bottom at t1
            out.append(_measure(joint, solid, rod, "b", t1, _through_chamfer(t0, -1, cham), L, c, a, ax))
        elif t0 > END_TOL and t1 < L - END_TOL:
            out.append(_measure(joint, solid, rod, None, t0, t1, t0, c, a, ax))
    return out


def near(rod: Rod, box: tuple[np.ndarray, np.ndarray], margin: float = NEAR) -> bool:
    lo = np.minimum(rod.a, rod.b) - rod.diameter / 2 - margin
    hi = np.maximum(rod.a, rod.b) + rod.diameter / 2 + margin
    return bool(np.all(box[0] <= hi) and np.all(box[1] >= lo))


def find_sockets(rods: list[Rod], others, boxes: dict | None = None) -> list[Socket]:
    """Every socket and sleeve of every rod in the other solids (NamedSolids; `boxes`: their
    `geometry.bbox` by name, when known)."""
    boxes = boxes if boxes is not None else {ns.name: bbox(ns.solid) for ns in others}
    cyl_cache: dict[str, list[Cyl]] = {}
    out = []
    for rod in rods:
        for ns in others:
            if not near(rod, boxes[ns.name]):
                continue
            if ns.name not in cyl_cache:
                cyl_cache[ns.name] = cylinders(ns.solid)
            out.extend(sockets_of(rod, ns.name, ns.solid, cyl_cache[ns.name]))
    return out


def nearest_hole(rod: Rod, end: str, others, reach: float = 15.0) -> tuple[str, float, float, float] | None:
    """For a loose rod end: the closest hole of a rod's size in any solid within `reach` mm, as
    (solid, bore, axis offset at the rod end mm, tilt deg): what the CAD may have meant."""
    p, d = np.asarray(rod.end(end)), np.asarray(rod.direction_from(end))
    r = rod.diameter / 2
    best = None
    for ns in others:
        lo, hi = bbox(ns.solid)
        if np.any(p < lo - reach) or np.any(p > hi + reach):
            continue
        for c in cylinders(ns.solid):
            if not c.hole or not (BORE_MIN * r <= c.radius <= BORE_MAX * r):
                continue
            mid = c.at((c.v0 + c.v1) / 2)
            if np.linalg.norm(mid - p) > reach:
                continue
            tilt = math.degrees(math.acos(min(1.0, abs(float(np.dot(c.direction, d))))))
            off = line_distance(p, c.origin, c.direction)
            score = off + tilt / 10
            if best is None or score < best[0]:
                best = (score, ns.name, 2 * c.radius, off, tilt)
    return None if best is None else best[1:]

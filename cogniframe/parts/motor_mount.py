"""TPU motor mount: a flat seat for the motor that clips around the two arm rods.

Local frame (partlist): origin on the motor axis at the arm centreline, z up, the seat's top face at
z = `seat_z` and horizontal; `arm_rods` gives (point, direction) of each arm rod, sloping down
toward the core by `arm_slope_deg`.

Printed upside down, the seat on the bed (z_print = seat_z - z_local). Pieces:
* the seat plate, `width` square, aligned with the arm, `wall + 1.5` thick;
* per rod, a clip sleeve (OD = bore + 2 wall) with a vertical web down to the seat, so nothing
  hangs in print; it runs from where the seat leaves a full `wall` above the bore, down-slope for
  `width`. Anything above the seat plane (the up-slope ends) is cut flat by the bed;
* through holes: each rod's bore (full length, so the rod slides through), the square motor bolt
  pattern (`bolt_spacing`, `screw_clearance`), and the centre hole `shaft_hole`.
"""

from __future__ import annotations

import math

import numpy as np

from ..partlist import PartSpec
from .joint import FLIP_X, Built, above_bed, fuse_all, horizontal, prism, sloped_sleeve, transform, vec


def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(FLIP_X, (0.0, 0.0, float(part.param("seat_z"))))


def build(part: PartSpec) -> Built:
    import cadquery as cq

    m = print_from_local(part)
    rot, shift = m[:3, :3], m[:3, 3]
    seat_z = float(part.param("seat_z"))
    width = float(part.param("width"))
    bore = float(dict(part.params).get("bore", 3.1))
    wall = part.wall
    r = bore / 2 + wall
    plate_t = min(wall + 1.5, seat_z)
    rods = [(np.asarray(p, float), np.asarray(d, float) / np.linalg.norm(d)) for p, d in part.param("arm_rods")]
    a_h = horizontal(rods[0][1])
    lat = np.array([-a_h[1], a_h[0], 0.0])

    def to_print(p):
        return rot @ p + shift

    half = width / 2
    corners = [to_print(a_h * sa * half + lat * sl * half)[:2] for sa, sl in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    pieces = [prism(corners, 0.0, plate_t)]
    cutters = []
    for p, d in rods:
        dz = float(d[2])
        cos_a = math.sqrt(1 - dz * dz)
        rb = bore / 2 / max(cos_a, 1e-6)
        # Where the seat still leaves a full wall above the bore (going down-slope from there).
        if abs(dz) > 1e-9:
            s_lo = (seat_z - wall - rb - p[2]) / dz
            s_lo = min(max(s_lo, -half), 0.0) if dz < 0 else max(min(s_lo, half), 0.0) - width
        else:
            s_lo = -half
        start, dp = to_print(p + d * s_lo), rot @ d
        if dp[2] < 0:  # build the sleeve rising in print
            start, dp = to_print(p + d * (s_lo + width)), -dp
        pieces.append(sloped_sleeve(start, dp, width, r) if abs(dp[2]) > 1e-9 else
                      cq.Solid.makeCylinder(r, width, vec(start), vec(dp)))
        through = 4 * width
        cutters.append(cq.Solid.makeCylinder(bore / 2, 2 * through, vec(to_print(p - d * through)), vec(rot @ d)))
    body = above_bed(fuse_all(pieces))
    b = float(part.param("bolt_spacing")) / 2
    hole_r = float(part.param("screw_clearance")) / 2
    for sa, sl in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        c = to_print(a_h * sa * b + lat * sl * b)
        cutters.append(cq.Solid.makeCylinder(hole_r, 200.0, cq.Vector(c[0], c[1], -1.0), cq.Vector(0, 0, 1)))
    c = to_print(np.zeros(3))
    cutters.append(cq.Solid.makeCylinder(float(part.param("shaft_hole")) / 2, 200.0, cq.Vector(c[0], c[1], -1.0), cq.Vector(0, 0, 1)))
    shape = body.cut(fuse_all(cutters)).clean()
    solids = shape.Solids()
    if len(solids) != 1:
        raise RuntimeError(f"motor mount geometry produced {len(solids)} solids instead of 1")
    return Built(solids[0], m)

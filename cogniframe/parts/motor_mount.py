"""TPU motor mount: a flat seat for the motor that clips around the two arm rods.

Local frame (partlist): origin on the motor axis at the arm centreline, z up, the seat's top face at
z = `seat_z` and horizontal; `arm_rods` gives (point, direction) of each arm rod, sloping down
toward the core by `arm_slope_deg`.

Printed upside down, the seat on the bed (z_print = seat_z - z_local). Pieces:
* the seat plate, `width` square, aligned with the arm, `wall + 1.5` thick;
* per rod, a clip sleeve (OD = bore + 2 wall) with a vertical web down to the seat, so nothing
  hangs in print (a level arm: a D-section sleeve, its flat sides down to the seat); it runs from
  where the seat leaves a full `wall` above the bore, down-slope for `width`. Anything above the
  seat plane (the up-slope ends) is cut flat by the bed;
* through holes: each rod's bore (full length, so the rod slides through), the motor's holes
  (`holes`: the catalogue pattern across the shaft, turned onto the arm axis and across it, only
  the pairs that clear the rods; `screw_clearance`), and the centre hole `shaft_hole`; under each
  hole a counterbore (`counterbore_d`) from `grip` below the seat down through anything there (a
  clip sleeve or web), so the screw head bears on flat plate and the stock screw engages the
  motor's thread (partlist.motor_screw).
"""

from __future__ import annotations

import math

import numpy as np

from ..partlist import PartSpec
from .joint import (
    FLIP_X,
    SKIRT,
    STACK_SNAP,
    Built,
    above_bed,
    dsleeve,
    fuse_all,
    horizontal,
    prism,
    sloped_sleeve,
    transform,
    vec,
)


HOLE_CLEAR = 0.2  # mm: a hole's side never within this of a clip web's flat face


def _skirt(r: float, rod_point, rod_dir, holes) -> float:
    """The clip web's half-width over the sleeve radius: SKIRT, or a narrower web where a hole's
    side would lie on or next to the web's face. A cylinder tangent to a plane breaks OCC's cut:
    carbon with 1.45 mm walls put the web's faces 2.7 mm from the rod, the side of a bolt hole
    2.7 mm from it too, and the cut gave the mount plus a phantom solid of 210 mm^3."""
    h = horizontal(rod_dir)
    across = np.array([-h[1], h[0], 0.0])
    offsets = [(float((np.asarray(c, float) - rod_point) @ across), hr) for c, hr in holes]
    for f in (SKIRT, SKIRT - 0.1, SKIRT - 0.2):
        w = f * r
        if all(abs(o + side * hr - face) >= HOLE_CLEAR for o, hr in offsets for side in (-1, 1) for face in (-w, w)):
            return f
    return SKIRT


def _parallel(rods):
    """The rods the two clip sleeves are built on: the second moved onto the line exactly parallel
    to the first, through the same cross-section. The part's rods are stored to 1e-6 mm: in a
    rectangle the pair came out ~2e-6 mm apart along the arm, and where thick walls (joints.wall
    4.6-6 mm) make the two sleeves overlap, their end caps and webs, 2e-6 mm out of plane, fused
    into faces of 1e-6 mm^2 and an STL that was not watertight. The sleeves only: the bores are
    cut where the rods are. A square box's pair is parallel to round-off and kept as it is."""
    (p0, d0), (p1, d1) = rods
    along = float((p1 - p0) @ d0)
    if abs(along) <= 1e-9 and float(np.abs(d1 - d0).max()) <= 1e-9:
        return rods
    if abs(along) > STACK_SNAP or float(np.abs(d1 - d0).max()) > STACK_SNAP:
        raise ValueError(f"motor mount rods are not a parallel pair ({along:g} mm apart along the arm)")
    return [(p0, d0), (p1 - d0 * along, d0)]


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
    clips = _parallel(rods)
    a_h = horizontal(rods[0][1])
    lat = np.array([-a_h[1], a_h[0], 0.0])

    def to_print(p):
        return rot @ p + shift

    half = width / 2
    corners = [to_print(a_h * sa * half + lat * sl * half)[:2] for sa, sl in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    pieces = [prism(corners, 0.0, plate_t)]
    cutters = []
    hole_r = float(part.param("screw_clearance")) / 2
    bolts = [np.array([x, y, 0.0]) for x, y in part.param("holes")]
    cb_r = float(part.param("counterbore_d")) / 2
    holes = [(c, hole_r) for c in bolts] + [(np.zeros(3), float(part.param("shaft_hole")) / 2)]
    grip = float(part.param("grip"))
    for (p, d), (pc, dc) in zip(rods, clips):
        dz = float(dc[2])
        cos_a = math.sqrt(1 - dz * dz)
        rb = bore / 2 / max(cos_a, 1e-6)
        # Where the seat still leaves a full wall above the bore (going down-slope from there).
        if abs(dz) > 1e-9:
            s_lo = (seat_z - wall - rb - pc[2]) / dz
            s_lo = min(max(s_lo, -half), 0.0) if dz < 0 else max(min(s_lo, half), 0.0) - width
        else:
            s_lo = -half - float(pc @ dc)  # across the seat, its ends flush with the seat's edges
        start, dp = to_print(pc + dc * s_lo), rot @ dc
        if dp[2] < 0:  # build the sleeve rising in print
            start, dp = to_print(pc + dc * (s_lo + width)), -dp
        if abs(dp[2]) > 1e-9:
            pieces.append(sloped_sleeve(start, dp, width, r, skirt=_skirt(r, pc, dc, holes + [(c, cb_r) for c in bolts])))
        else:
            # A level arm (frame.knee_height puts the knee level with the core link): a D-section
            # sleeve from the bed, as the joints' level sockets. A bare cylinder stood 0.5 mm
            # above the seat plate there (bamboo, frame.knee_height 0.38), and the mount printed
            # in three pieces.
            pieces.append(dsleeve(start, dp, width, float(start[2]), r))
        through = 4 * width
        cutters.append(cq.Solid.makeCylinder(bore / 2, 2 * through, vec(to_print(p - d * through)), vec(rot @ d)))
    body = above_bed(fuse_all(pieces))
    for centre, hr in holes:
        c = to_print(centre)
        cutters.append(cq.Solid.makeCylinder(hr, 200.0, cq.Vector(c[0], c[1], -1.0), cq.Vector(0, 0, 1)))
    for centre in bolts:  # the heads' seats: up from `grip` as printed (down from the plate in the air)
        c = to_print(centre)
        cutters.append(cq.Solid.makeCylinder(cb_r, 200.0, cq.Vector(c[0], c[1], grip), cq.Vector(0, 0, 1)))
    shape = body.cut(fuse_all(cutters)).clean()
    solids = shape.Solids()
    if len(solids) != 1:
        raise RuntimeError(f"motor mount geometry produced {len(solids)} solids instead of 1")
    return Built(solids[0], m)

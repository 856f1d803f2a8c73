"""The joints' geometry in plan and in print, without the CAD kernel (pure numpy): how a joint
printed on its side lies on the bed (`side_print`: the knee, the tab core link; each joint kind's
`print_from_local` is its module's in families/joint_kinds/) and its sockets there (`map_sockets`,
`PSocket`); the knee in plan (its rigid leg's start, the hub where that start cannot join it, the
arm bridge, the living hinge's web); the core link's seat and the flat link's bands. The joint
kinds' closed forms and solids (families/joint_kinds/, on parts/joint_solid.py's pieces) and the
joint FE (analysis/joints/) read the same plan, so estimate, solid and mesh agree; importing this
module imports no CAD kernel, so `check` stays fast."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..frame import HINGE_GAP
from .record import PARALLEL_TOL, PartSpec
JOIN = 0.4  # mm, least overlap of the knee's rigid leg sleeve with the arm bridge, each way (one 0.4 mm line)
TAB_CLEAR = 0.2  # mm: a core link's tab top never within this of a sleeve's top (no coincident top faces)


@dataclass(frozen=True, eq=False)
class PSocket:
    """A socket mapped into print coordinates."""

    port: np.ndarray
    direction: np.ndarray
    seat: float
    depth: float
    bore: float
    rod: str

    def at(self, s: float) -> np.ndarray:
        return self.port + self.direction * s

    @property
    def bottom(self) -> np.ndarray:
        return self.at(self.seat)

    @property
    def mouth(self) -> np.ndarray:
        return self.at(self.seat + self.depth)


# -- print orientation -----------------------------------------------------------------------

def transform(rot: np.ndarray, shift) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rot
    m[:3, 3] = shift
    return m


FLIP_X = np.diag([1.0, -1.0, -1.0])  # 180 deg about x: upside down, still right-handed


def side_print(part: PartSpec) -> np.ndarray:
    """4x4 print <- local transform of a joint printed on its side (the knee, the tab core link):
    the side normal (`_side_normal`) vertical, the arm direction along x, the lowest socket end
    one sleeve radius above the bed."""
    r = (part.sockets[0].bore + 2 * part.wall) / 2
    dirs = np.array([s.direction for s in part.sockets], float)
    w = _side_normal(part, dirs)
    x = arm_direction(part)
    x = x - w * (x @ w)
    x /= np.linalg.norm(x)
    y = np.cross(w, x)
    rot = np.vstack([x, y, w])
    ends = np.array([p for s in part.sockets for p in (s.port, s.mouth())], float)
    low = float((ends @ w).min())
    return transform(rot, (0.0, 0.0, r - low))


def _side_normal(part: PartSpec, dirs: np.ndarray) -> np.ndarray:
    """The lateral axis (vertical in print): normal to the legs' plane (knee) or to the arm and
    strut (core link). Every socket lies in that plane (frame.frame_of keeps each corner's fold in the
    vertical plane through the corner and its core link, in a rectangle too), and the arm pair is
    offset across it, so the two arm sockets stack into one block."""
    arm = arm_direction(part)
    others = [d for d in dirs if d @ arm < 1 - PARALLEL_TOL]
    w = np.cross(others[0], others[1]) if len(others) >= 2 else np.zeros(3)
    if others and np.linalg.norm(w) < 1e-6:
        # one other socket, or two in one line (frame.knee_inset: 0, straight sides: the upper and
        # lower legs are one vertical line; the knee's plane is then the legs' and the arms')
        w = np.cross(arm, others[0])
    elif not others:  # arm sockets only (frame.struts: false): lie the two arm sleeves side by side on the bed
        pair = [np.asarray(s.port, float) for s in part.sockets if np.asarray(s.direction) @ arm > 1 - PARALLEL_TOL]
        w = np.cross(arm, np.cross(arm, pair[1] - pair[0]))
    w /= np.linalg.norm(w)
    # Deterministic sign; a mirrored prototype (fr) uses the mirrored reference, so its print is
    # the exact mirror image of the fl part's.
    ref = np.array([-1.0, 1.0, 0.25]) if dict(part.params).get("mirror") else np.array([1.0, 1.0, 0.25])
    return w if w @ ref >= 0 else -w


def arm_direction(part: PartSpec) -> np.ndarray:
    """Direction shared by the two parallel arm sockets."""
    dirs = [np.asarray(s.direction, float) for s in part.sockets]
    for i in range(len(dirs)):
        for k in range(i + 1, len(dirs)):
            if dirs[i] @ dirs[k] > 1 - PARALLEL_TOL:
                return dirs[i]
    raise ValueError(f"{part.name}: no pair of parallel (arm) sockets")


def map_sockets(part: PartSpec, m: np.ndarray) -> list[PSocket]:
    out = []
    for s in part.sockets:
        port = m[:3, :3] @ np.asarray(s.port, float) + m[:3, 3]
        d = m[:3, :3] @ np.asarray(s.direction, float)
        out.append(PSocket(port, d / np.linalg.norm(d), float(s.seat), float(s.depth), float(s.bore), s.rod))
    return out


def horizontal(d) -> np.ndarray:
    h = np.array([d[0], d[1], 0.0])
    return h / np.linalg.norm(h)


def split_arms(socks: list[PSocket]) -> tuple[list[PSocket], list[PSocket]]:
    """(the parallel arm sockets, the others)."""
    for i in range(len(socks)):
        par = [s for s in socks if s.direction @ socks[i].direction > 1 - PARALLEL_TOL]
        if len(par) > 1:
            return par, [s for s in socks if s not in par]
    raise ValueError("no parallel arm sockets")


# -- the knee in plan -----------------------------------------------------------------------

def footprint_rect(s: PSocket, start: float, end: float, half: float, grow: float = 0.0):
    """xy corners of a sleeve's footprint from `start` to `end` along it, grown by `grow`."""
    d = horizontal(s.direction)
    lat = np.array([-d[1], d[0]])
    a = s.port[:2] + d[:2] * (start - grow)
    b = s.port[:2] + d[:2] * (end + grow)
    h = half + grow
    return [a - lat * h, b - lat * h, b + lat * h, a + lat * h]


@dataclass(frozen=True)
class Hinge:
    """The knee's living-hinge web in print coordinates (xy points, z from 0 to `height`)."""

    start: np.ndarray  # xy, inside the upper-leg sleeve
    end: np.ndarray  # xy, inside the arm bridge
    normal: np.ndarray  # xy unit vector across the web (the bending direction)
    thickness: float
    height: float
    probe: np.ndarray  # xy on the web's centre line, in the middle of the slot that frees the leg


def knee_hinge(part: PartSpec) -> Hinge:
    """Where the knee's hinge web runs (pure numpy; the CAD and the tests share it)."""
    m = side_print(part)
    socks = map_sockets(part, m)
    r = (part.sockets[0].bore + 2 * part.wall) / 2
    h = float(part.param("hinge_thickness"))
    arms, legs = split_arms(socks)
    a = arms[0]
    s_back = a.seat - part.wall
    hinged = min(legs, key=lambda s: float(s.direction @ a.direction))
    c = hinged.at(hinged.seat - part.wall)
    d = horizontal(a.direction)
    lat = np.array([-d[1], d[0], 0.0])
    off = float((c - a.port)[:2] @ lat[:2])
    off = float(np.clip(off, -(r - h / 2 - 0.3), r - h / 2 - 0.3))
    q = a.port + d * (s_back + 0.6) + lat * off
    e = (q - c)[:2] / np.linalg.norm((q - c)[:2])
    probe = (a.port + d * (s_back - HINGE_GAP / 2) + lat * off)[:2]
    # The web stands on the bed up to just above the legs' top lines: a web top level with the
    # hinged leg's round top touched it along a line, and OCC's mesher left that face out of the
    # STL (carbon, 153 x 190.6 x 168.2 box). Clear of the arm sleeves' levels too.
    top = clear_of(max(float(s.port[2]) for s in legs) + r, sleeve_levels(socks, r))
    return Hinge(c[:2] - e * 0.6, q[:2], np.array([-e[1], e[0]]), h, float(top), probe)


def rigid_leg_start(a: PSocket, s: PSocket, r: float, s_back: float, wall: float) -> float | None:
    """Where the rigid (lower) leg's sleeve starts, along it from the port, so that it joins the arm
    block (`a`: an arm socket, the block from `s_back` along the arm, r either side): at its back
    face (seat - wall) when the sleeve's inner back corner lies `JOIN` inside the block's footprint
    there; else further back, just far enough, but never behind the knee centre (t < 0). None when
    no such start puts that corner inside the block on every side: the leg leaves the knee (nearly)
    square to the arms and the seat puts the block's back face beyond the sleeve's reach (a large
    `joints.seat`, d22: 5.98 mm seat, leg at 93 deg); the hub joins them then (`knee_hub`). The
    leg joins the knee only through that overlap (the hinged leg is cut free of both), and it
    shrinks as the leg leans back from the arms: with 2.3 mm rods (r 2.4) and a 91 mm frame the
    leg, at 107 deg to the arms, missed the block and the knee fell apart in two. Pure numpy; in
    plan (every knee sleeve stands on the bed)."""
    t0 = s.seat - wall
    dx = horizontal(a.direction)
    lat = np.array([-dx[1], dx[0], 0.0])
    u = horizontal(s.direction)
    n = np.array([-u[1], u[0], 0.0])
    n = n if n @ dx >= 0 else -n  # across the leg, towards the arms
    side = 1.0 if u @ lat >= 0 else -1.0  # which side of the arms the leg leaves on
    p0 = (s.port - a.port) * np.array([1.0, 1.0, 0.0]) + n * r  # the inner back corner at t = 0
    # each margin is c + k t (mm inside the block): along the arm past the block's back face, and
    # across it inside the block's side the leg leaves on, then inside its other side
    margins = [(float(p0 @ dx) - s_back - JOIN, float(u @ dx)), (r - side * float(p0 @ lat) - JOIN, -side * float(u @ lat)),
               (r + side * float(p0 @ lat) - JOIN, side * float(u @ lat))]
    t = t0
    for c, k in margins[:2]:
        if c + k * t < 0 and k < 0:
            t = min(t, -c / k)  # moving the start back raises this margin
    if t < min(0.0, t0) or any(c + k * t < -1e-9 for c, k in margins):
        return None
    return t


def knee_hub(a: PSocket, s: PSocket, r: float, s_back: float, wall: float, web: Hinge) -> np.ndarray:
    """The rigid leg's hub in plan (xy polygon): the hull of its sleeve's back face and the arm
    block's back face, cut back to `HINGE_GAP` from the hinge web's side (the web and the slots
    either side of it stay as `knee_hinge` draws them). Only where no sleeve start joins the leg to
    the block (`rigid_leg_start` is None). Pure numpy."""
    t0 = s.seat - wall
    hull = np.array(convex_hull(np.array(footprint_rect(a, s_back, s_back, r) + footprint_rect(s, t0, t0, r))))
    centre = s.at(t0)[:2]
    sign = 1.0 if float((centre - web.start) @ web.normal) >= 0 else -1.0
    keep = web.thickness / 2 + HINGE_GAP  # the kept side: sign * (p - web.start) . normal >= keep
    return _clip(hull, sign * web.normal, keep + sign * float(web.start @ web.normal))


def _clip(poly: np.ndarray, n: np.ndarray, c: float) -> np.ndarray:
    """The part of convex polygon `poly` (xy, in order) where p . n >= c (one Sutherland-Hodgman pass)."""
    out = []
    for i in range(len(poly)):
        p, q = poly[i], poly[(i + 1) % len(poly)]
        fp, fq = float(p @ n) - c, float(q @ n) - c
        if fp >= 0:
            out.append(p)
        if fp * fq < 0:
            out.append(p + (q - p) * (fp / (fp - fq)))
    return np.array(out)


def knee_bridge(a: PSocket, joined: list[tuple[PSocket, float]], r: float, s_back: float) -> float:
    """Where the knee's bridge ends, along the arm from its port (pure numpy). The arm pair's
    sleeves are joined by a solid bridge, the old arm block's section (bed to the top arm), from
    their back face `s_back` over one sleeve OD (the authors' U bracket: two sleeves and a bridge
    about one OD wide), longer where a rigid leg's inner back corner would not lie `JOIN` inside
    it (each leg in `joined` with its sleeve start joins the knee there: `rigid_leg_start`).
    Where less than a millimetre of sleeve would be left past it, the bridge runs to the mouths
    (the old block, no sliver)."""
    end = s_back + 2 * r
    dx = horizontal(a.direction)
    for s, t in joined:
        u = horizontal(s.direction)
        n = np.array([-u[1], u[0], 0.0])
        n = n if n @ dx >= 0 else -n
        corner = (s.port - a.port) * np.array([1.0, 1.0, 0.0]) + u * t + n * r
        end = max(end, float(corner @ dx) + JOIN)
    mouth = a.seat + a.depth
    return mouth if end > mouth - 1.0 else end


# -- the core link's seat ---------------------------------------------------------------------

def seat_geometry(part: PartSpec):
    """The plate corner a core link seats against, in its local frame: (corner xy, signs (sx,
    sy) pointing out of the plate, plate bottom z, plate top z). The plate is
    {sx (x - cx) <= 0, sy (y - cy) <= 0, z0 <= z <= z1}."""
    params = dict(part.params)
    c, sign = link_plate_corner(params)
    z1 = float(params["plate_top_z"])
    return c, sign, -z1, z1  # the link's node lies at the plate's mid-height


def link_plate_corner(params: dict) -> tuple[np.ndarray, np.ndarray]:
    """The plate corner a core link seats against, in the link's local frame (x, y), and the
    signs (sx, sy) pointing out of the plate: the plate is {sx (x - cx) <= 0, sy (y - cy) <= 0}."""
    corner = np.asarray(params["plate_corner"], float)[:2]
    return corner, np.sign(corner - np.asarray(params["bolt_hole"], float)[:2])  # the bolt is inside the plate


def seat_plan(params: dict, ports, d: np.ndarray, s_back: float, r: float) -> list[np.ndarray]:
    """A core link's seat in plan, in its local frame, before the plate's corner is cut out and the
    print height clips it: the quadrilateral from 1 mm inside the arm block's back (the arm
    `ports`, direction `d`, sockets' backs `s_back` out) to past the plate corner, a millimetre
    past the block's width on both sides."""
    corner, _ = link_plate_corner(params)
    e_in = -np.array([d[0], d[1]]) / np.hypot(d[0], d[1])  # horizontal, toward the core
    e_w = np.array([-e_in[1], e_in[0]])
    u_b = min(float((np.asarray(p) + d * s_back)[:2] @ e_in) for p in ports) - 1.0
    w_half = max(abs(float(np.asarray(p)[:2] @ e_w)) for p in ports) + r + 1.0
    u_far = float(corner @ e_in) + w_half + 1.0
    return [e_in * u_b - e_w * w_half, e_in * u_far - e_w * w_half, e_in * u_far + e_w * w_half, e_in * u_b + e_w * w_half]


# -- the flat core link (level arms) ---------------------------------------------------------------
# With level arms (frame.level_arms) every core-link socket but the strut is parallel to the
# plate, so the link prints flat and upside down: its top (the tab's top, on the plate) on the bed,
# the arm sleeves lying on the bed side by side, the strut rising with a web under it. Nothing then
# has to be extruded across the arm pair: each arm's sleeve joins the bolt pad through its own band
# (the tab, split), and the seat is the bands' part below the plate top outside the plate, down to
# the plate's bottom: it bears on the plate's edges, and it makes each band 9 mm deep (at a 3 mm
# plate) from its sleeve to the plate, where the hinge the bare arms hang on bends (cubic in depth).
# A band runs into its sleeve to `BAND_PAST` beyond the socket's bottom: the rod's moment then
# enters the band through the socket's side wall. Ending at the sleeve's back face (the rod's
# moment through the thin ring behind the socket's bottom) gave the bare arms' hinge 38 N mm/rad at
# 25 mm spacing, ending 1.3 mm past the socket's bottom 113 (carbon, joint FE).
BAND_PAST = 1.5  # mm
BAND_BACK = 0.2  # mm
BAND_NARROWER = 0.5  # mm: a band's sides stand this far inside its sleeve's (never tangent to its round: an STL with open edges; at 0.3 carbon 12 mm gave one)
PAD_SIDES = 16  # the bolt pad's polygon (circumscribes the pad's circle)
TEAR_WEB = 1.6  # mm: the web under a teardrop arm sleeve (four 0.4 mm lines)
TEAR_MIN = 1.0  # mm: least web height below a teardrop's apex; lower, the arm sleeve is a D section


def link_is_flat(sockets) -> bool:
    """Whether a core link prints flat: its parallel (arm) sockets are level in the frame."""
    dirs = [np.asarray(s.direction, float) for s in sockets]
    arms = [d for d in dirs if sum(float(d @ e) > 1 - PARALLEL_TOL for e in dirs) > 1]
    return len(arms) >= 2 and all(abs(float(d[2])) < 1e-5 for d in arms)


def link_bed_z(params: dict, sockets, r: float) -> float:
    """The flat link's bed, as a height in its local frame (it prints upside down): the tab's top,
    or a sleeve's top where one stands higher."""
    tops = [float(np.asarray(p, float)[2]) + r for s in sockets for p in (s.port, np.asarray(s.port) + np.asarray(s.direction) * (s.seat + s.depth))]
    return max(float(params["plate_top_z"]) + float(params["tab_thickness"]), *tops)


def hull_ccw(pts) -> np.ndarray:
    """Convex hull of 2-D points rounded to 1e-9, counter-clockwise from the lowest x (monotone
    chain): the flat link's bands and plate, and the closed forms' hull areas."""
    pts = sorted(map(tuple, np.round(np.asarray(pts, float), 9)))

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]) <= 0:
                out.pop()
            out.append(p)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def link_bands(params: dict, sockets, wall: float, r: float) -> list[np.ndarray]:
    """The flat link's bands in plan (local xy, counter-clockwise convex polygons): for each socket
    the hull of its sleeve's back end (from its back face to `BAND_PAST` beyond the socket's
    bottom, and past where a sloped sleeve's web begins; `BAND_NARROWER` inside the sleeve's sides)
    and the bolt pad (a polygon round the screw hole, one `wall` outside it)."""
    bolt = np.asarray(params["bolt_hole"], float)[:2]
    r_pad = (float(params["screw_clearance"]) / 2 + wall) / math.cos(math.pi / PAD_SIDES)
    pad = [bolt + r_pad * np.array([math.cos(a), math.sin(a)]) for a in 2 * math.pi * (np.arange(PAD_SIDES) + 0.5) / PAD_SIDES]
    out = []
    for s in sockets:
        d = np.asarray(s.direction, float)
        h = d[:2] / np.linalg.norm(d[:2])
        n = np.array([-h[1], h[0]])
        t0 = s.seat - wall
        # a sloped sleeve's web begins r sin a ahead of its back
        sa, ca = abs(float(d[2])), float(np.linalg.norm(d[:2]))
        # from BAND_BACK behind the sleeve's back face: a band side turning there met the back
        # face's edge on the sleeve's round (an STL with open edges: a carbon box 304.6 mm square)
        ends = [(np.asarray(s.port, float) + d * t)[:2] for t in (t0 - BAND_BACK, s.seat + BAND_PAST + r * sa / ca)]
        half = r - BAND_NARROWER
        out.append(hull_ccw([c + n * k * half for c in ends for k in (-1.0, 1.0)] + pad))
    return out


def link_plate_region(params: dict, big: float = 500.0) -> np.ndarray:
    """The core plate's corner near the link in plan (local xy, counter-clockwise): the plate is
    {sx (x - cx) <= 0, sy (y - cy) <= 0}."""
    c, sign = link_plate_corner(params)
    return hull_ccw([c, c - np.array([sign[0], 0.0]) * big, c - sign * big, c - np.array([0.0, sign[1]]) * big])


# -- heights and hulls -------------------------------------------------------------------------

def clear_of(z: float, levels, gap: float = TAB_CLEAR) -> float:
    """`z`, or the least height above it that is `gap` clear of every one of `levels` (moving up
    past one level can bring it near the next)."""
    for level in sorted(levels):
        if abs(z - level) < gap:
            z = level + gap
    return z


def sleeve_levels(socks: list[PSocket], r: float) -> list[float]:
    """The heights where a level sleeve's surface turns (its axis: flat sides meet the round top)
    or is tangent to a plane (its top line): a flat top there meets the sleeve along a line."""
    return [float(s.port[2]) + dz for s in socks for dz in (0.0, r)]


def convex_hull(pts: np.ndarray) -> list[np.ndarray]:
    """Corners of the convex hull of 2-D points, counter-clockwise from where Qhull starts: the
    CAD's hub prisms are drawn from them (`hull_ccw` is the closed forms' and the flat link's)."""
    from scipy.spatial import ConvexHull  # where used: importing the plan stays light

    h = ConvexHull(pts)
    return [pts[i] for i in h.vertices]

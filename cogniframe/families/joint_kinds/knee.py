"""The knee: it joins an arm pair to the upper and lower legs, and the sides fold at it
("fold as you assemble"; on impact the hourglass closes).

Printed lying on its side: every socket direction lies in the frame's diagonal side plane and the
two arm rods are offset across it, so with the lateral axis vertical every socket is parallel to
the bed and the arm sockets stack (parts/joint_plan.py `side_print`). The arm pair is a U: a bridge
of the block's section over one sleeve OD at their back, past it the lower sleeve on the bed and
the upper one a teardrop (round top, 45 deg flanks) on a vertical web one wall thick; the legs,
halfway up, are teardrops on such webs too. A web is print support that also ties what it holds:
a D-section pillar from the bed to a sleeve 15 mm up weighs 2.5 times as much.

Living hinge. The legs rotate relative to the arms about the lateral axis, vertical in print, so
the hinge is a vertical TPU web `hinge_thickness` thick (across the bend) from the upper-leg
sleeve to the arm bridge, with a `HINGE_GAP` slot on both sides that frees the upper leg
everywhere else: layer lines run along the bend, the way printed living hinges survive. The lower
leg leaves almost at right angles to the arms and its socket shares a wall with the arm sockets
(the seat is only `joints.seat` from the knee centre), so it stays solid with the arm bridge
(where a large seat keeps their sleeves apart, a hub between their back faces joins them); the
upper leg, which makes the larger angle with the arms and carries the fold, is the one hinged.
frame.py raises the knee's seat until the slot leaves that leg's back end whole. Its plan in print
(the rigid leg's start, the hub, the bridge, the hinge web) is parts/joint_plan.py's."""

from __future__ import annotations

import math

import numpy as np

from ...frame import HINGE_GAP
from ...parts.joint_plan import (PSocket, clear_of, convex_hull, footprint_rect, knee_bridge, knee_hinge, knee_hub,
                                 rigid_leg_start, side_print, sleeve_levels, split_arms)
from ...parts.record import Estimate, PartSpec, Socket
from .kind import JointKind
from .sleeves import arrays, closed, less_bores, side, side_extents
from ..base import polygon_area


class Knee(JointKind):
    node = "knee"
    hinged = True

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        """Closed-form volume/areas of the solid, in print orientation: the arm pair's U and the
        legs' teardrops (`_knee_sleeves`), the hub where a rigid leg's sleeve cannot join the
        bridge (`_knee_hub_area`), the hinge web. Minus the bores."""
        j = spec.joints
        a = arrays(spec, sockets)
        r = a.r
        vol = less_bores(a, sockets)
        a_h = a_v = 0.0
        sd = side(spec, sockets, a)
        vol, a_h, a_v = _knee_sleeves(r, j.wall, sd.z, sd.sleeve_l, sd.par, sd.rest, vol, a_h, a_v)
        hub = _knee_hub_area(sockets, a.dirs, a.ports, sd.w, sd.z, sd.par, sd.rest, r, j.wall)
        vol += hub[0] * hub[1]
        a_h += hub[0]
        a_v += 2 * 2 * r * hub[1]
        top = sd.top(r)
        vol += j.hinge_thickness * 2.7 * top
        a_v += 2 * 2.7 * top
        return closed(spec, sockets, vol, a_h, a_v, side_extents(a, sd))

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        return side_print(part)

    def solid(self, part: PartSpec):
        _, socks, r = self.in_print(part)
        return _knee(part, socks, r)

    def surrogate_reads(self, param: str) -> bool:
        return True  # the hinge's thickness too


def _knee_sleeves(r: float, wall: float, z: np.ndarray, sleeve_l: list[float], par: list[int], rest: list[int],
                  vol: float, a_h: float, a_v: float) -> tuple[float, float, float]:
    """A knee's sleeves added to the running volume and areas, as `_knee` builds them
    (axis heights `z`): the arm pair's bridge (`knee_bridge`: the top arm's D-section, bed up, over
    one sleeve OD from the back; to the mouths where less than a millimetre would be left), the
    lowest arm's D-section sleeve past it, the higher arms' and the legs' teardrops on a `wall`
    thick web (`teardrop`). A rigid leg that joins past one OD lengthens the bridge a little: not
    counted."""
    def d_section(h: float, n: float) -> tuple[float, float, float]:
        return (2 * r * h + math.pi * r**2 / 2) * n, (2 * r + math.pi * r / 2) * n, (2 * h + math.pi * r / 2) * n

    def tear(h: float, n: float) -> tuple[float, float, float]:
        k = r / math.sqrt(2.0)
        z_web = h - r * math.sqrt(2.0) + wall / 2  # where the flanks meet the web, above the bed
        if wall / 2 >= k - 0.05 or z_web <= 0.2:
            return d_section(h, n)
        # round top and 45 deg flanks (3/4 of the circle + the kite r^2) less the kite's tip below
        # the web's top, plus the web
        area = 0.75 * math.pi * r**2 + r**2 - wall**2 / 4 + wall * z_web
        flank = r - wall / math.sqrt(2.0)  # one flank's length
        return area * n, (wall + 0.75 * math.pi * r + flank) * n, (2 * z_web + 0.75 * math.pi * r + flank) * n

    n_arm = sleeve_l[par[0]]
    bridge = 2 * r if 2 * r <= n_arm - 1.0 else n_arm
    low = min(par, key=lambda i: float(z[i]))
    pieces = [d_section(float(z[par].max()), bridge), d_section(float(z[low]), n_arm - bridge)]
    pieces += [tear(float(z[i]), n_arm - bridge) for i in par if i != low]
    pieces += [tear(float(z[i]), sleeve_l[i]) for i in rest]
    for v, ah, av in pieces:
        vol, a_h, a_v = vol + v, a_h + ah, a_v + av
    return vol, a_h, a_v


def _knee_hub_area(sockets: list[Socket], dirs: np.ndarray, ports: np.ndarray, w: np.ndarray, z: np.ndarray,
                   par: list[int], rest: list[int], r: float, wall: float) -> tuple[float, float]:
    """(plan area, height) of the hub that joins a knee's rigid leg to its arm bridge where no
    sleeve start can (parts/joint_plan.py `rigid_leg_start` is None: a large seat): the hull of the two
    back faces, from the bed to halfway up the leg's round top (the hinge-side clip not counted).
    (0, 0) where the leg's sleeve joins the bridge itself."""
    a_i = par[0]
    x = dirs[a_i] - w * (dirs[a_i] @ w)
    x /= np.linalg.norm(x)
    rot = np.vstack([x, np.cross(w, x), w])  # print-like axes: the side plane on the bed, as `_knee` prints it

    def psock(i: int) -> PSocket:
        return PSocket(rot @ ports[i] + np.array([0.0, 0.0, z[i] - float(w @ ports[i])]), rot @ dirs[i], float(sockets[i].seat),
                       float(sockets[i].depth), float(sockets[i].bore), sockets[i].rod)

    a = psock(a_i)
    legs = [psock(i) for i in rest]
    if len(legs) < 2:
        return 0.0, 0.0
    hinged = min(legs, key=lambda s: float(s.direction @ a.direction))
    s_back = a.seat - wall
    area = height = 0.0
    for s in legs:
        if s is hinged or rigid_leg_start(a, s, r, s_back, wall) is not None:
            continue
        t0 = s.seat - wall
        pts = np.array(footprint_rect(a, s_back, s_back, r) + footprint_rect(s, t0, t0, r))
        area += polygon_area(convex_hull(pts))
        height = max(height, float(s.port[2]) + r / 2)
    return area, height



def _arm_bracket(arms: list[PSocket], r: float, s_back: float, bridge_end: float, web: float):
    """The knee's arm pair as a U, not a solid block: the bridge (`knee_bridge`) carries the top
    arm's moment down to the legs (in torsion about the print vertical: its square section twists
    ~40x less than a web one wall thick); past it the lowest arm's sleeve lies on the bed (a
    D-section) and every higher arm's sleeve is a `teardrop` on a `web` thick web, which the print
    needs under it and which ties the pair in its own plane."""
    from ...parts import joint_solid as cad

    stacked = [cad.stacked(arms[0], s) for s in arms]
    low = min(stacked, key=lambda s: float(s.port[2]))
    mouth = low.seat + low.depth
    if bridge_end >= mouth:
        return cad.arm_block(arms, r, s_back)
    pieces = [cad.fuse_all([cad.sleeve(s, s_back, r, bridge_end) for s in stacked]), cad.sleeve(low, bridge_end, r)]
    pieces += [cad.teardrop(s.at(bridge_end), s.direction, mouth - bridge_end, s.port[2], r, web) for s in stacked if s is not low]
    return cad.fuse_all(pieces)


def _knee_leg(s: PSocket, start: float, r: float, web: float):
    """A knee leg's sleeve: a teardrop on a web (the legs lie halfway up the arm pair in print)."""
    from ...parts import joint_solid as cad

    if abs(float(s.direction[2])) < cad.FLAT:
        return cad.teardrop(s.at(start), s.direction, s.seat + s.depth - start, s.port[2], r, web)
    return cad.sleeve(s, start, r)


def _knee(part: PartSpec, socks: list[PSocket], r: float):
    from ...parts import joint_solid as cad

    arms, legs = split_arms(socks)
    a = arms[0]
    s_back = a.seat - part.wall
    web_t = part.wall  # the print webs: one socket wall, at least two extrusion lines (spec checks the wall)
    # The hinged leg makes the larger angle with the arms (see the module docstring).
    hinged = min(legs, key=lambda s: float(s.direction @ a.direction))
    rigid = [s for s in legs if s is not hinged]
    t_back = {id(s): s.seat - part.wall for s in legs}
    web = knee_hinge(part)
    hubs = []  # (plan polygon, top z) of each rigid leg that no sleeve start joins to the block
    joined = []  # (leg, sleeve start) of each rigid leg that its sleeve joins to the bridge
    for s in rigid:
        t = rigid_leg_start(a, s, r, s_back, part.wall)
        if t is None:
            # from the bed to halfway up the leg sleeve's round top: a plane through neither its
            # top line nor the seam of its flat sides (nor the arm block's)
            hubs.append((knee_hub(a, s, r, s_back, part.wall, web), clear_of(float(s.port[2]) + r / 2, sleeve_levels(socks, r))))
        else:
            t_back[id(s)] = t
            joined.append((s, t))
    block = _arm_bracket(arms, r, s_back, knee_bridge(a, joined, r, s_back), web_t)
    rigid_solids = [_knee_leg(s, t_back[id(s)], r, web_t) for s in rigid] + [cad.prism(poly, 0.0, top) for poly, top in hubs]
    # Upper leg, freed from everything rigid by HINGE_GAP ...
    upper = _knee_leg(hinged, t_back[id(hinged)], r, web_t)
    clear = [cad.prism(footprint_rect(a, s_back, a.seat + a.depth, r, HINGE_GAP), -1.0, 1000.0)]
    clear += [cad.prism(footprint_rect(s, t_back[id(s)], s.seat + s.depth, r, HINGE_GAP), -1.0, 1000.0) for s in rigid]
    clear += [cad.prism(convex_hull(_grown(poly, HINGE_GAP)), -1.0, 1000.0) for poly, _ in hubs]
    upper = upper.cut(cad.fuse_all(clear))
    # ... and joined to the arm bridge by the hinge web (`web`): from the centre of the upper leg's
    # back face straight to the bridge's back face.
    body = cad.above_bed(cad.fuse_all([block, *rigid_solids, upper, cad.box_along(web.start, web.end, web.thickness, 0.0, web.height)]))
    return cad.finish(body, [cad.socket_cutter(s) for s in socks])


def _grown(pts: np.ndarray, by: float) -> np.ndarray:
    """The corners of squares `2 by` wide around each point: their hull is the points' hull grown by at least `by`."""
    return np.array([p + np.array([sx, sy]) * by for p in pts for sx in (-1.0, 1.0) for sy in (-1.0, 1.0)])



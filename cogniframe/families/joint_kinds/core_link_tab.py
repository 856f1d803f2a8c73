"""The core link with a tab (core.link: tab): an arm pair's sockets stacked in one block, the
strut's sleeve, a hub between their back faces, and the tab that bolts onto the core plate's
corner with one screw; the seat fills the gap between the block and the plate's edges. Printed
lying on its side, as the knee is (every socket direction in the frame's diagonal side plane, the
arm rods offset across it: parts/joint_plan.py `side_print`), the tab a wall standing on the bed.
On level arms its sockets lie flat and it is the flat link instead (core_link_flat.py), whose
params and screw are these."""

from __future__ import annotations

import math

import numpy as np

from ...frame import CORNER_SIGN, STACK_BOTTOM
from ...materials import SCREWS, STACK_PATTERNS
from ...parts.joint_plan import (PSocket, TAB_CLEAR, clear_of, convex_hull, footprint_rect, link_is_flat,
                                 link_plate_corner, seat_geometry, seat_plan, side_print, sleeve_levels, split_arms)
from ...parts.record import Estimate, HardwareLine, PartSpec, Socket
from ..base import link_hole, polygon_area, rounded
from .kind import JointKind
from .polygons import clip, hull_area
from .sleeves import arrays, closed, less_bores, side, side_extents

# The core link's tab: it carries an arm's thrust moment from the arm block, across the seat at
# the plate corner, onto the plate top. Its bending there is the hinge the bare arms hang on
# (cubic in its depth: at 3 mm the bare arms folded at full thrust; docs/stiffness-model.md).
LINK_TAB = 6.0  # mm


class CoreLinkTab(JointKind):
    """The links are chiral (printed on their side, sleeves on the bed), and the battery holder is a
    rectangle, not a square: a link rotated from fl to fr meets the holder differently, so there is
    always a part for fl/rr and its mirror image for fr/rl. The plate's corner bolt and the tab's
    underside on the plate hold it (its support body)."""

    node = "core_link"
    variant = "tab"
    has_body = True
    chiral = True
    fitted = "bolted"

    @property
    def surrogate_family(self) -> str:
        return self.node

    def plans(self, spec) -> bool:
        return spec.core.link == "tab"

    def claims(self, params: dict, sockets) -> bool:
        return params.get("link", "tab") == "tab" and not link_is_flat(sockets)

    def params(self, spec, frame, corner, origin, sockets) -> list[tuple[str, object]]:
        """The screw, and in the link's local frame (its node at the plate's mid-height) the
        plate-corner hole, the plate top, the plate corner the link seats against (its two edge
        faces), the ESC board's footprint (its centre, at the height of its underside less 0.5 mm)
        and half-side: the tab keeps below the board."""
        screw = SCREWS[spec.core.stack_screw]
        hole = link_hole(spec)
        sx, sy = CORNER_SIGN[corner]
        return [("screw", screw.name), ("screw_clearance", screw.clearance_d),
                ("bolt_hole", rounded(np.array([sx * hole, sy * hole, 0.0]) - np.array([origin[0], origin[1], 0.0]))),
                ("plate_top_z", round(spec.core.plate_thickness / 2, 4)), ("tab_thickness", LINK_TAB),
                ("plate_corner", rounded(np.array([sx, sy, 0.0]) * spec.core.plate_size / 2 - np.array([origin[0], origin[1], 0.0]))),
                ("esc_keepout", rounded(np.array([0.0, 0.0, float(frame.core.stack.lo[2]) + STACK_BOTTOM - 0.5]) - origin)),
                ("esc_half", STACK_PATTERNS[spec.core.stack_pattern][1] / 2 + 0.5)]

    def plate_bolts(self, spec) -> list[tuple[float, float]]:
        """One bolt at each plate corner (`link_hole`)."""
        hole = link_hole(spec)
        return [(sx * hole, sy * hole) for sx in (-1, 1) for sy in (-1, 1)]

    def hardware(self, spec, frame) -> tuple[HardwareLine, ...]:
        """One screw and nut through tab + plate + spacer (the nut in the spacer's nut trap; a
        hanging plate: under the plate), rounded up to a stock length."""
        screw = SCREWS[spec.core.stack_screw]
        grip = LINK_TAB + spec.core.plate_thickness + (spec.core.spacer_thickness if frame.core.hang == 0 else 2.0)
        length = next((n for n in (8, 10, 12, 14, 16, 20) if n >= grip), 20)
        return (HardwareLine(f"{screw.name} x {length} socket-head screw + nut (core link to plate)", 1, screw.mass_g * length / 6 + 0.1),)

    def fixing_words(self, which: str, spacer: str | None) -> str:
        return (f"Bolt a TPU core link onto each corner of the core plate{which}: screw down through the link tab and the plate"
                + (f", nut in the hex trap under the {spacer}" if spacer else ", nut underneath") + ". ")

    def estimate(self, spec, sockets, params: dict) -> Estimate:
        """Closed-form volume/areas of the solid, in print orientation: the arm block and the
        strut's D-section sleeves (less the strut's run inside the block), then the bolt tab, the
        hub and the plate seat (`_link_pieces`). Minus the bores."""
        j = spec.joints
        a = arrays(spec, sockets)
        r, dirs = a.r, a.dirs
        vol = less_bores(a, sockets)
        a_h = a_v = 0.0
        sd = side(spec, sockets, a)
        z, par, rest, sleeve_l = sd.z, sd.par, sd.rest, sd.sleeve_l
        for h, n in [(z[par].max(), sleeve_l[par[0]])] + [(z[i], sleeve_l[i]) for i in rest]:
            vol += a.d_area(h) * n
            a_h += (2 * r + math.pi * r / 2) * n
            a_v += (2 * h + math.pi * r / 2) * n
        for i in rest:  # a sleeve leaving at a small angle to the arm block runs partly inside it
            sin_t = float(np.linalg.norm(np.cross(dirs[i], dirs[par[0]])))
            s0, s1 = sockets[i].seat - j.wall, sockets[i].seat + sockets[i].depth
            s_end = min(s1, 2 * r / sin_t) if sin_t > 1e-9 else s1
            if s_end > s0:
                overlap = 2 * r * (s_end - s0) - sin_t * (s_end**2 - s0**2) / 2
                vol -= overlap * (z[i] + math.pi * r / 4)
        vol, a_h, a_v = _link_pieces(spec, params, sockets, dirs, a.ports, z, sd.zc, sd.w, par, rest, sd.top(r), r,
                                     vol, a_h, a_v)
        return closed(spec, sockets, vol, a_h, a_v, side_extents(a, sd))

    def print_from_local(self, part: PartSpec) -> np.ndarray:
        return side_print(part)

    def solid(self, part: PartSpec):
        m, socks, r = self.in_print(part)
        return _core_link(part, socks, r, m)

    def support_faces(self, part: PartSpec, m: np.ndarray, tol: float, curvature: int):
        """The bolt hole's wall and the tab's underside where it lies on the plate (local z =
        plate_top_z, facing down, inside the plate corner); the seat's faces on the plate's edges
        stay free (they open under thrust)."""
        R, o = m[:3, :3], m[:3, 3]
        bolt = R @ np.asarray(part.param("bolt_hole"), float) + o
        axis = R @ np.array([0.0, 0.0, 1.0])
        r_hole = float(part.param("screw_clearance")) / 2
        z0 = float(part.param("plate_top_z"))
        corner, sign, _, _ = seat_geometry(part)

        def sel_bolt(c, n, bolt=bolt, axis=axis):
            rel = c - bolt[:, None]
            t = axis @ rel
            radial = np.linalg.norm(rel - np.outer(axis, t), axis=0)
            hole = np.abs(radial - r_hole) < tol
            zl = axis @ (c - o[:, None])
            cl = R.T @ (c - o[:, None])
            on = (sign[0] * (cl[0] - corner[0]) < 1e-3) & (sign[1] * (cl[1] - corner[1]) < 1e-3)
            under = (np.abs(zl - z0) < 1e-3) & ((axis @ n) < -0.99) & on
            return hole | under

        return sel_bolt


def _link_pieces(spec, params: dict, sockets: list[Socket], dirs: np.ndarray, ports: np.ndarray, z: np.ndarray,
                 zc: np.ndarray, w: np.ndarray, par: list[int], rest: list[int], top: float, r: float,
                 vol: float, a_h: float, a_v: float) -> tuple[float, float, float]:
    """A core link's bolt tab, hub and plate seat added to the running volume and areas (the
    arm block's print plane normal `w`, axis heights `z`, parallel arm sockets `par`)."""
    j = spec.joints
    s_back = sockets[par[0]].seat - j.wall
    t = float(params.get("tab_thickness", spec.core.plate_thickness))
    hole_d = float(params.get("screw_clearance", 2.4))
    bolt = np.asarray(params.get("bolt_hole", (0.0, 0.0, 0.0)), float)
    r_tab = hole_d / 2 + j.wall
    tab_len = float(np.hypot(bolt[0], bolt[1])) + r_tab + 1.0
    tab_h = float(bolt @ w - zc.min() + r + r_tab)
    vol += tab_len * t * tab_h - math.pi / 4 * hole_d**2 * t
    a_h += tab_len * t
    a_v += 2 * tab_len * tab_h
    # Hub: a prism over the convex hull of the sleeves' back faces and the tab root.
    x = dirs[par[0]] - w * (dirs[par[0]] @ w)
    x /= np.linalg.norm(x)
    y = np.cross(w, x)
    pts = []
    for i in [par[0]] + rest:
        d = dirs[i]
        lat = np.cross(w, d)
        lat /= np.linalg.norm(lat)
        c = ports[i] + d * (sockets[i].seat - j.wall)
        pts += [c + lat * r, c - lat * r]
    e_u = bolt - w * (bolt @ w)
    e_u[2] = 0.0
    e_u /= max(float(np.linalg.norm(e_u)), 1e-9)
    v0 = float(params.get("plate_top_z", 0.0))
    pts += [e_u * 0.5 + np.array([0, 0, v0]), e_u * 0.5 + np.array([0, 0, v0 + t])]
    hub_area = hull_area(np.array([[p_ @ x, p_ @ y] for p_ in pts]))
    hub_h = max(top, tab_h)
    vol += hub_area * hub_h
    a_h += hub_area
    a_v += 2 * s_back * hub_h
    seat_area = _seat_area(params, ports[par], z[par], dirs[par[0]], sockets[par[0]].seat - j.wall, r,
                           min(float(z[par].max() + r - 0.5), tab_h))
    vol += seat_area * 2 * v0
    a_v += 2 * seat_area
    return vol, a_h, a_v


def _seat_area(params: dict, ports: np.ndarray, heights: np.ndarray, d: np.ndarray, s_back: float, r: float,
               height: float) -> float:
    """Plan area (mm^2) of a core link's seat as `_seat` builds it (`seat_plan`, less the
    plate's corner quadrant), from the bed up to `height` in print (the arm pair's two `ports`
    print at `heights`: print height runs across the pair)."""
    corner, sign = link_plate_corner(params)
    quad = seat_plan(params, ports, d, s_back, r)
    across = ports[1, :2] - ports[0, :2]
    g = across * (heights[1] - heights[0]) / float(across @ across)  # print height per mm in plan
    h0 = float(heights[0] - ports[0, :2] @ g)  # print height = h0 + p . g
    band = clip(clip(quad, -g, h0), g, height - h0)
    inside = clip(clip(band, np.array([sign[0], 0.0]), sign[0] * corner[0]), np.array([0.0, sign[1]]), sign[1] * corner[1])
    return polygon_area(band) - polygon_area(inside) if len(band) > 2 else 0.0


def _core_link(part: PartSpec, socks: list[PSocket], r: float, m: np.ndarray):
    """Stacked arm sockets + strut sleeve + a hub + the tab that bolts onto the core plate top."""
    from ...parts import joint_solid as cad

    arms, others = split_arms(socks)
    a = arms[0]
    s_back = a.seat - part.wall
    pieces = [cad.arm_block(arms, r, s_back)]
    backs = footprint_rect(a, s_back, s_back, r)[:2] + footprint_rect(a, s_back, s_back, r)[2:]
    tops = []
    for s in others:
        t0 = s.seat - part.wall
        pieces.append(cad.sleeve(s, t0, r))
        backs += footprint_rect(s, t0, t0, r)
        tops.append(s.port[2] + r)
    # The tab: local z from plate_top_z to plate_top_z + tab_thickness, from just outside the
    # node to past the bolt hole, standing on the bed (it is a wall in print orientation).
    rot = m[:3, :3]
    e_v = rot @ np.array([0.0, 0.0, 1.0])
    node = m[:3, 3]
    bolt = rot @ np.asarray(part.param("bolt_hole"), float) + m[:3, 3]
    v0 = float(part.param("plate_top_z"))
    t = float(part.param("tab_thickness"))
    hole_d = float(part.param("screw_clearance"))
    r_tab = hole_d / 2 + part.wall
    u = bolt - node
    u = u - e_v * (u @ e_v)
    u_len = float(np.linalg.norm(u[:2]))
    e_u = u / u_len

    def tab_pt(uu, vv):
        return (node + e_u * uu + e_v * vv)[:2]

    z_top = float(bolt[2] + r_tab)
    near = [z for z in tops if abs(z_top - z) < TAB_CLEAR]
    if near:
        # The tab's top plane on a sleeve's round top (the bore = the screw clearance: 2.3 mm rods
        # and M2, 2.4 mm both) made the hub's top plane, the tab's and the strut sleeve's tangent
        # line coincide; OCC then meshed that top face with open edges (an STL that is not
        # watertight). Lift the tab clear of it.
        z_top = max(near) + TAB_CLEAR
    pieces.append(cad.prism([tab_pt(-1.0, v0), tab_pt(u_len + r_tab, v0), tab_pt(u_len + r_tab, v0 + t), tab_pt(-1.0, v0 + t)],
                        0.0, z_top))
    # Hub: the convex hull of the sleeves' back faces and the root of the tab.
    backs += [tab_pt(0.5, v0), tab_pt(0.5, v0 + t)]
    # The hub's top clears every sleeve's top line and axis: level with the strut sleeve's top it
    # touched that round top along a line, and OCC's mesher left the hub's top face out of the STL
    # (bamboo with joints.fit_clearance 0.22); 0.03 mm above the upper arm's axis it made faces
    # of 1e-6 mm^2 (bamboo, joints.wall 5.48).
    pieces.append(cad.prism(convex_hull(np.array(backs)), 0.0, clear_of(max(tops + [z_top]), sleeve_levels(socks, r))))
    pieces.append(_seat(part, arms, socks, r, m, z_top))
    bolt_hole = cad.cylinder(bolt + e_v * (v0 - 1.0), e_v, t + 2.0, hole_d / 2)
    return cad.finish(cad.above_bed(cad.fuse_all(pieces)), [cad.socket_cutter(s) for s in socks] + [bolt_hole, _esc_keepout(part, m)])




def _esc_keepout(part: PartSpec, m: np.ndarray):
    """The room under the ESC board (its footprint, from 0.5 mm under the board up), in print
    coordinates: where a small plate brings the tab under the board's corner, the tab is cut
    down to clear it."""
    from ...parts import joint_solid as cad

    c = np.asarray(part.param("esc_keepout"), float)
    h = float(part.param("esc_half"))
    square = [c[:2] + np.array([sx, sy]) * h for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return cad.apply(cad.prism(square, float(c[2]), float(c[2]) + 100.0), m)


def _seat(part: PartSpec, arms: list[PSocket], socks: list[PSocket], r: float, m: np.ndarray, cap: float):
    """The seat: TPU filling the gap between the arm block's back and the core plate's two edge
    faces, over the plate's thickness, up to the tab (print coordinates). Without it the arm
    block meets the core only through the tab, which crosses a ~4 mm gap to the plate's edges over
    air: the seat makes the block + tab junction the plate's thickness deeper from the block to
    the plate edge, and leaves the tab's underside only where it lies on the plate. Its faces on
    the plate edge bear under the whole frame's payload / landing and open under thrust, so the
    joint FE leaves them free (docs/stiffness-model.md)."""
    from ...parts import joint_solid as cad

    cq = cad._cq()
    c, sign, z0, z1 = seat_geometry(part)
    rot, o = m[:3, :3], m[:3, 3]
    quad = seat_plan(dict(part.params), [rot.T @ (s.port - o) for s in arms], rot.T @ arms[0].direction,
                     arms[0].seat - part.wall, r)
    # up into the tab by 1 mm: a seat top in the tab's underside plane left faces of 5e-5 mm^2
    # (the two planes built along different paths agree only to round-off)
    body = cad.apply(cad.prism(quad, z0, z1 + 1.0), m)
    big = 200.0
    plate = cad.apply(cad.prism([c, c - np.array([sign[0], 0.0]) * big, c - sign * big, c - np.array([0.0, sign[1]]) * big],
                        z0 - 1.0, z1 + 1.0), m)
    # In print the block's width is vertical: from the bed to the tab's top (`cap`: the seat is as
    # wide as the tab it deepens; wider, it weighs more than it stiffens), at most to the top of
    # the highest sleeve less half a millimetre (clear of the round top's tangent line and of the
    # sleeves' levels).
    top = clear_of(min(cap, max(float(s.port[2]) for s in arms) + r - 0.5), sleeve_levels(socks, r))
    clip = cq.Solid.makeBox(2 * big, 2 * big, cad.exact(top), cq.Vector(-big, -big, 0.0))
    return body.cut(plate).intersect(clip)



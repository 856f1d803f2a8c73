"""TPU joints (corner_top, corner_bottom, knee, core_link), generated from their sockets.

Every joint is built directly IN PRINT ORIENTATION: `print_from_local(part)` (parts/joint_plan.py,
pure numpy, with the rest of the joints' plan the closed forms share) maps the part's local frame
(sockets, bolt hole) to the printer, and the solid is assembled there from "print-safe" pieces,
so TPU prints without supports:

* a socket parallel to the bed gets a D-section sleeve (flat bottom on the bed, vertical sides,
  round top, OD = bore + 2 wall): its hole is a bridge of one bore diameter (<= 6 mm);
* a socket within 45 deg of vertical gets a plain tilted cylinder, its end inside the corner's hub
  (its surface never faces down more than 45 deg);
* a socket sloped less than 45 deg above horizontal (the strut at a bottom corner) gets a cylinder
  plus a vertical web (90 % of the OD wide) from its axis down to the bed, so nothing hangs; its
  hole is a sloped bridge one bore wide.

Each socket is then cut as a blind hole of diameter `socket.bore` from `socket.bottom()` to past
`socket.mouth()`, with a 45 deg chamfer of `CHAMFER` mm at the mouth. Walls are `part.wall`.

Print orientations
* corner_top: ring plane on the bed, upside down (the leg socket then points up; the flat bed face
  is the top of the frame). corner_bottom: as in the frame, ring sleeves and a foot pad on the bed:
  the bottom corners are the feet, and the foot pad is what touches the ground.
* the pegged core link (core.link: pegs): standing, the arms' direction up and the pegs' ends on
  the bed (parts/peg_plan.py `pegged_plan`); the arch's underside is a bridge between the
  columns, as in the authors' connector.
* knee, core_link: every socket direction lies in the frame's diagonal side plane and the two arm
  rods are offset across it, so the joint is printed lying on its side: the lateral axis is vertical,
  every socket is parallel to the bed, the two arm sockets are stacked. The core link holds them in
  one block. The knee holds them as a U: a bridge of the block's section over one sleeve OD at
  their back, and past it the lower sleeve on the bed and the upper one a teardrop (round top,
  45 deg flanks) on a vertical web one wall thick; its legs, halfway up, are teardrops on such
  webs too. A web is print support that also ties what it holds: a D-section pillar from the bed
  to a sleeve 15 mm up weighs 2.5 times as much.

Living hinge (knee). The sides fold at the knees ("fold as you assemble"; on impact the hourglass
closes): the legs rotate relative to the arms about the lateral axis. That axis is vertical in
print, so the hinge is a vertical TPU web `hinge_thickness` thick (across the bend) running from the
upper-leg sleeve to the arm bridge, with a `HINGE_GAP` slot on both sides that frees the upper leg
everywhere else. Layer lines then run along the bend, the way printed living hinges survive. The
lower leg leaves the knee almost at right angles to the arms and its socket shares a wall with the
arm sockets (the seat is only `joints.seat` from the knee centre), so it stays solid with the arm
bridge (where a large seat keeps their sleeves apart, a hub between their back faces joins them);
the upper leg, which makes the larger angle with the arms and carries the fold, is the one hinged.
frame.py raises the knee's seat until the slot leaves that leg's back end whole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..frame import HINGE_GAP
from .joint_plan import (
    JOINT_KINDS,
    TAB_CLEAR,
    TEAR_MIN,
    TEAR_WEB,
    PSocket,
    clear_of,
    convex_hull,
    footprint_rect,
    horizontal,
    kind_of,
    knee_bridge,
    knee_hinge,
    knee_hub,
    link_bands,
    link_is_flat,
    link_plate_region,
    map_sockets,
    print_from_local,
    rigid_leg_start,
    seat_geometry,
    seat_plan,
    sleeve_levels,
    split_arms,
)
from .peg_plan import is_pegged, pegged_plan
from .record import PartSpec

CHAMFER = 0.5  # mm, 45 deg, at every socket mouth
# A knee or core-link socket is parallel to the bed below this slope (rad): the stored sockets'
# 1e-6 rounding tilts a rectangle's by up to ~1e-6, which must not turn a D-section sleeve into a
# degenerate sloped one (a square box's are level to ~1e-17).
FLAT = 1e-5
STACK_SNAP = 1e-3  # mm: the most two arm sleeves are moved to stack them (rounding noise is ~1e-5)
VOID_MM3 = 1e-6  # a solid smaller than this is a boolean artifact, not a piece of the part
SKIRT = 0.9  # web under a sloped sleeve, as a fraction of the sleeve OD (never tangent to it)


@dataclass(frozen=True)
class Built:
    """A part solid in print orientation and the 4x4 transform print <- part local frame."""

    shape: object  # cq.Shape
    print_from_local: np.ndarray
    shells: int = 1


# -- print-safe primitives (CadQuery) --------------------------------------------------------

def _cq():
    import cadquery as cq

    return cq


def vec(p):
    return _cq().Vector(float(p[0]), float(p[1]), float(p[2]))


def along(start, d, length: float, axis_z: float, section):
    """A prism of `length` along horizontal `d` from `start` (its axis at `axis_z`), over a section
    drawn by `section(wp)` on a workplane whose x runs across `d` (to its left) and whose y is up,
    from the axis. The section is drawn and extruded at the origin and then placed by one rigid
    transform: drawn on a workplane at the sleeve's own origin and direction, OCC's arcs came out
    with different last bits from one call to the next (the STEP bytes of the same params differed)."""
    cq = _cq()
    d = horizontal(d)
    lat = np.array([-d[1], d[0], 0.0])
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = lat, d, (0.0, 0.0, 1.0)
    m[:3, 3] = (float(start[0]), float(start[1]), float(axis_z))
    return apply(section(cq.Workplane("XZ")).extrude(-length).val(), m)


def dsleeve(start, d, length: float, axis_z: float, r: float, bottom: float = 0.0):
    """D-section sleeve along horizontal `d` from `start`: flat bottom at `bottom`, round top."""
    lo = bottom - axis_z
    return along(start, d, length, axis_z,
                 lambda wp: wp.moveTo(-r, lo).lineTo(r, lo).lineTo(r, 0).threePointArc((0, r), (-r, 0)).close())


def prism(points_xy, z0: float, z1: float):
    """Vertical prism over a polygon (xy points, any winding) from z0 to z1."""
    cq = _cq()
    pts = [(float(x), float(y)) for x, y in points_xy]
    return cq.Workplane("XY", origin=(0, 0, z0)).polyline(pts).close().extrude(z1 - z0).val()


def box_along(p0, p1, width: float, z0: float, z1: float):
    """Vertical prism: a strip `width` wide from xy point p0 to p1."""
    a, b = np.asarray(p0[:2], float), np.asarray(p1[:2], float)
    e = (b - a) / np.linalg.norm(b - a)
    n = np.array([-e[1], e[0]]) * width / 2
    return prism([a - n, b - n, b + n, a + n], z0, z1)


def cylinder(p0, d, length: float, r: float):
    return _cq().Solid.makeCylinder(r, length, vec(p0), vec(d))


def sloped_sleeve(start, d, length: float, r: float, skirt: float = SKIRT):
    """Cylinder along a sloped `d` plus a vertical web from its axis down below the bed, `skirt`
    of the radius wide on each side."""
    cq = _cq()
    d = np.asarray(d, float)
    h = horizontal(d)
    lat = np.array([-h[1], h[0], 0.0])
    p0 = np.asarray(start, float)
    p1 = p0 + d * length
    run = float((p1 - p0)[:2] @ h[:2])
    # The web reaches under the whole cylinder: its ends lie in the planes of the end caps (the
    # lowest point of an end cap is r sin(slope) ahead of the axis end, r cos(slope) below it).
    sa, ca = float(d[2]), math.sqrt(1 - float(d[2]) ** 2)
    z0, z1 = float(p0[2]), float(p1[2])
    outline = [(r * sa, -1.0), (run + r * sa, -1.0), (run + r * sa, z1 - r * ca), (run, z1), (0, z0), (r * sa, z0 - r * ca)]
    plane = cq.Plane(origin=(float(p0[0]), float(p0[1]), 0.0), xDir=tuple(h), normal=tuple(-lat))
    web = cq.Workplane(plane).polyline(outline).close().extrude(skirt * r, both=True).val()
    return cylinder(p0, d, length, r).fuse(web)


def sleeve(s: PSocket, start: float, r: float, end: float | None = None):
    """The print-safe sleeve of a socket from `start` (along it, from the port) to `end` (the mouth)."""
    end = s.seat + s.depth if end is None else end
    dz = float(s.direction[2])
    length = end - start
    if abs(dz) < FLAT:
        return dsleeve(s.at(start), s.direction, length, s.port[2], r)
    if abs(dz) >= math.cos(math.radians(45)):
        return cylinder(s.at(start), s.direction, length, r)
    return sloped_sleeve(s.at(start), s.direction, length, r)


def socket_cutter(s: PSocket, chamfer: float = CHAMFER):
    """Blind hole from the socket bottom out past the mouth, with a 45 deg mouth chamfer."""
    cq = _cq()
    rb = s.bore / 2
    extra = 2.0
    hole = cq.Solid.makeCylinder(rb, s.depth + extra, vec(s.bottom), vec(s.direction))
    cone = cq.Solid.makeCone(rb, rb + chamfer + extra, chamfer + extra, vec(s.mouth - s.direction * chamfer), vec(s.direction))
    return hole.fuse(cone)


def apply(shape, m: np.ndarray):
    """Rigid 4x4 transform of a cq shape (a copy), via gp_Trsf."""
    import cadquery as cq
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf

    t = gp_Trsf()
    t.SetValues(*[float(v) for v in np.asarray(m, float)[:3].ravel()])
    return cq.Shape.cast(BRepBuilderAPI_Transform(shape.wrapped, t, True).Shape())


def fuse_all(shapes):
    first, *rest = shapes
    return first.fuse(*rest).clean() if rest else first


def above_bed(shape, big: float = 2000.0):
    """Keep z >= 0 (the flat cut on the bed)."""
    cq = _cq()
    return shape.intersect(cq.Solid.makeBox(2 * big, 2 * big, big, cq.Vector(-big, -big, 0.0)))


def finish(body, cutters):
    """Cut the socket holes; return a single solid (raises if the part fell apart). A solid of no
    volume is not a piece: OCC's fuse of many pieces at once can leave one where surfaces only
    touch (a rectangle's bottom corner: its strut off the diagonal, a 0 mm^3 solid on the hub)."""
    cq = _cq()
    shape = body.cut(fuse_all(cutters)).clean() if cutters else body.clean()
    solids = [x for x in shape.Solids() if x.Volume() > VOID_MM3]
    if len(solids) != 1:
        raise RuntimeError(f"joint geometry produced {len(solids)} solids instead of 1")
    return cq.Solid(solids[0].wrapped) if not isinstance(solids[0], cq.Solid) else solids[0]


# -- the joints ------------------------------------------------------------------------------

def solid(part: PartSpec) -> Built:
    m = print_from_local(part)
    socks = map_sockets(part, m)
    r = (part.sockets[0].bore + 2 * part.wall) / 2
    kind = kind_of(part)
    if kind in ("corner_top", "corner_bottom"):
        shape = _corner(part, socks, r)
    elif kind == "knee":
        shape = _knee(part, socks, r)
    elif kind == "core_link" and is_pegged(part):
        shape = _core_link_pegged(part, socks)
    elif kind == "core_link" and link_is_flat(part.sockets):
        shape = _core_link_flat(part, socks, r, m)
    elif kind == "core_link":
        shape = _core_link(part, socks, r, m)
    else:
        raise ValueError(f"unknown joint {part.name!r}; valid: {', '.join(JOINT_KINDS)}")
    return Built(shape, m)


def _corner(part: PartSpec, socks: list[PSocket], r: float):
    """Ring sleeves flat on the bed meeting in a round hub, the leg (and strut) rising from it."""
    params = dict(part.params)
    port = socks[0].port
    # The hub stands TAB_CLEAR wider than the sleeves and clear of their top lines. Of the sleeves'
    # own radius, its axis through theirs, it met every sleeve in the degenerate equal-radius
    # intersection (two curves crossing where the surfaces touch), and OCC's fuse of all the pieces
    # at once dropped a piece: a bottom corner lost most of its strut sleeve (459 of 648 mm^3) and
    # still came out one watertight solid, its strut socket a hole in the air (8 of 249 random
    # designs, e.g. a carbon box 154.1 x 175.9 x 128.5), or lost everything ("0 solids").
    pieces = [cylinder((port[0], port[1], 0.0), (0, 0, 1), clear_of(2 * r, sleeve_levels(socks, r)), r + TAB_CLEAR)]  # hub
    # Every sleeve starts TAB_CLEAR out from the port, its end inside the hub. All the sleeves share
    # the port and the radius r, and two equal cylinders whose axes cross touch at two points level
    # with the crossing: on the rim of a sleeve that started there. A leg and a strut so met made
    # OCC's fuse drop both (the mirrored bottom corner of a carbon 184.7 x 169.7 x 81.8 box: 781 of
    # 1534 mm^3). The leg (within 45 deg of vertical) used to run down through the bed, where its
    # cut ellipse could pass through the point where the hub's rim meets a ring sleeve's side (an
    # STL with a hole: carbon, 284.4 x 289.1 x 141.2); inside the hub its end hangs over nothing.
    cos45 = math.cos(math.radians(45))
    for s in socks:
        dz = s.direction[2]
        length = s.seat + s.depth
        if abs(dz) < 1e-6:
            pieces.append(dsleeve(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, s.port[2], r))
        elif dz >= cos45:
            pieces.append(cylinder(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, r))
        elif dz > 0:
            pieces.append(sloped_sleeve(s.at(TAB_CLEAR), s.direction, length - TAB_CLEAR, r))
        else:
            raise ValueError(f"{part.name}: socket {s.rod} points into the bed in print orientation")
    if params.get("foot"):
        # The foot: a flat pad on the ground side, twice the sleeve OD across, one wall thick.
        pieces.append(cylinder((port[0], port[1], 0.0), (0, 0, 1), part.wall, 2 * r))
    body = above_bed(fuse_all(pieces))
    return finish(body, [socket_cutter(s) for s in socks])


def _block(arms: list[PSocket], r: float, start: float):
    """The stacked arm sockets: each arm's sleeve stands on the bed, so together they make one block.
    Every sleeve is built straight above or below the first arm's (`_stacked`)."""
    return fuse_all([sleeve(_stacked(arms[0], s), start, r) for s in arms])


def _stacked(a: PSocket, s: PSocket) -> PSocket:
    """Arm socket `s` moved onto the vertical through arm `a`'s axis, along `a`. Sockets are stored
    to 1e-6 mm: off a 45 deg diagonal (a rectangle) the rounding leaves the two arms of a pair up
    to ~1e-5 mm apart sideways and along, steps between the two sleeves that became zero-area
    faces, a failed boolean or a mesh the FE rejected. The sleeves only; the holes are cut where
    the sockets are. A square box's pair is stacked to round-off (~1e-16) and kept as it is."""
    off = s.port - a.port
    stray = off - np.array([0.0, 0.0, off[2]])
    if s is a or float(np.abs(stray).max()) <= 1e-9 and float(np.abs(s.direction - a.direction).max()) <= 1e-9:
        return s
    if float(np.abs(stray).max()) > STACK_SNAP:
        raise ValueError(f"arm sockets {a.rod} and {s.rod} are not stacked in print ({stray} mm apart)")
    return PSocket(a.port + np.array([0.0, 0.0, off[2]]), a.direction, s.seat, s.depth, s.bore, s.rod)


def teardrop(start, d, length: float, axis_z: float, r: float, web: float):
    """A sleeve along horizontal `d` from `start` that stands on a thin web: its round top, 45 deg
    flanks tangent to it below, and a vertical web `web` thick from the flanks down to the bed.
    Every face is vertical or faces down at most 45 deg, so it prints without supports however
    high its axis, at a fraction of a D-section's TPU. Where the flanks would not reach the web
    (a web as wide as the tangent points, or an axis too low for them) it is the D-section sleeve."""
    k = r / math.sqrt(2.0)  # the tangent points: (+-k, -k) from the axis
    z_web = -r * math.sqrt(2.0) + web / 2  # where the flanks meet the web, from the axis
    if web / 2 >= k - 0.05 or axis_z + z_web <= 0.2:
        return dsleeve(start, d, length, axis_z, r)
    h = web / 2
    return along(start, d, length, axis_z,
                 lambda wp: (wp.moveTo(-h, -axis_z).lineTo(h, -axis_z).lineTo(h, z_web).lineTo(k, -k)
                             .threePointArc((0, r), (-k, -k)).lineTo(-h, z_web).close()))


def _arm_bracket(arms: list[PSocket], r: float, s_back: float, bridge_end: float, web: float):
    """The knee's arm pair as a U, not a solid block: the bridge (`knee_bridge`) carries the top
    arm's moment down to the legs (in torsion about the print vertical: its square section twists
    ~40x less than a web one wall thick); past it the lowest arm's sleeve lies on the bed (a
    D-section) and every higher arm's sleeve is a `teardrop` on a `web` thick web, which the print
    needs under it and which ties the pair in its own plane."""
    stacked = [_stacked(arms[0], s) for s in arms]
    low = min(stacked, key=lambda s: float(s.port[2]))
    mouth = low.seat + low.depth
    if bridge_end >= mouth:
        return _block(arms, r, s_back)
    pieces = [fuse_all([sleeve(s, s_back, r, bridge_end) for s in stacked]), sleeve(low, bridge_end, r)]
    pieces += [teardrop(s.at(bridge_end), s.direction, mouth - bridge_end, s.port[2], r, web) for s in stacked if s is not low]
    return fuse_all(pieces)


def _knee_leg(s: PSocket, start: float, r: float, web: float):
    """A knee leg's sleeve: a teardrop on a web (the legs lie halfway up the arm pair in print)."""
    if abs(float(s.direction[2])) < FLAT:
        return teardrop(s.at(start), s.direction, s.seat + s.depth - start, s.port[2], r, web)
    return sleeve(s, start, r)


def _knee(part: PartSpec, socks: list[PSocket], r: float):
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
    rigid_solids = [_knee_leg(s, t_back[id(s)], r, web_t) for s in rigid] + [prism(poly, 0.0, top) for poly, top in hubs]
    # Upper leg, freed from everything rigid by HINGE_GAP ...
    upper = _knee_leg(hinged, t_back[id(hinged)], r, web_t)
    clear = [prism(footprint_rect(a, s_back, a.seat + a.depth, r, HINGE_GAP), -1.0, 1000.0)]
    clear += [prism(footprint_rect(s, t_back[id(s)], s.seat + s.depth, r, HINGE_GAP), -1.0, 1000.0) for s in rigid]
    clear += [prism(convex_hull(_grown(poly, HINGE_GAP)), -1.0, 1000.0) for poly, _ in hubs]
    upper = upper.cut(fuse_all(clear))
    # ... and joined to the arm bridge by the hinge web (`web`): from the centre of the upper leg's
    # back face straight to the bridge's back face.
    body = above_bed(fuse_all([block, *rigid_solids, upper, box_along(web.start, web.end, web.thickness, 0.0, web.height)]))
    return finish(body, [socket_cutter(s) for s in socks])


def _grown(pts: np.ndarray, by: float) -> np.ndarray:
    """The corners of squares `2 by` wide around each point: their hull is the points' hull grown by at least `by`."""
    return np.array([p + np.array([sx, sy]) * by for p in pts for sx in (-1.0, 1.0) for sy in (-1.0, 1.0)])


def _core_link(part: PartSpec, socks: list[PSocket], r: float, m: np.ndarray):
    """Stacked arm sockets + strut sleeve + a hub + the tab that bolts onto the core plate top."""
    arms, others = split_arms(socks)
    a = arms[0]
    s_back = a.seat - part.wall
    pieces = [_block(arms, r, s_back)]
    backs = footprint_rect(a, s_back, s_back, r)[:2] + footprint_rect(a, s_back, s_back, r)[2:]
    tops = []
    for s in others:
        t0 = s.seat - part.wall
        pieces.append(sleeve(s, t0, r))
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
    pieces.append(prism([tab_pt(-1.0, v0), tab_pt(u_len + r_tab, v0), tab_pt(u_len + r_tab, v0 + t), tab_pt(-1.0, v0 + t)],
                        0.0, z_top))
    # Hub: the convex hull of the sleeves' back faces and the root of the tab.
    backs += [tab_pt(0.5, v0), tab_pt(0.5, v0 + t)]
    # The hub's top clears every sleeve's top line and axis: level with the strut sleeve's top it
    # touched that round top along a line, and OCC's mesher left the hub's top face out of the STL
    # (bamboo with joints.fit_clearance 0.22); 0.03 mm above the upper arm's axis it made faces
    # of 1e-6 mm^2 (bamboo, joints.wall 5.48).
    pieces.append(prism(convex_hull(np.array(backs)), 0.0, clear_of(max(tops + [z_top]), sleeve_levels(socks, r))))
    pieces.append(_seat(part, arms, socks, r, m, z_top))
    cq = _cq()
    bolt_hole = cq.Solid.makeCylinder(hole_d / 2, t + 2.0, vec(bolt + e_v * (v0 - 1.0)), vec(e_v))
    return finish(above_bed(fuse_all(pieces)), [socket_cutter(s) for s in socks] + [bolt_hole, _esc_keepout(part, m)])


def _core_link_flat(part: PartSpec, socks: list[PSocket], r: float, m: np.ndarray):
    """The flat core link (level arms), printed upside down: each arm's sleeve lying on the bed (a
    teardrop on a thin web, or a D section where the axis stands low), the strut's sleeve rising on
    its web, and one band per socket from its sleeve's back end to the bolt pad, from the bed (the
    tab's top) down to the plate top: the tab, in as many strips as there are sockets, each as deep
    as the tab. Outside the plate the bands go on below the plate top, down to the plate's bottom:
    the seat, bearing on the plate's edges. Every face then looks up or sideways in print but
    the bores' ceilings (bridges of one bore) and the plate's imprint (the bands' undersides over
    the plate, which face up in print)."""
    params = dict(part.params)
    arms, others = split_arms(socks)
    rot, o = m[:3, :3], m[:3, 3]
    z_bed = float(o[2])  # the bed, as a height in the local frame (local z maps to z_bed - z)
    v0 = float(part.param("plate_top_z"))
    T = z_bed - v0
    pieces = []
    for s in socks:
        t0 = s.seat - part.wall
        if abs(float(s.direction[2])) >= FLAT:
            # the strut: its web as wide as a sloped sleeve's (a teardrop on a thin web, 0.16 g
            # lighter, carries the payload worse: docs/stiffness-model.md)
            pieces.append(sloped_sleeve(s.at(t0), s.direction, s.depth + part.wall, r))
        elif float(s.port[2]) - r * math.sqrt(2) >= TEAR_MIN:
            pieces.append(teardrop(s.at(t0), s.direction, s.depth + part.wall, float(s.port[2]), r, TEAR_WEB))
        else:
            pieces.append(sleeve(s, t0, r))

    def plan(poly):
        return [rot[:2, :2] @ np.asarray(p, float) + o[:2] for p in poly]

    levels = sleeve_levels(socks, r)
    bands = link_bands(params, part.sockets, part.wall, r)
    # each band from the bed to the plate's bottom (clear of the sleeves' levels); the plate's cut
    # leaves the tab over the plate and the seat beside it
    bottom = clear_of(z_bed + v0, levels)
    pieces += [prism(plan(b), 0.0, bottom) for b in bands]
    body = fuse_all(pieces)
    plate = prism(plan(link_plate_region(params)), T, 1000.0)  # the plate, under its top
    c = np.asarray(part.param("esc_keepout"), float)
    h = float(part.param("esc_half"))
    # under the ESC board nothing stands above the board's underside (less 0.5 mm); cut through
    # the whole depth, so the cut faces are walls (a cut from the bed up would leave a ceiling)
    esc = prism(plan([c[:2] + np.array([sx, sy]) * h for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]), -1.0, 1000.0) \
        if float(c[2]) < z_bed else None
    body = body.cut(plate) if esc is None else body.cut(plate).cut(esc)
    cq = _cq()
    bolt = rot @ np.asarray(part.param("bolt_hole"), float) + o
    hole_d = float(part.param("screw_clearance"))
    bolt_hole = cq.Solid.makeCylinder(hole_d / 2, T + 2.0, vec((bolt[0], bolt[1], -1.0)), vec((0.0, 0.0, 1.0)))
    return finish(above_bed(body), [socket_cutter(s) for s in socks] + [bolt_hole])


def _core_link_pegged(part: PartSpec, socks: list[PSocket]):
    """The pegged core link (parts/peg_plan.py `pegged_plan`), standing in print: per arm a solid
    peg from the bed and a column round the socket above it, the arch joining the columns from
    their mouths down to the pegs' shoulder round its opening, the crown's block over the mouths,
    and the strut's sleeve along its socket, its back end in the crown; less the sockets."""
    cq = _cq()
    pl = pegged_plan(part.sockets, dict(part.params))
    pieces = []
    for c in pl.columns:
        x, y = float(c.axis[0]), float(c.axis[1])
        if pl.peg_r == c.col_r:  # one cylinder (frame.py `peg_column_r`)
            pieces.append(cylinder((x, y, c.peg0), (0, 0, 1), c.col1 - c.peg0, c.col_r))
        else:
            pieces += [cylinder((x, y, c.peg0), (0, 0, 1), c.col0 - c.peg0, pl.peg_r),
                       cylinder((x, y, c.col0), (0, 0, 1), c.col_len, c.col_r)]
    (x0, x1), (n0, n1) = pl.arch_x, pl.arch_n
    arch = cq.Solid.makeBox(x1 - x0, n1 - n0, pl.arch_hi - pl.arch_lo, cq.Vector(x0, n0, pl.arch_lo))
    if pl.opening is not None:
        # the opening's outline (x, z) extruded through the arch's depth, overshooting both faces
        xz = pl.opening.outline(below=1.0)
        hole = cq.Workplane("XZ", origin=(0, n1 + 1.0, 0)).polyline(xz).close().extrude(n1 - n0 + 2.0).val()
        arch = arch.cut(hole)
    pieces.append(arch)
    if pl.block is not None:
        (bx0, by0, bz0), (bx1, by1, bz1) = pl.block
        pieces.append(cq.Solid.makeBox(bx1 - bx0, by1 - by0, bz1 - bz0, cq.Vector(bx0, by0, bz0)))
    for st in pl.struts:
        s = socks[st.index]
        pieces.append(cylinder(s.at(st.start), s.direction, st.end - st.start, pl.col_r))
    return finish(fuse_all(pieces), [socket_cutter(s) for s in socks])


def _esc_keepout(part: PartSpec, m: np.ndarray):
    """The room under the ESC board (its footprint, from 0.5 mm under the board up), in print
    coordinates: where a small plate brings the tab under the board's corner, the tab is cut
    down to clear it."""
    c = np.asarray(part.param("esc_keepout"), float)
    h = float(part.param("esc_half"))
    square = [c[:2] + np.array([sx, sy]) * h for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return apply(prism(square, float(c[2]), float(c[2]) + 100.0), m)


def _seat(part: PartSpec, arms: list[PSocket], socks: list[PSocket], r: float, m: np.ndarray, cap: float):
    """The seat: TPU filling the gap between the arm block's back and the core plate's two edge
    faces, over the plate's thickness, up to the tab (print coordinates). Without it the arm
    block meets the core only through the tab, which crosses a ~4 mm gap to the plate's edges over
    air: the seat makes the block + tab junction the plate's thickness deeper from the block to
    the plate edge, and leaves the tab's underside only where it lies on the plate. Its faces on
    the plate edge bear under the whole frame's payload / landing and open under thrust, so the
    joint FE leaves them free (docs/stiffness-model.md)."""
    cq = _cq()
    c, sign, z0, z1 = seat_geometry(part)
    rot, o = m[:3, :3], m[:3, 3]
    quad = seat_plan(dict(part.params), [rot.T @ (s.port - o) for s in arms], rot.T @ arms[0].direction,
                     arms[0].seat - part.wall, r)
    # up into the tab by 1 mm: a seat top in the tab's underside plane left faces of 5e-5 mm^2
    # (the two planes built along different paths agree only to round-off)
    body = apply(prism(quad, z0, z1 + 1.0), m)
    big = 200.0
    plate = apply(prism([c, c - np.array([sign[0], 0.0]) * big, c - sign * big, c - np.array([0.0, sign[1]]) * big],
                        z0 - 1.0, z1 + 1.0), m)
    # In print the block's width is vertical: from the bed to the tab's top (`cap`: the seat is as
    # wide as the tab it deepens; wider, it weighs more than it stiffens), at most to the top of
    # the highest sleeve less half a millimetre (clear of the round top's tangent line and of the
    # sleeves' levels).
    top = clear_of(min(cap, max(float(s.port[2]) for s in arms) + r - 0.5), sleeve_levels(socks, r))
    clip = cq.Solid.makeBox(2 * big, 2 * big, top, cq.Vector(-big, -big, 0.0))
    return body.cut(plate).intersect(clip)



"""The pieces the TPU joints' solids are built of (CadQuery, imported where used), and the
`Built` record of a part's solid. Each joint kind's solid is its module's in families/joint_kinds/.

Every joint is built directly IN PRINT ORIENTATION: its kind's `print_from_local(part)` (pure
numpy, on the plan in parts/joint_plan.py and parts/peg_plan.py) maps the part's local frame
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

Every number a primitive here hands to CadQuery goes through `numfmt.cad` (9 decimals): the plans
compute them with small numpy products whose last bits follow the CPU's BLAS kernel, and the
same params must give the same solid, and bytes, on every machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..numfmt import cad as exact
from .joint_plan import PSocket, horizontal

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
    x, y, z = exact(np.asarray(p, float)[:3])
    return _cq().Vector(float(x), float(y), float(z))


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
    return apply(section(cq.Workplane("XZ")).extrude(-exact(length)).val(), m)


def dsleeve(start, d, length: float, axis_z: float, r: float, bottom: float = 0.0):
    """D-section sleeve along horizontal `d` from `start`: flat bottom at `bottom`, round top."""
    axis_z, r = exact(axis_z), exact(r)
    lo = exact(bottom - axis_z)
    return along(start, d, length, axis_z,
                 lambda wp: wp.moveTo(-r, lo).lineTo(r, lo).lineTo(r, 0).threePointArc((0, r), (-r, 0)).close())


def prism(points_xy, z0: float, z1: float):
    """Vertical prism over a polygon (xy points, any winding) from z0 to z1."""
    cq = _cq()
    pts = [(float(x), float(y)) for x, y in exact(np.asarray(points_xy, float).reshape(-1, 2))]
    z0, z1 = exact(z0), exact(z1)
    return cq.Workplane("XY", origin=(0, 0, z0)).polyline(pts).close().extrude(exact(z1 - z0)).val()


def box_along(p0, p1, width: float, z0: float, z1: float):
    """Vertical prism: a strip `width` wide from xy point p0 to p1."""
    a, b = np.asarray(p0[:2], float), np.asarray(p1[:2], float)
    e = (b - a) / np.linalg.norm(b - a)
    n = np.array([-e[1], e[0]]) * width / 2
    return prism([a - n, b - n, b + n, a + n], z0, z1)


def cylinder(p0, d, length: float, r: float):
    return _cq().Solid.makeCylinder(exact(r), exact(length), vec(p0), vec(d))


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
    outline = [tuple(map(float, xz)) for xz in exact([(r * sa, -1.0), (run + r * sa, -1.0), (run + r * sa, z1 - r * ca),
                                                        (run, z1), (0, z0), (r * sa, z0 - r * ca)])]
    plane = cq.Plane(origin=tuple(map(float, exact((p0[0], p0[1], 0.0)))), xDir=tuple(map(float, exact(h))),
                     normal=tuple(map(float, exact(-lat))))
    web = cq.Workplane(plane).polyline(outline).close().extrude(exact(skirt * r), both=True).val()
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
    rb = exact(s.bore / 2)
    extra = 2.0
    hole = cq.Solid.makeCylinder(rb, exact(s.depth + extra), vec(s.bottom), vec(s.direction))
    cone = cq.Solid.makeCone(rb, exact(rb + chamfer + extra), exact(chamfer + extra), vec(s.mouth - s.direction * chamfer),
                             vec(s.direction))
    return hole.fuse(cone)


def apply(shape, m: np.ndarray):
    """Rigid 4x4 transform of a cq shape (a copy), via gp_Trsf."""
    import cadquery as cq
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf

    t = gp_Trsf()
    t.SetValues(*[float(v) for v in exact(np.asarray(m, float)[:3]).ravel()])
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


# -- the pieces the side-printed joints share (families/joint_kinds/: the knee, the core links) --

def arm_block(arms: list[PSocket], r: float, start: float):
    """The stacked arm sockets: each arm's sleeve stands on the bed, so together they make one block.
    Every sleeve is built straight above or below the first arm's (`stacked`)."""
    return fuse_all([sleeve(stacked(arms[0], s), start, r) for s in arms])


def stacked(a: PSocket, s: PSocket) -> PSocket:
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
    axis_z, r = exact(axis_z), exact(r)
    k = r / math.sqrt(2.0)  # the tangent points: (+-k, -k) from the axis
    z_web = -r * math.sqrt(2.0) + web / 2  # where the flanks meet the web, from the axis
    if web / 2 >= k - 0.05 or axis_z + z_web <= 0.2:
        return dsleeve(start, d, length, axis_z, r)
    h = web / 2
    return along(start, d, length, axis_z,
                 lambda wp: (wp.moveTo(-h, -axis_z).lineTo(h, -axis_z).lineTo(h, z_web).lineTo(k, -k)
                             .threePointArc((0, r), (-k, -k)).lineTo(-h, z_web).close()))

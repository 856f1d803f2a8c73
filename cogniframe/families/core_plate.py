"""The core plate (ABS/PLA): a flat plate with the FC/ESC stack holes and the core links' bolt
holes, printed as it sits (translated up by half its thickness); its local frame is centred on
its placement origin, axes as the frame.

With the pegged core link (core.link: pegs) the plate has no link bolt holes; it carries one ABS
tube per peg instead, the bore the peg presses into (`frame.PEG_D`, `frame.PEG_TUBE_WALL`
round it, as long as the peg and coaxial with it), hanging under the plate with its top flush
with the plate's top (frame.py `peg_drop` puts the arms there). The tubes lie beyond the plate's
edges (7 mm in both presets), and each is joined to the nearest edge by a web as thick as the
plate: the hull of the tube's footprint and its inner end's footprint corners projected onto that
edge. Webs, not a larger (plus-shaped) plate: they carry the same peg into the same edge for a
fraction of the ABS, and the web under the whole tube is what lets the round tube print. The
plate then prints upside down: its top, the webs and the tubes' tops on the bed, each tube lying
along the bed (its bore's ceiling is a bridge 4.8 mm wide, its round outside above the web never
steeper than 45 deg).
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import PEG_TUBE_WALL, Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts.blocks import plate
from ..parts.joint_plan import FLIP_X, hull_ccw, transform
from ..parts.joint_solid import Built
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import link_hole, plate_estimate, rounded

NAME = "core_plate"
SIZE_KEY = "core.plate_size"
DOC = "ABS/PLA core plate with stack and core-link holes (or, with pegged links, the pegs' tubes)"


# An M2 hex nylon standoff (4 mm across flats, threaded through): PA66 at 1.14 g/cm^3 over the
# hexagon less the M2 thread's core, about 11.8 mm^2.
NYLON_STANDOFF_G_PER_MM = 0.0135
# mm: a web reaches this far into the plate (its CAD overlaps the plate instead of touching it
# along a face; the closed form counts only what lies outside the plate)
WEB_INTO_PLATE = 0.5
LEVEL_TOL = 1e-5  # mm: a tube's axis level and flush as planned (sockets and placements are stored to 1e-6)
# mm: OCC's fuzzy boolean tolerance for the tubes and webs. A web's outer end face is the plane
# of its tube's end (the web runs under the whole tube); with the arms off the diagonal (a
# rectangle) the exact booleans left the union split along such faces, in up to 25 solids of the
# right total volume; fuzzy, each of 20 random designs gave one solid of the same volume.
FUZZ = 1e-4


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_core_plate(spec, frame),)


def _core_plate(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    pegs = c.link == "pegs"
    holes = [(sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1)]
    if not pegs:
        hole = link_hole(spec)
        holes += [(sx * hole, sy * hole) for sx in (-1, 1) for sy in (-1, 1)]
    est = plate_estimate(c.plate_size, c.plate_size, c.plate_thickness, [screw.clearance_d] * len(holes))
    params: list[tuple[str, object]] = [("size", c.plate_size), ("thickness", c.plate_thickness), ("holes", tuple(holes)),
                                        ("hole_d", screw.clearance_d)]
    if pegs:
        tubes, bore = peg_tubes(spec, frame)
        webs = tuple(tube_web(e, s, bore / 2 + PEG_TUBE_WALL, c.plate_size / 2) for e, s in tubes)
        params += [("tube_bore", bore), ("tube_wall", PEG_TUBE_WALL), ("tubes", tubes), ("webs", webs)]
        est = _with_tubes(est, dict(params))
    hang = frame.core.hang
    if hang > 0:
        # level arms: the plate stands on four standoffs on the holder; the stack screws end in
        # their tops, short screws come up through the holder (and spacer) into their bottoms
        hw = (HardwareLine(f"{screw.name} x 20 screw + 8 mm nylon standoffs (FC/ESC stack onto the plate)", 4, 1.0),
              HardwareLine(f"{screw.name} x {hang:g} mm nylon standoff, female-female (plate on the battery holder)", 4,
                           round(NYLON_STANDOFF_G_PER_MM * hang, 3)),
              HardwareLine(f"{screw.name} x 6 screw (battery holder to standoff)", 4, screw.mass_of(6)))
    else:
        hw = (HardwareLine(f"{screw.name} x 20 screw + 8 mm nylon standoffs (FC/ESC stack through plate and holder)", 4, 1.0),)
    return PartSpec("core_plate", "core_plate", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(frame.core.plate.centre)),), (), c.plate_thickness, est, tuple(params), hw)


# -- the pegs' tubes (core.link: pegs) -----------------------------------------------------------

def peg_tubes(spec: Spec, frame: Frame) -> tuple[tuple[tuple, tuple], float]:
    """((inner end, outer end) of each tube's axis in the plate's local frame, ...), the bore (mm):
    one tube per peg of every placed core link, coaxial with it and as long (parts/joint_plan.py
    `peg_axes` of the joint family's own link parts, through each copy's placement)."""
    from ..parts.joint_plan import peg_axes
    from .joint import core_links

    centre = np.asarray(frame.core.plate.centre, float)
    top = spec.core.plate_thickness / 2
    tubes = []
    radii = set()
    for link in core_links(spec, frame):
        axes = peg_axes(link.sockets, dict(link.params))
        for pl in link.placements:
            m = pl.matrix()
            for ax in axes:
                e, s = (m[:3, :3] @ p + m[:3, 3] - centre for p in (ax.end, ax.shoulder))
                r_out = ax.radius + PEG_TUBE_WALL
                # the frame hangs the plate so that the arms' tubes are flush with the plate's top
                # (frame.peg_drop); the strut's peg may lie lower (its column stands under the
                # strut's bore), its tube then sunk into its web. A tube above the plate's top
                # (below the bed in print), off the web, or not level is a bug, not a design.
                if abs(e[2] - s[2]) > LEVEL_TOL or e[2] + r_out > top + LEVEL_TOL or e[2] + r_out < top - LEVEL_TOL - r_out:
                    raise RuntimeError(f"{link.name} at {pl.instance}: its peg's axis runs from z {e[2]:.6f} to {s[2]:.6f} "
                                       f"in the plate's frame: its tube (outside radius {r_out:g}) is not level within the "
                                       f"plate's {2 * top:g} mm under its top")
                tubes.append((rounded(e), rounded(s)))
                radii.add(round(ax.radius, 9))
    if len(radii) != 1:
        raise RuntimeError(f"the core links' pegs differ in radius: {sorted(radii)}")
    return tuple(tubes), 2 * radii.pop()


def tube_web(end, shoulder, r_out: float, half: float) -> tuple:
    """A tube's web in plan (the plate's local xy, counter-clockwise): the hull of the tube's
    footprint (its axis from `end` to `shoulder`, `r_out` either side) and its inner end's two
    footprint corners projected onto the plate edge the end lies beyond (`WEB_INTO_PLATE` inside
    it). The plate is |x|, |y| <= `half`."""
    e, s = np.asarray(end, float)[:2], np.asarray(shoulder, float)[:2]
    u = (s - e) / np.linalg.norm(s - e)
    n = np.array([-u[1], u[0]]) * r_out
    rect = [e - n, s - n, s + n, e + n]
    k = int(np.argmax(np.abs(e)))
    feet = []
    for p in (e - n, e + n):
        f = p.copy()
        f[k] = math.copysign(half - WEB_INTO_PLATE, e[k])
        feet.append(f)
    return tuple((round(float(x), 6), round(float(y), 6)) for x, y in hull_ccw(rect + feet))


def _webs_off_plate(webs, half: float) -> list[np.ndarray]:
    """The union of the webs (plan) outside the plate |x|, |y| <= `half`, as polygons: where a
    link's webs overlap (arms off the plate's diagonal) they are one prism, as in the CAD
    (manifold3d's exact 2-D boolean, the library the meshes already use)."""
    import manifold3d as m3

    square = m3.CrossSection.square((2 * half, 2 * half), center=True)
    union = m3.CrossSection([[tuple(map(float, q)) for q in webs[0]]])
    for w in webs[1:]:
        union = union + m3.CrossSection([[tuple(map(float, q)) for q in w]])
    return [np.asarray(poly, float) for poly in (union - square).to_polygons()], float((union - square).area())


def _on_edge(a, b, half: float) -> bool:
    return any(abs(abs(a[k]) - half) < 1e-6 and abs(abs(b[k]) - half) < 1e-6 and a[k] * b[k] > 0 for k in range(2))


def webs_outside(webs, half: float) -> tuple[float, float]:
    """(area, perimeter) of the webs' union outside the plate |x|, |y| <= `half`; the perimeter
    leaves out its sides along the plate's edge (they join the plate: no surface)."""
    polys, area = _webs_off_plate(webs, half)
    per = sum(float(np.linalg.norm(b - a)) for pts in polys for a, b in zip(pts, np.roll(pts, -1, axis=0))
              if not _on_edge(a, b, half))
    return area, per


def web_roots(webs, half: float) -> list[tuple[tuple[float, float], float]]:
    """Where the webs join the plate: each side of their union that lies along the plate's edge,
    as (its midpoint in plan, its length), mm: the section a pegged link's load crosses into the
    plate (analysis/load_cases.py)."""
    polys, _ = _webs_off_plate(webs, half)
    return [(tuple(float(v) for v in (a + b) / 2), float(np.linalg.norm(b - a)))
            for pts in polys for a, b in zip(pts, np.roll(pts, -1, axis=0)) if _on_edge(a, b, half)]


def _with_tubes(base: Estimate, params: dict) -> Estimate:
    """The plate's closed form plus the tubes and webs, in print (upside down: the plate's top on
    the bed). The webs are one prism `t` thick over their union's plan outside the plate; each tube (length L,
    bore r_b, outside r_o, its axis z above the bed, the web's top h = z - t below the axis)
    adds its outside circle's part above the web, less the bore: L (pi r_o^2 - seg(h) - pi r_b^2),
    h its axis's height over the web (r_o - t flush with the plate's top; a sunk tube's higher),
    seg(h) = r_o^2 acos(h / r_o) - h sqrt(r_o^2 - h^2) (the circle below a chord h from its
    centre). Exact but for faceting wherever the tubes keep clear of each other (families/joint.py
    `PEG_WEB`) and of the plate's holes: the webs (or the plate) lie under every tube, the bore
    inside the two."""
    t, half = float(params["thickness"]), float(params["size"]) / 2
    r_b = float(params["tube_bore"]) / 2
    r_o = r_b + float(params["tube_wall"])
    a_w, p_w = webs_outside(params["webs"], half)
    vol = base.volume + a_w * t
    a_h = base.area_h + 2 * a_w
    a_v = base.area_v + t * p_w
    pts = [np.array([x, y]) for x in (-half, half) for y in (-half, half)]
    z_top = t
    for (e, s), web in zip(params["tubes"], params["webs"]):
        z = t / 2 - float(e[2])  # the axis's height in print: r_o for a tube flush with the plate's top
        h = min(max(z - t, -r_o), r_o)
        seg = r_o**2 * math.acos(h / r_o) - h * math.sqrt(r_o**2 - h * h)
        above = math.pi * r_o**2 - seg
        chord = 2 * math.sqrt(r_o**2 - h * h)
        arc = r_o * (2 * math.pi - 2 * math.acos(h / r_o))
        L = float(np.linalg.norm(np.asarray(s, float) - np.asarray(e, float)))
        vol += L * (above - math.pi * r_b**2)
        a_h += -chord * L + arc * L / 2  # the tube on its web's top, half its round
        a_v += arc * L / 2 + 2 * math.pi * r_b * L + 2 * (above - math.pi * r_b**2)
        pts += [np.asarray(p, float) for p in web]
        z_top = max(z_top, z + r_o)
    p = np.asarray(pts)
    ext = np.ptp(p, axis=0)
    return Estimate(vol, a_h, a_v, (float(ext[0]), float(ext[1]), z_top))


# -- the solid --------------------------------------------------------------------------------

def print_from_local(part: PartSpec) -> np.ndarray:
    """As it sits, or upside down (its top on the bed) when it carries the pegs' tubes."""
    t = float(part.param("thickness"))
    return transform(FLIP_X if dict(part.params).get("tubes") else np.eye(3), (0.0, 0.0, t / 2))


def solid(part: PartSpec) -> Built:
    size = float(part.param("size"))
    t = float(part.param("thickness"))
    m = print_from_local(part)
    holes = tuple((float(x), float(y) * float(m[1, 1])) for x, y in part.param("holes"))
    shape = plate(size, size, t, [(float(part.param("hole_d")), holes)])
    params = dict(part.params)
    if params.get("tubes"):
        shape = _with_tube_solids(shape, params, m)
    return Built(shape, m)


def _with_tube_solids(shape, params: dict, m: np.ndarray):
    """The plate (print coordinates) with each tube and its web, less the bores: webs on the bed
    `t` thick, each tube's outside from halfway up the web (inside it: no face tangent to the
    bed) to its round top, the bore through it."""
    import cadquery as cq

    from ..parts.joint_solid import VOID_MM3, cylinder, prism

    t = float(params["thickness"])
    r_b = float(params["tube_bore"]) / 2
    r_o = r_b + float(params["tube_wall"])
    big = 1000.0
    keep = cq.Solid.makeBox(2 * big, 2 * big, big, cq.Vector(-big, -big, t / 2))
    pieces, bores = [shape], []
    for (e, s), web in zip(params["tubes"], params["webs"]):
        pe, ps = (m[:3, :3] @ np.asarray(p, float) + m[:3, 3] for p in (e, s))
        d = ps - pe
        L = float(np.linalg.norm(d))
        d /= L
        pieces.append(prism([(m[:2, :2] @ np.asarray(p, float)) for p in web], 0.0, t))
        pieces.append(cylinder(pe, d, L, r_o).intersect(keep))
        # the bore from the peg's end on, out past the tube's outer end (no end face of it there)
        bores.append(cylinder(pe, d, L + 1.0, r_b))
    first, *rest = pieces
    body = first.fuse(*rest, tol=FUZZ).clean()
    bore = bores[0].fuse(*bores[1:], tol=FUZZ) if len(bores) > 1 else bores[0]
    solids = [x for x in body.cut(bore, tol=FUZZ).clean().Solids() if x.Volume() > VOID_MM3]
    if len(solids) != 1:
        raise RuntimeError(f"the core plate with its peg tubes came out as {len(solids)} solids instead of 1")
    return solids[0]

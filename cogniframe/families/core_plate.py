"""The core plate (ABS/PLA): a flat plate with the FC/ESC stack holes and the core links' bolt
holes, printed as it sits (translated up by half its thickness); its local frame is centred on
its placement origin, axes as the frame.

With the pegged core link (core.link: pegs) the plate has no link bolt holes; it carries one ABS
tube per peg instead, the bore the peg presses into (`frame.PEG_D`, `frame.PEG_TUBE_WALL` round
it, as long as the peg and coaxial with it), hanging under the plate with its top flush with the
plate's top (frame.py `peg_drop` puts the arms there). The plate is then an X like the authors'
plus-shaped MainBase rather than the square (`pegged_layout`): per link a bar under its tubes, a
stem from its stack hole to them, ribbed underneath where the link's pull bends it, and a strip
on to the centre. It prints upside down: its top, the bars and the tubes' tops on the bed, each
tube lying along the bed on its bar (its bore's ceiling a bridge 4.8 mm wide, its round outside
above the slab never steeper than 45 deg), the ribs standing up from the stems.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..frame import PEG_TUBE_WALL, Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts.blocks import plate
from ..parts.joint_plan import FLIP_X, hull_ccw, transform
from ..parts.joint_solid import Built
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import plate_estimate, rounded
from .joint_kinds.kinds import core_link, kind_of, node_of

NAME = "core_plate"
SIZE_KEY = "core.plate_size"
DOC = "ABS/PLA core plate with stack and core-link holes (or, with pegged links, the pegs' tubes)"


# An M2 hex nylon standoff (4 mm across flats, threaded through): PA66 at 1.14 g/cm^3 over the
# hexagon less the M2 thread's core, about 11.8 mm^2.
NYLON_STANDOFF_G_PER_MM = 0.0135
# mm: the pegged plate's rails, centre -> stack hole -> the link's tubes: the M2 stack hole's
# 2.4 mm clearance with 2.3 mm of ABS either side (five 0.45 mm lines; an M2 standoff's 4 mm hex
# seats on it), as the spacer's rails (sensor_mount.SPACER_RAIL)
PLATE_RAIL = 7.0
# mm: the strips joining the four stems at the centre carry no link's load (the stack's standoffs
# hold the plate at the holes): ten 0.4 mm lines
CENTRE_RAIL = 4.0
# mm: each stem's rib under the plate. A link's pull bends its stem as a cantilever off the stack
# standoffs (analysis/load_cases.py): the rib makes the stem 7 mm deep, its section 7 x 7 mm
# (a bending modulus of 57 mm^3, the 40 mm square's corner across its stack hole had 42). It
# starts clear of the standoff (4 mm across flats, 2.31 mm to a corner) and stops short of the
# tubes (no face of it on a tube's), where the gusset, a slab `GUSSET` wide, carries on.
RIB = 3.5
RIB_START = 2.5
RIB_GAP = 1.0
GUSSET = 20.0
# core.support_holes: the authors' base carries four 3.0 mm through holes on a 25.4 mm radius on
# its axes, 9.2 mm deep (thecognifly/CogniFly-STL, CogniFly_v8_Crash_Tests/MainBase.stl, measured
# with tools/compare_parts.py: 2.98 mm at (+-25.41, 0) and (0, +-25.41)), the pattern of their Pi
# support's 3.98 mm holes (RPI_Support_new.stl). Each sits in a boss as wide as a stem
# (`PLATE_RAIL`: 2.0 mm of ABS round the hole, five 0.4 mm lines) and as deep as the pegs' tubes
# (their 9.2 mm block), at the end of a bar as wide from the plate's centre.
SUPPORT_HOLE_D = 3.0
SUPPORT_HOLE_RADIUS = 25.4
LEVEL_TOL = 1e-5  # mm: a tube's axis level and flush as planned (sockets and placements are stored to 1e-6)
# mm: OCC's fuzzy boolean tolerance for the slab, ribs and tubes. A bar's outer edge is the plane
# of its tubes' outer ends (the bar runs under the whole tube) and a rib's sides are its stem's;
# exact booleans left such unions split along those faces (the webs before the bars: up to 25
# solids of the right total volume); fuzzy, one (tests/test_core_plate_pegs.py's random designs).
FUZZ = 1e-4


PLANS_FROM_EARLIER = True  # its peg tubes are placed from the joint family's core links (registry.py)


def plan(spec: Spec, frame: Frame, earlier=None) -> tuple[PartSpec, ...]:
    """The core plate; `earlier`: the parts planned before it (`PLANS_FROM_EARLIER`), whose core
    links place its peg tubes, else those links are planned here."""
    links = None if earlier is None else tuple(p for p in earlier if p.family == "joint" and node_of(p) == "core_link")
    return (_core_plate(spec, frame, links),)


def _core_plate(spec: Spec, frame: Frame, links=None) -> PartSpec:
    c = spec.core
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    holes = [(sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1)]
    holes += core_link(spec).plate_bolts(spec)
    est = plate_estimate(c.plate_size, c.plate_size, c.plate_thickness, [screw.clearance_d] * len(holes))
    params: list[tuple[str, object]] = [("size", c.plate_size), ("thickness", c.plate_thickness), ("holes", tuple(holes)),
                                        ("hole_d", screw.clearance_d)]
    tubes, bore = peg_tubes(spec, frame, links)
    if tubes:
        r_out = bore / 2 + PEG_TUBE_WALL
        outline, ribs = pegged_layout(tubes, r_out, holes)
        params += [("tube_bore", bore), ("tube_wall", PEG_TUBE_WALL), ("tubes", tubes), ("outline", outline),
                   ("ribs", ribs), ("rib_width", PLATE_RAIL), ("rib_depth", RIB)]
        if c.support_holes:
            supports = support_holes(spec, tubes, bore, outline)
            params += [("support_holes", supports), ("support_hole_d", SUPPORT_HOLE_D), ("boss_d", PLATE_RAIL),
                       ("boss_depth", 2 * r_out)]
            params[params.index(("outline", outline))] = ("outline", outline + support_bars(supports, PLATE_RAIL))
        est = _with_tubes(dict(params))
    hw = stack_plan(spec, frame).lines
    return PartSpec("core_plate", "core_plate", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(frame.core.plate.centre)),), (), c.plate_thickness, est, tuple(params), hw)


# -- the stack's hardware ------------------------------------------------------------------------

STACK_SPACER = 8.0  # mm: the nylon spacers between the ESC and the FC (a 20x20 stack's)
CORNERS = {(-1, 1): "fl", (1, 1): "fr", (-1, -1): "rl", (1, -1): "rr"}  # as frame.py's: fl = (-x, +y)


@dataclass(frozen=True)
class Leg:
    """One stack hole's hardware, world coordinates (mm): the standoff under the plate (level arms;
    `standoff` its length, from `z0`), what the countersunk screw from inside the holder passes
    (`under`: the parts with their hole, `grip` their thickness from the cavity's ceiling)."""

    corner: str
    xy: tuple[float, float]
    z0: float
    standoff: float
    under: tuple[tuple[str, float], ...]
    grip: float


@dataclass(frozen=True)
class StackPlan:
    """The FC/ESC stack's screws, spacers and standoffs (fasteners.py places them, the hardware
    lines carry their masses): one truth for both. `ceiling`: the holder cavity's ceiling, where the
    countersunk heads sit flush; `head_z`: the stack screws' heads (on the FC, or on the computer
    mount); `spacers`: (z0, length, hardware line) of the nylon spacers every hole carries."""

    level: bool
    screw: str
    legs: tuple[Leg, ...]
    ceiling: float
    holder_screw: float  # its length (ISO 7046: overall, the head included)
    stack_screw: float  # level: from the FC (or computer mount) into the standoffs; else 0
    head_z: float
    stack_grip: float  # level: head to the plate's underside; else head to the ceiling
    through: tuple[tuple[str, float], ...]  # the printed parts the stack screw passes (hole d)
    spacers: tuple[tuple[float, float, str], ...]
    lines: tuple[HardwareLine, ...]


def _stock(screw, need: float) -> float:
    """The shortest stock length of `screw` at least `need` mm (the longest when none is)."""
    return float(next((L for L in screw.lengths if L >= need - 1e-9), screw.lengths[-1]))


def stack_plan(spec: Spec, frame: Frame) -> StackPlan:
    """The stack's hardware (fasteners.py's docstring tells the order). The holder screw is the
    shortest stock length that engages its standoff 4 turns past the thickest grip; the stack screw
    the shortest that engages 4 turns past the plate's underside (level arms), or fills a nut on
    top (the plate on the holder)."""
    from ..materials import BOARDS, MIN_THREAD_TURNS
    from ..frame import STACK_BOTTOM
    from .computer_mount import COMPUTER_T
    from .sensor_mount import sensor_mount_outline

    c, core = spec.core, frame.core
    screw = SCREWS[c.stack_screw]
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    key = "20x20" if pitch < 25 else "30x30"
    esc_t, fc_t = BOARDS[f"esc_{key}"].size[2], BOARDS[f"fc_{key}"].size[2]
    wall = c.holder_wall
    ceiling = float(core.holder.hi[2]) - wall
    spacer_holes = set()
    spacer_name = "sensor_mount" if c.flow_sensor else "core_spacer"
    if core.spacer is not None:
        spacer_holes = {(round(x, 6), round(y, 6)) for x, y in sensor_mount_outline(spec, frame)["stack_holes"]}
    level = core.hang > 0
    z_fc = float(core.stack.lo[2]) + STACK_BOTTOM + esc_t + STACK_SPACER + fc_t  # the FC's top face
    head_z, through = z_fc, []
    spacers = [(z_fc - fc_t - STACK_SPACER, STACK_SPACER,
                f"{screw.name} x {STACK_SPACER:g} mm nylon spacer (between the ESC and the FC)")]
    lines = [HardwareLine(spacers[0][2], 4, round(NYLON_STANDOFF_G_PER_MM * STACK_SPACER, 3))]
    if c.computer and core.computer is not None:
        from ..frame import COMPUTER_LIFT

        mount_z = float(core.computer.lo[2]) - COMPUTER_LIFT - COMPUTER_T
        gap = round(mount_z - z_fc, 3)
        spacers.append((z_fc, gap, f"{screw.name} x {gap:g} mm nylon spacer (computer mount over the FC)"))
        lines.append(HardwareLine(spacers[-1][2], 4, round(NYLON_STANDOFF_G_PER_MM * gap, 3)))
        head_z = mount_z + COMPUTER_T
        through.append(("computer_mount", screw.clearance_d))
    if c.camera:
        through.append(("front_camera_mount", screw.clearance_d))
    through.append(("core_plate", screw.clearance_d))
    legs = []
    for sx, sy in ((-1, 1), (1, 1), (-1, -1), (1, -1)):
        xy = (sx * pitch / 2, sy * pitch / 2)
        on_spacer = (round(xy[0], 6), round(xy[1], 6)) in spacer_holes
        under = (("battery_holder", screw.clearance_d),) + (((spacer_name, screw.clearance_d),) if on_spacer else ())
        z0 = float(core.spacer.hi[2]) if on_spacer else float(core.holder.hi[2])
        legs.append(Leg(CORNERS[(sx, sy)], xy, z0, round(float(core.plate.lo[2]) - z0, 4) if level else 0.0, under,
                        round(z0 - ceiling, 4)))
    engage = MIN_THREAD_TURNS * screw.pitch
    if level:
        holder_screw = _stock(screw, max(g.grip for g in legs) + engage)
        grip = round(head_z - float(core.plate.lo[2]), 4)
        stack_screw = _stock(screw, grip + engage)
        by_length: dict[float, list[str]] = {}
        for g in legs:
            by_length.setdefault(g.standoff, []).append(g.corner)
        split = len(by_length) > 1  # the spacer's bar under the rear two only (sensor_mount.rear_only)
        for length, corners in sorted(by_length.items()):
            on_spacer = any(dict(g.under).get(spacer_name) for g in legs if g.standoff == length)
            where = (f"on the {'sensor mount' if c.flow_sensor else 'spacer'}'s bar" if on_spacer else "on the battery holder") \
                + ((", rear" if on_spacer else ", front") if split else "")
            lines.append(HardwareLine(f"{screw.name} x {length:g} mm nylon standoff, female-female (plate {where})", len(corners),
                                      round(NYLON_STANDOFF_G_PER_MM * length, 3)))
        lines.insert(0, HardwareLine(f"{screw.name} x {stack_screw:g} socket-head screw (ISO 4762): FC/ESC stack"
                                     + (", computer mount" if c.computer else "") + " into the standoffs", 4,
                                     screw.mass_of(stack_screw)))
        lines.append(HardwareLine(f"{screw.name} x {holder_screw:g} countersunk screw (ISO 7046): battery holder to "
                                  "standoff, from inside", 4, screw.mass_of(holder_screw)))
    else:  # one long screw from inside the holder through everything, a nut on top
        grip = round(head_z - ceiling, 4)
        holder_screw = _stock(screw, grip + screw.nut_m)
        stack_screw = 0.0
        lines.insert(0, HardwareLine(f"{screw.name} x {holder_screw:g} countersunk screw (ISO 7046) + nut: battery holder, "
                                     "plate and FC/ESC stack, from inside the holder", 4, screw.mass_of(holder_screw) + 0.1))
    return StackPlan(level, screw.name, tuple(legs), round(ceiling, 4), holder_screw, stack_screw, round(head_z, 4), grip,
                     tuple(through), tuple((round(z, 4), L, line) for z, L, line in spacers), tuple(lines))


# -- the pegs' tubes (core.link: pegs) -----------------------------------------------------------

def peg_tubes(spec: Spec, frame: Frame, links=None) -> tuple[tuple[tuple, tuple], float]:
    """((inner end, outer end) of each tube's axis in the plate's local frame, ...), the bore (mm):
    one tube per peg of every placed core link, coaxial with it and as long (its kind's `peg_axes`:
    parts/peg_plan.py's, of the joint family's own link parts, through each copy's placement);
    none, bore 0, for a link without pegs. `links`: the joint family's core link parts
    (`joint.core_links`) when the caller has them."""
    if links is None:
        from .joint import core_links

        links = core_links(spec, frame)
    centre = np.asarray(frame.core.plate.centre, float)
    top = spec.core.plate_thickness / 2
    tubes = []
    radii = set()
    for link in links:
        axes = kind_of(link).peg_axes(link)
        for pl in link.placements:
            m = pl.matrix()
            for ax in axes:
                e, s = (m[:3, :3] @ p + m[:3, 3] - centre for p in (ax.end, ax.shoulder))
                r_out = ax.radius + PEG_TUBE_WALL
                # the frame hangs the plate so that the tubes are flush with the plate's top
                # (frame.peg_drop). A tube off the plate's top or not level is a bug, not a design.
                if abs(e[2] - s[2]) > LEVEL_TOL or abs(e[2] + r_out - top) > LEVEL_TOL:
                    raise RuntimeError(f"{link.name} at {pl.instance}: its peg's axis runs from z {e[2]:.6f} to {s[2]:.6f} "
                                       f"in the plate's frame: its tube (outside radius {r_out:g}) is not level within the "
                                       f"plate's {2 * top:g} mm under its top")
                tubes.append((rounded(e), rounded(s)))
                radii.add(round(ax.radius, 9))
    if not tubes:
        return (), 0.0
    if len(radii) != 1:
        raise RuntimeError(f"the core links' pegs differ in radius: {sorted(radii)}")
    return tuple(tubes), 2 * radii.pop()


def pegged_layout(tubes, r_out: float, stack_holes) -> tuple[tuple, tuple]:
    """The pegged plate in plan (its local xy), as (pieces, ribs). Per core link (`tubes` come link
    copy by link copy, `peg_tubes`, the same number each): a bar, the hull of its tubes' footprints
    (each axis `r_out` either side); a stem `PLATE_RAIL` wide from behind its stack hole to the
    middle of its tubes; a strip `CENTRE_RAIL` wide from the plate's centre to the hole (the four
    corners one piece); and a gusset `GUSSET` wide across the stem from `RIB_GAP` + 0.5 before the
    tubes' inner ends to 0.5 past them. Each piece counter-clockwise. A rib (its axis's two ends)
    `PLATE_RAIL` wide and `RIB` deep runs under the stem from `RIB_START` past the hole to
    `RIB_GAP` before the nearest tube footprint."""
    n = len(tubes) // 4
    pieces, ribs = [], []

    def strip(a, b, w, back=0.0, ahead=0.0):
        u = (b - a) / np.linalg.norm(b - a)
        m = np.array([-u[1], u[0]]) * w / 2
        a, b = a - u * back, b + u * ahead
        return [a - m, b - m, b + m, a + m]

    for i in range(0, len(tubes), n):
        group = [tuple(np.asarray(p, float)[:2] for p in t) for t in tubes[i:i + n]]
        feet = []
        for e, s in group:
            feet += strip(e, s, 2 * r_out)
        mid = np.mean([(e + s) / 2 for e, s in group], axis=0)
        hole = np.asarray(min(stack_holes, key=lambda h: float(np.linalg.norm(np.asarray(h, float) - mid))), float)
        u = (mid - hole) / np.linalg.norm(mid - hole)
        reach = min(float((f - hole) @ u) for f in feet)  # the tubes' nearest footprint, along the stem
        end = hole + u * (reach - RIB_GAP)
        for poly in (feet, strip(hole, mid, PLATE_RAIL, back=PLATE_RAIL / 2), strip(np.zeros(2), hole, CENTRE_RAIL),
                     strip(end, hole + u * reach, GUSSET, back=0.5, ahead=0.5)):
            pieces.append(tuple((round(float(x), 6), round(float(y), 6)) for x, y in hull_ccw(poly)))
        ribs.append(tuple((round(float(x), 6), round(float(y), 6)) for x, y in (hole + u * RIB_START, end)))
    return tuple(pieces), tuple(ribs)


def support_holes(spec: Spec, tubes, bore: float, outline) -> tuple[tuple[float, float], ...]:
    """The four mounting holes (core.support_holes), the plate's local xy, on the authors' pattern;
    or an error naming the key where a hole would open into a peg's bore (a smaller core or wider
    arm pair brings the tubes onto the axes): the hole must keep a nozzle line (0.4 mm) of ABS
    from every bore, as the authors' holes keep 0.54 mm from theirs. The boss's half past its
    bar's end must lie off the X's `outline` (the closed form counts it whole, `_with_tubes`)."""
    import manifold3d as m3

    pts = ((SUPPORT_HOLE_RADIUS, 0.0), (0.0, SUPPORT_HOLE_RADIUS), (-SUPPORT_HOLE_RADIUS, 0.0), (0.0, -SUPPORT_HOLE_RADIUS))
    x_plate = m3.CrossSection.batch_boolean([m3.CrossSection([[tuple(map(float, q)) for q in p]]) for p in outline], m3.OpType.Add)
    for q in pts:
        u = np.asarray(q, float) / SUPPORT_HOLE_RADIUS
        n = np.array([-u[1], u[0]]) * PLATE_RAIL
        b = np.asarray(q, float)
        beyond = m3.CrossSection([[tuple(map(float, p)) for p in (b - n, b + 2 * PLATE_RAIL * u - n, b + 2 * PLATE_RAIL * u + n, b + n)]])
        overlap = (m3.CrossSection.circle(PLATE_RAIL / 2, 64).translate(tuple(b)) ^ beyond ^ x_plate).area()
        if overlap > 1e-3:
            raise spec.error("core.support_holes", f"the mounting hole's boss at ({q[0]:g}, {q[1]:g}) mm runs into the bar under "
                             f"a core link's tubes ({overlap:.2f} mm^2)",
                             "set core.support_holes: false, or change core.plate_size or frame.arm_spacing to move the tubes off the axes")
    for q in pts:
        for e, s in tubes:
            a, b, x = np.asarray(e[:2], float), np.asarray(s[:2], float), np.asarray(q, float)
            f = min(max(float((x - a) @ (b - a) / ((b - a) @ (b - a))), 0.0), 1.0)
            gap = float(np.linalg.norm(x - (a + f * (b - a)))) - bore / 2 - SUPPORT_HOLE_D / 2
            if gap < 0.4:
                raise spec.error("core.support_holes", f"the mounting hole at ({q[0]:g}, {q[1]:g}) mm keeps only {gap:.2f} mm "
                                 f"from a peg's {bore:g} mm bore (the tube from ({e[0]:g}, {e[1]:g}))",
                                 "set core.support_holes: false, or move the tubes off the axes (a larger core.plate_size)")
    return pts


def support_bars(holes, width: float) -> tuple[tuple[tuple[float, float], ...], ...]:
    """One bar per mounting hole, `width` wide from the plate's centre to the hole's centre, where
    its boss (a circle as wide) takes over: the bar covers exactly half the boss's circle, which
    the closed form (`_with_tubes`) counts once."""
    out = []
    for x, y in holes:
        u = np.array([x, y], float) / math.hypot(x, y)
        n = np.array([-u[1], u[0]]) * width / 2
        b = np.array([x, y], float)
        out.append(tuple((round(float(p[0]), 6), round(float(p[1]), 6)) for p in (-n, b - n, b + n, n)))
    return tuple(out)


def outline_union(pieces):
    """The union of the outline's pieces (manifold3d's exact 2-D boolean, the library the meshes
    already use): its one outer loop, counter-clockwise, and that loop's area; or an error naming
    the plate. Any hole the pieces enclose is filled: where a bar, a stem and a gusset nearly meet
    they leave slivers of a fraction of a mm^2, which no printer can hold open."""
    import manifold3d as m3

    union = m3.CrossSection.batch_boolean([m3.CrossSection([[tuple(map(float, q)) for q in p]]) for p in pieces],
                                          m3.OpType.Add)
    outer = [np.asarray(p, float) for p in union.to_polygons() if _signed_area(np.asarray(p, float)) > 0]
    if len(outer) != 1:
        raise RuntimeError(f"the pegged core plate's outline came out as {len(outer)} pieces instead of one")
    return outer[0], _signed_area(outer[0])


def _signed_area(pts: np.ndarray) -> float:
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _with_tubes(params: dict) -> Estimate:
    """The pegged plate's closed form, in print (upside down: its top on the bed): the outline's
    union (area A, perimeter P) `t` thick less the stack holes, then each tube (length L, bore r_b,
    outside r_o, its axis z above the bed, the slab's top h = z - t below the axis) adds its
    outside circle's part above the slab, less the bore: L (pi r_o^2 - seg(h) - pi r_b^2), h its
    axis's height over the slab (r_o - t: flush with the plate's top),
    seg(h) = r_o^2 acos(h / r_o) - h sqrt(r_o^2 - h^2) (the circle below a chord h from its
    centre). Each rib (length L_r, width w, depth d) stands on the slab: w d L_r more, its two
    sides and two ends vertical, its top where the slab's top was. Exact but for faceting wherever
    the tubes keep clear of each other (families/joint_kinds/core_link_pegs.py `PEG_WEB`) and of the stack holes: the
    bars lie under every tube, the bore inside the two."""
    t = float(params["thickness"])
    r_b = float(params["tube_bore"]) / 2
    r_o = r_b + float(params["tube_wall"])
    poly, area = outline_union(params["outline"])
    per = float(np.sum(np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)))
    r_h = float(params["hole_d"]) / 2
    n_h = len(params["holes"])
    vol = (area - n_h * math.pi * r_h**2) * t
    a_h = 2 * (area - n_h * math.pi * r_h**2)
    a_v = (per + n_h * 2 * math.pi * r_h) * t
    z_top = t
    w_r, d_r = float(params["rib_width"]), float(params["rib_depth"])
    for a, b in params["ribs"]:
        L_r = float(np.linalg.norm(np.subtract(b, a)))
        vol += w_r * d_r * L_r
        a_v += 2 * (L_r + w_r) * d_r
        z_top = t + d_r
    # core.support_holes: each boss a cylinder (diameter w_b) from the bed to `boss_depth`, its
    # half beyond the bar's end over the slab's outline (support_bars), the hole through all of it
    w_b, r_s = float(params.get("boss_d", 0.0)) / 2, float(params.get("support_hole_d", 0.0)) / 2
    for _ in params.get("support_holes", ()):
        depth = float(params["boss_depth"])
        vol += math.pi * w_b**2 * (depth - t / 2) - math.pi * r_s**2 * depth
        a_h += -2 * math.pi * r_s**2 + math.pi * w_b**2 / 2  # the hole's two mouths; the boss's top past the slab
        a_v += math.pi * w_b * (depth - t) + math.pi * w_b * t / 2 + 2 * math.pi * r_s * depth
        z_top = max(z_top, depth)
    for e, s in params["tubes"]:
        z = t / 2 - float(e[2])  # the axis's height in print: r_o for a tube flush with the plate's top
        h = min(max(z - t, -r_o), r_o)
        seg = r_o**2 * math.acos(h / r_o) - h * math.sqrt(r_o**2 - h * h)
        above = math.pi * r_o**2 - seg
        chord = 2 * math.sqrt(r_o**2 - h * h)
        arc = r_o * (2 * math.pi - 2 * math.acos(h / r_o))
        L = float(np.linalg.norm(np.asarray(s, float) - np.asarray(e, float)))
        vol += L * (above - math.pi * r_b**2)
        a_h += -chord * L + arc * L / 2  # the tube on its bar's top, half its round
        a_v += arc * L / 2 + 2 * math.pi * r_b * L + 2 * (above - math.pi * r_b**2)
        z_top = max(z_top, z + r_o)
    ext = np.ptp(poly, axis=0)
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
    params = dict(part.params)
    if params.get("tubes"):
        return Built(_with_tube_solids(params, m, holes), m)
    return Built(plate(size, size, t, [(float(part.param("hole_d")), holes)]), m)


def _with_tube_solids(params: dict, m: np.ndarray, holes):
    """The pegged plate (print coordinates): the outline's union on the bed `t` thick less the
    stack holes, each tube's outside from halfway up the slab (inside it: no face tangent to the
    bed) to its round top, less the bores."""
    import cadquery as cq

    from ..parts.joint_solid import VOID_MM3, box_along, cylinder, prism

    t = float(params["thickness"])
    r_b = float(params["tube_bore"]) / 2
    r_o = r_b + float(params["tube_wall"])
    big = 1000.0
    keep = cq.Solid.makeBox(2 * big, 2 * big, big, cq.Vector(-big, -big, t / 2))
    poly, _ = outline_union(params["outline"])
    pieces, bores = [prism([(m[:2, :2] @ p) for p in poly], 0.0, t)], []
    w_r, d_r = float(params["rib_width"]), float(params["rib_depth"])
    for a, b in params["ribs"]:
        pieces.append(box_along(m[:2, :2] @ np.asarray(a, float), m[:2, :2] @ np.asarray(b, float), w_r, t, t + d_r))
    for x, y in holes:
        bores.append(cylinder((x, y, -1.0), (0.0, 0.0, 1.0), t + 2.0, float(params["hole_d"]) / 2))
    for x, y in params.get("support_holes", ()):
        q = m[:2, :2] @ np.asarray((x, y), float)
        depth = float(params["boss_depth"])
        pieces.append(cylinder((q[0], q[1], 0.0), (0.0, 0.0, 1.0), depth, float(params["boss_d"]) / 2))
        bores.append(cylinder((q[0], q[1], -1.0), (0.0, 0.0, 1.0), depth + 2.0, float(params["support_hole_d"]) / 2))
    for e, s in params["tubes"]:
        pe, ps = (m[:3, :3] @ np.asarray(p, float) + m[:3, 3] for p in (e, s))
        d = ps - pe
        L = float(np.linalg.norm(d))
        d /= L
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

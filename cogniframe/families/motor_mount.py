"""TPU motor mount: a round seat for the motor joined to two sleeves that clip around the arm rods.

Local frame: origin on the motor axis at the arm centreline, z up, the seat's top face at
z = `seat_z` and horizontal; `arm_rods` gives (point, direction) of each arm rod, sloping down
toward the core by `arm_slope_deg`.

Printed upside down, the seat on the bed (z_print = seat_z - z_local). Pieces:
* the seat: a disc `seat_d` across, `wall + 1.5` thick, round the motor's axis: as wide as the
  motor's bell (its base stands inside that footprint) and wide enough to carry every screw head
  with two extrusion lines of TPU outside it (see `seat_diameter`);
* per rod, a clip sleeve (OD = bore + 2 wall) `clip_len` long along the rod (the joints' socket
  depth: the grip a rod gets in any joint), from `clip_start` along it, with a vertical web
  (`skirt` of the sleeve's radius each side) down to the seat plane, so nothing hangs in print (a
  level arm: a D-section sleeve, its flat sides down to the seat). It runs centred on the motor
  axis, moved down-slope where the seat would not leave a full `wall` above the bore. Anything
  above the seat plane is cut flat by the bed;
* a bridge: a plate as thick as the seat, as long as the sleeves, across the arm from one rod's
  axis to the other's, so the seat, bridge and both webs are one flat slab on the bed;
* through holes: each rod's bore (`bore`, full length, so the rod slides through), the motor's
  holes (`holes`: the catalogue pattern across the shaft, turned `pattern_turn` degrees from the
  arm axis, only the pairs that clear the rods; `screw_clearance`), and the centre hole
  `shaft_hole`; under each hole a counterbore (`counterbore_d`) from `grip` below the seat down
  through anything there (a clip sleeve or web), so the screw head bears on flat plate and the
  stock screw engages the motor's thread (`motor_screw`).

The motor mount is symmetric about its arm, so one part serves every corner, turned to the actual
plan direction of each arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..frame import Frame
from ..materials import MIN_THREAD_TURNS, SCREWS
from ..parts.joint_solid import (
    SKIRT,
    STACK_SNAP,
    Built,
    above_bed,
    dsleeve,
    fuse_all,
    prism,
    sloped_sleeve,
    vec,
)
from ..parts.joint_plan import FLIP_X, horizontal, transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement, Vec
from .base import CORNER_ROTATION, FIT_TOL, rot_z, rounded

NAME = "motor_mount"
SIZE_KEY = "motors.model"
DOC = "TPU motor seat clipped around the two arm rods"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_motor_mount(spec, frame),)

def mount_rods(frame: Frame, motor) -> list[tuple[Vec, Vec]]:
    """(point, direction) of a motor's two arm rods, in the frame's axes with the motor axis point
    at the origin: the point is where the rod axis passes nearest to it."""
    axis = np.asarray(motor.axis)
    out = []
    for rn in motor.arm:
        r = frame.rods[rn]
        p = r.start - axis
        d = r.axis
        t = -np.dot(p, d)
        out.append((rounded(p + t * d), rounded(d)))
    return out


def _rods_fit(rods, rotation_deg: float, target) -> float:
    """Worst point + direction error of `rods` turned about z onto `target` (either pairing)."""
    turned = [(rot_z(np.asarray(p, float), rotation_deg), rot_z(np.asarray(d, float), rotation_deg)) for p, d in rods]

    def err(a, b) -> float:
        return float(np.linalg.norm(a[0] - np.asarray(b[0])) + np.linalg.norm(a[1] - np.asarray(b[1])))

    return min(max(err(turned[0], target[0]), err(turned[1], target[1])),
               max(err(turned[0], target[1]), err(turned[1], target[0])))


def _mount_rotation(frame: Frame, m0, m) -> float:
    """The turn about z that puts the fl motor mount on motor `m`'s arm: the corner's rotation when
    it fits (a square box), else the turn between the two arms' plan directions (a rectangle: the
    mount is symmetric about its arm, so the mirrored arm takes the same part turned)."""
    fl, target = mount_rods(frame, m0), mount_rods(frame, m)
    if _rods_fit(fl, CORNER_ROTATION[m.corner], target) <= FIT_TOL:
        return CORNER_ROTATION[m.corner]
    d0, d = frame.rods[m0.arm[0]].axis, frame.rods[m.arm[0]].axis
    deg = round((math.degrees(math.atan2(d[1], d[0]) - math.atan2(d0[1], d0[0])) + 180.0) % 360.0 - 180.0, 9)
    err = _rods_fit(fl, deg, target)
    if err > FIT_TOL:
        raise RuntimeError(f"motor_mount: no turn of the fl mount fits the arm of {m.name} (error {err:.3g} mm)")
    return deg


HOLE_CLEAR = 0.2  # mm: a hole's side, the seat's rim, a bridge's end never within this of a face they could touch flat
HEAD_CLEAR = 0.3  # mm: a screw head's counterbore (and seat) is this much wider than the head, radially


def mount_hole_limits(spec: Spec, bore: float) -> tuple[float, float]:
    """(plan distance a motor hole keeps from a rod's axis so the hole leaves two extrusion lines
    of wall to the bore, plan distance its screw head's seat keeps from it), mm. The head's seat
    is a counterbore up to the plate's underside, cut through any clip sleeve or web below it, so
    the head bears on flat plate; it too leaves two extrusion lines to the bore."""
    screw = SCREWS[spec.motor.screw]
    wall = 2 * spec.printer.nozzle
    return bore / 2 + screw.clearance_d / 2 + wall, screw.head_d / 2 + HEAD_CLEAR + bore / 2 + wall


PATTERN_DIAGONAL = 45.0  # deg from the arm axis: where the authors' motor base carries its four holes


def mount_holes(spec: Spec, rods_local, bore: float) -> tuple[tuple[tuple[float, float], ...], float]:
    """(the motor's holes the mount carries, (x, y) about the motor axis in the mount's local frame;
    the pattern's turn from the arm axis, deg). The catalogue pattern (opposite holes across the
    shaft) at 45 deg to the arm when all four holes clear both rods: there the holes stand
    furthest from the rods, so four fit between the closest rods. Otherwise the pattern turned so
    its first pair lies on the arm axis and its second across it, each pair kept when both its
    holes clear both rods (a hole through a sleeve would make the screw go through the rod).
    Raises the spec's error on frame.arm_spacing when no pair clears (the rods sit where every
    pair's screws would go)."""
    motor = spec.motor
    d0 = np.asarray(rods_local[0][1], float)
    arm = math.degrees(math.atan2(d0[1], d0[0]))
    bore_wall, head = mount_hole_limits(spec, bore)
    need = max(bore_wall, head)

    def clear(xy) -> bool:
        return all(_plan_distance(xy, p, d) >= need - 1e-9 for p, d in rods_local)

    def stored(pts):
        return tuple((round(x, 6) + 0.0, round(y, 6) + 0.0) for x, y in pts)

    diagonal = motor.hole_points(arm + PATTERN_DIAGONAL)
    if all(clear(xy) for xy in diagonal):
        return stored(diagonal), PATTERN_DIAGONAL
    pts = motor.hole_points(arm)
    kept = tuple(xy for i in (0, 2) if clear(pts[i]) and clear(pts[i + 1]) for xy in pts[i:i + 2])
    if not kept:
        half = spec.frame.arm_spacing / 2
        ok = [2 * (r + need) for r in (0.0, motor.holes[1] / 2)]
        raise spec.error("frame.arm_spacing",
                         f"the {motor.name} motor's {motor.pattern} mm {motor.screw} holes (opposite holes across the shaft, "
                         f"{motor.holes[0] / 2:g} mm from it) all fall on the arm rods {2 * half:g} mm apart: every screw would "
                         f"go through a rod's clip sleeve",
                         f"set frame.arm_spacing to at least {min(ok):.1f} (the holes on the arm axis) "
                         f"or choose a motor whose pattern fits between the rods")
    return stored(kept), 0.0


def _plan_distance(xy, point, direction) -> float:
    """Plan (x, y) distance from a vertical line through `xy` to a rod's axis line."""
    d = np.asarray(direction, float)[:2]
    n = float(np.linalg.norm(d))
    d = d / n
    v = np.asarray(xy, float) - np.asarray(point, float)[:2]
    return float(abs(v[0] * d[1] - v[1] * d[0]))


def motor_screw(spec: Spec, plate_t: float) -> tuple[float, float, float]:
    """(stock length, grip under the head, thread engagement) of the motor's mounting screws
    through a seat plate `plate_t` thick: the longest stock length that engages the motor's
    thread by at least MIN_THREAD_TURNS pitches and stays within its thread depth. When every
    stock length is too short through the whole plate, the head sits in a counterbore that leaves
    `grip` of plate under it (the engagement then the middle of the allowed range)."""
    motor = spec.motor
    screw = SCREWS[motor.screw]
    e_min = MIN_THREAD_TURNS * screw.pitch
    depth = motor.thread_depth
    fits = [n for n in screw.lengths if e_min - 1e-9 <= n - plate_t <= depth + 1e-9]
    if fits:
        n = float(max(fits))
        return n, round(plate_t, 4), round(n - plate_t, 4)
    if e_min > depth:
        raise spec.error("motors.thread_depth",
                         f"the {motor.name}'s {depth:g} mm thread is shallower than {MIN_THREAD_TURNS} turns of its "
                         f"{screw.name} screws ({e_min:g} mm): a screw that short strips out",
                         f"measure the motor's thread depth (a screw in by hand until it stops) and give it as "
                         f"motors.thread_depth, at least {e_min:g}")
    shorter = [n for n in screw.lengths if n - plate_t < e_min]
    if not shorter:
        raise spec.error("motors.thread_depth",
                         f"no stock {screw.name} screw ({', '.join(f'{n:g}' for n in screw.lengths)} mm) both clamps the "
                         f"{plate_t:.2f} mm motor seat and engages the {motor.name}'s {depth:g} mm thread by {e_min:g} mm",
                         "give the motor's real thread depth (motors.thread_depth) or change joints.wall")
    n = float(max(shorter))
    e = round((e_min + depth) / 2, 4)
    return n, round(n - e, 4), e


def sleeve_bore(spec: Spec) -> float:
    """The bore of the mount's clip sleeves, mm: the rods slide through them (a through-sleeve,
    `joints.sleeve_clearance`), where a joint's blind socket grips its rod."""
    return spec.sleeve_bore


# The authors' motor base holds each 3 mm rod in a through-sleeve 6.3 mm long
# (Flex_MotorBase_Shorter.stl, CogniFly_v8_Crash_Tests, measured): 2.1 rod diameters.
SLEEVE_DIAMETERS = 2.1


def sleeve_length(rod_d: float) -> float:
    """How long each clip sleeve holds its rod of diameter `rod_d` (the arm rod's, `frame.Rod`), mm:
    the authors' 2.1 rod diameters. A through-sleeve the rod slides in only has to keep the seat
    square to the arm; a blind socket's depth is grip, which this is not."""
    return round(SLEEVE_DIAMETERS * rod_d, 3)


def shaft_hole(spec: Spec, holes, counterbore_d: float) -> float:
    """The centre hole, mm: the motor's shaft boss with 0.5 mm round it, made HOLE_CLEAR smaller
    where its side would touch a screw hole's or a head seat's (the whoop classes' M1.4 holes on a
    6.6 mm circle come to 2.5 mm from the axis, where a 4 mm boss's hole ends: OCC's cut of two
    tangent cylinders left an STL with holes), or HOLE_CLEAR larger when that would not pass the
    boss (the hole then takes in the screw holes' inner sides)."""
    boss = spec.motor.shaft_boss_d
    r = boss / 2 + 0.5
    clear = SCREWS[spec.motor.screw].clearance_d / 2
    touch = [math.hypot(x, y) + sign * hr for x, y in holes for hr in (clear, counterbore_d / 2) for sign in (-1, 1)]
    for t in sorted(touch):
        if abs(r - t) < HOLE_CLEAR:
            r = t - HOLE_CLEAR if t - HOLE_CLEAR >= boss / 2 + 0.1 else t + HOLE_CLEAR
    return round(2 * r, 4)


def _centre_clears_rods(spec: Spec, rods_local, bore: float, centre_d: float) -> None:
    """Raises the spec's error on frame.arm_spacing when the centre hole would open into a rod's
    bore (it keeps two extrusion lines of TPU to it, as the screw holes do): the motor's shaft boss
    would stand against the rod."""
    lines = 2 * spec.printer.nozzle
    need = centre_d / 2 + lines + bore / 2
    near = min(_plan_distance((0.0, 0.0), p, d) for p, d in rods_local)
    if near < need - 1e-6:  # the rods' plan distance carries their stored rounding (1e-6 mm)
        motor = spec.motor
        raise spec.error("frame.arm_spacing",
                         f"the {motor.name} motor's shaft boss ({motor.shaft_boss_d:g} mm) needs a {centre_d:g} mm hole in the "
                         f"motor mount, and the arm rods {spec.frame.arm_spacing:g} mm apart pass through it",
                         f"set frame.arm_spacing to at least {math.ceil(20 * need - 1e-6) / 10:.1f} or choose a smaller motor")


def seat_diameter(spec: Spec, holes, counterbore_d: float) -> float:
    """The least seat that carries the motor, mm: the motor's bell (its base stands inside that
    footprint; the authors' 15 mm seat carries a 14 mm 1104), and every screw head's seat with two
    extrusion lines of TPU outside it."""
    reach = max((math.hypot(x, y) for x, y in holes), default=0.0)
    return max(spec.motor.bell_d, 2 * (reach + counterbore_d / 2 + 2 * spec.printer.nozzle))


@dataclass(frozen=True)
class Layout:
    """Where the seat, sleeves and bridge go (local frame): the seat's diameter, the sleeves' start
    along the rods (from each rod's point nearest the motor axis) and length, each sleeve's web as a
    fraction of its radius, and the bridge's plan interval along the arm."""

    seat_d: float
    clip_start: float
    clip_len: float
    skirts: tuple[float, ...]
    span: tuple[float, float]


def _rod_frame(rods):
    """(arm's plan direction, across it, cos of the arm's slope) of a mount's rods."""
    d = np.asarray(rods[0][1], float)
    d = d / np.linalg.norm(d)
    a_h = horizontal(d)
    return a_h, np.array([-a_h[1], a_h[0], 0.0]), math.sqrt(max(1 - float(d[2]) ** 2, 0.0))


def _span(rods, start: float, length: float) -> tuple[float, float]:
    """The plan interval along the arm a sleeve from `start` to `start + length` along its rod covers
    (the plan positions of its axis's ends)."""
    a_h, _, cos_a = _rod_frame(rods)
    base = float(np.asarray(rods[0][0], float) @ a_h)
    return base + start * cos_a, base + (start + length) * cos_a


def layout(spec: Spec, rods, holes, seat_z: float, counterbore_d: float, centre_d: float, rod_d: float) -> Layout:
    """The mount's seat and sleeves for `holes` on `rods` (local frame; `rod_d` their diameter). The seat and the sleeves
    start at their least sizes (`seat_diameter`, `sleeve_length`) and grow by 0.1 mm steps until no
    face of one stands within HOLE_CLEAR of touching another flat (OCC's boolean breaks on a
    cylinder tangent to a plane): the seat's rim and the bridge's ends, the sleeves' sides and the
    webs' faces; the bridge's ends and the holes, the heads' seats and the shaft hole."""
    bore = sleeve_bore(spec)
    wall = spec.joints.wall
    r = bore / 2 + wall
    rods = [(np.asarray(p, float), np.asarray(d, float) / np.linalg.norm(d)) for p, d in rods]
    a_h, lat, cos_a = _rod_frame(rods)
    dz = float(rods[0][1][2])
    flat = abs(dz) <= 1e-9
    bolts = [np.array([x, y, 0.0]) for x, y in holes]
    cuts = [(c, float(SCREWS[spec.motor.screw].clearance_d) / 2) for c in bolts] + [(np.zeros(3), centre_d / 2)]
    skirts = tuple(1.0 if flat else _skirt(r, p, d, cuts + [(c, counterbore_d / 2) for c in bolts]) for p, d in rods)
    along = [(float(c @ a_h), hr) for c, hr in cuts + [(c, counterbore_d / 2) for c in bolts]]
    sides = [abs(float(p @ lat)) + sign * f * r for p, _ in rods for f in (*skirts, 1.0) for sign in (-1, 1)]
    # the up-slope limit: where the seat still leaves a full wall above the bore
    rb = bore / 2 / max(cos_a, 1e-6)
    limit = None if flat else (seat_z - wall - rb - float(rods[0][0][2])) / dz
    d0, l0 = seat_diameter(spec, holes, counterbore_d), sleeve_length(rod_d)

    def place(length: float) -> float:
        start = -length / 2
        if limit is not None:
            start = max(start, limit) if dz < 0 else min(start, limit - length)
        return round(start, 6) + 0.0

    def clear(seat_r: float, span) -> bool:
        ends_ok = all(abs(abs(e - a) - hr) >= HOLE_CLEAR and abs(abs(e) - seat_r) >= HOLE_CLEAR
                      for e in span for a, hr in along)
        return ends_ok and all(abs(seat_r - v) >= HOLE_CLEAR for v in sides)

    for i in range(40):
        seat_d = round(d0 + 0.1 * i, 4)
        for j in range(40):
            length = round(l0 + 0.1 * j, 4)
            start = place(length)
            span = _span(rods, start, length)
            if clear(seat_d / 2, span):
                return Layout(seat_d, start, length, skirts, span)
    start = place(l0)
    return Layout(round(d0, 4), start, round(l0, 4), skirts, _span(rods, start, l0))


def _disc_strip(radius: float, x0: float, x1: float, c: float) -> float:
    """Area of the disc of `radius` about the origin inside x0 <= x <= x1, |y| <= c (mm^2)."""

    def chord(x: float) -> float:  # integral of sqrt(R^2 - x^2) from 0 to x
        return (x * math.sqrt(max(radius * radius - x * x, 0.0)) + radius * radius * math.asin(x / radius)) / 2

    def g(x: float) -> float:  # integral of min(c, sqrt(R^2 - x^2)) from 0 to x, odd in x
        x = max(-radius, min(radius, x))
        sign, x = (1.0, x) if x >= 0 else (-1.0, -x)
        if c >= radius:
            return sign * chord(x)
        xc = math.sqrt(radius * radius - c * c)
        return sign * (c * x if x <= xc else c * xc + chord(x) - chord(xc))

    return 2 * (g(x1) - g(x0))


def _estimate(spec: Spec, rods, lay: Layout, seat_z: float, plate_t: float, holes, grip: float,
              counterbore_d: float, centre_d: float) -> Estimate:
    """Closed form: the flat slab (seat disc, bridge, and the webs' feet in the plate's layer), the
    sleeves (annulus x length) and the webs between them and the slab, less the holes and the
    counterbores inside the plate."""
    bore = sleeve_bore(spec)
    r = bore / 2 + spec.joints.wall
    rods = [(np.asarray(p, float), np.asarray(d, float) / np.linalg.norm(d)) for p, d in rods]
    _, lat, cos_a = _rod_frame(rods)
    seat_r = lay.seat_d / 2
    e0, e1 = lay.span
    half = max(abs(float(p @ lat)) for p, _ in rods)
    w = max(lay.skirts) * r
    slab = math.pi * seat_r**2 + (e1 - e0) * 2 * (half + w) - _disc_strip(seat_r, e0, e1, half + w)
    vol = slab * plate_t
    sleeves_v = 0.0
    for (p, d), f in zip(rods, lay.skirts):
        w = f * r
        z_mid = float(p[2] + d[2] * (lay.clip_start + lay.clip_len / 2))
        depth = seat_z - z_mid - plate_t  # from the sleeve's axis up to the slab's underside
        upper = _disc_strip(r, -w, w, r) / 2  # the sleeve's upper half inside the web
        sleeves_v += math.pi * (r * r - bore * bore / 4) * lay.clip_len
        sleeves_v += max(2 * w * depth * lay.clip_len * cos_a - upper * lay.clip_len, 0.0)
        # Close rods (thick walls): each level of a sleeve and its web is one span centred on its
        # rod, so the two overlap by twice what one reaches past the arm's centre line.
        c = abs(float(p @ lat))
        past = 0.0
        if c < r:
            past += r * r * math.acos(c / r) - c * math.sqrt(r * r - c * c)
        if c < w:
            past += (w - c) * depth - _disc_strip(r, c, min(w, r), depth) / 2
        sleeves_v -= past * lay.clip_len
    vol += sleeves_v
    screw = SCREWS[spec.motor.screw]
    n = len(holes)
    vol -= (n * screw.clearance_d**2 + centre_d**2) * math.pi / 4 * plate_t
    vol -= n * math.pi / 4 * (counterbore_d**2 - screw.clearance_d**2) * (plate_t - grip)
    length = max(lay.seat_d, e1 - e0 + 2 * r)
    wide = max(lay.seat_d, 2 * (half + r))
    area_v = (math.pi * lay.seat_d + 2 * (e1 - e0)) * plate_t + 2 * (2 * math.pi * r + 2 * (seat_z - plate_t)) * lay.clip_len
    return Estimate(vol, 2 * slab, area_v, (length, wide, seat_z + r))


def _motor_mount(spec: Spec, frame: Frame) -> PartSpec:
    m0 = frame.motors[0]
    motor = spec.motor
    axis = np.asarray(m0.axis)
    # Rod axis points through the mount's local origin (the motor axis on the arm centreline).
    rods_local = mount_rods(frame, m0)
    screw = SCREWS[motor.screw]
    bore = sleeve_bore(spec)
    holes, turn = mount_holes(spec, rods_local, bore)
    seat_z = round(m0.seat_z - axis[2], 4)
    plate_t = min(spec.joints.wall + 1.5, seat_z)
    length, grip, engagement = motor_screw(spec, plate_t)
    counterbore_d = round(screw.head_d + 2 * HEAD_CLEAR, 4)
    centre = shaft_hole(spec, holes, counterbore_d)
    _centre_clears_rods(spec, rods_local, bore, centre)
    lay = layout(spec, rods_local, holes, seat_z, counterbore_d, centre, frame.rods[m0.arm[0]].diameter)
    est = _estimate(spec, rods_local, lay, seat_z, plate_t, holes, grip, counterbore_d, centre)
    placements = tuple(Placement(m.name, _mount_rotation(frame, m0, m), rounded(m.axis)) for m in frame.motors)
    params = (("holes", holes), ("pattern", motor.holes), ("pattern_turn", turn), ("screw", screw.name),
              ("screw_clearance", screw.clearance_d), ("screw_length", length), ("grip", grip), ("engagement", engagement),
              ("counterbore_d", counterbore_d), ("shaft_hole", centre), ("bell_d", motor.bell_d), ("seat_z", seat_z),
              ("arm_rods", tuple(rods_local)), ("arm_slope_deg", round(m0.arm_slope_deg, 4)),
              ("seat_d", lay.seat_d), ("clip_start", lay.clip_start), ("clip_len", lay.clip_len),
              ("skirt", tuple(round(f, 4) for f in lay.skirts)), ("bore", round(bore, 4)))
    hw = (HardwareLine(f"{screw.name} x {length:g} socket-head screw (motor to mount)", len(holes), screw.mass_of(length)),)
    return PartSpec("motor_mount", "motor_mount", "exoskeleton", spec.joints.material, 1.0, placements, (), spec.joints.wall,
                    est, params, hw)



# -- the assembly's words ------------------------------------------------------------------

def fitting(spec: Spec) -> str:
    """How the builder fits the motor mounts on the arms."""
    return ("Thread a motor mount onto each pair of arm rods: its sleeves are closed, so slide both rods through them "
            f"(the two rods of one arm run parallel, {spec.frame.arm_spacing:g} mm apart) before the arm goes in, and screw "
            "its motor on now, while the mount's underside is free: {screws}. Then push both arm rods into the knee's arm "
            f"sockets and slide the mount to {spec.motors.radius:g} mm from the frame centre. Leave the inner ends free.")


def screw_words(mount: PartSpec | None) -> str:
    """The motor screws as the builder needs them: how many, which, into what and how deep."""
    if mount is None or "holes" not in dict(mount.params):
        return "the screws that come with the motors, no longer than the seat plus the motor's thread"
    n = len(mount.param("holes"))
    which = "the pair of opposite holes on the arm's axis" if n == 2 else "all four holes"
    return (f"{n} {mount.param('screw')} x {mount.param('screw_length'):g} screws per motor, up through {which} "
            f"into the motor's thread ({mount.param('engagement'):g} mm deep; a longer screw reaches the windings)")


# -- the solid --------------------------------------------------------------------------------

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


def solid(part: PartSpec) -> Built:
    import cadquery as cq

    m = print_from_local(part)
    rot, shift = m[:3, :3], m[:3, 3]
    seat_z = float(part.param("seat_z"))
    bore = float(part.param("bore"))
    wall = part.wall
    r = bore / 2 + wall
    plate_t = min(wall + 1.5, seat_z)
    rods = [(np.asarray(p, float), np.asarray(d, float) / np.linalg.norm(d)) for p, d in part.param("arm_rods")]
    clips = _parallel(rods)
    a_h, lat, _ = _rod_frame(rods)
    start, length = float(part.param("clip_start")), float(part.param("clip_len"))
    e0, e1 = _span(rods, start, length)

    def to_print(p):
        return rot @ p + shift

    seat_r = float(part.param("seat_d")) / 2
    centre = to_print(np.zeros(3))
    pieces = [cq.Solid.makeCylinder(seat_r, plate_t, cq.Vector(centre[0], centre[1], 0.0), cq.Vector(0, 0, 1))]
    across = sorted(float(p @ lat) for p, _ in rods)
    bridge = [to_print(a_h * e + lat * y)[:2] for e, y in ((e0, across[0]), (e1, across[0]), (e1, across[1]), (e0, across[1]))]
    pieces.append(prism(bridge, 0.0, plate_t))
    cutters = []
    hole_r = float(part.param("screw_clearance")) / 2
    bolts = [np.array([x, y, 0.0]) for x, y in part.param("holes")]
    cb_r = float(part.param("counterbore_d")) / 2
    holes = [(c, hole_r) for c in bolts] + [(np.zeros(3), float(part.param("shaft_hole")) / 2)]
    grip = float(part.param("grip"))
    for (p, d), (pc, dc), skirt in zip(rods, clips, part.param("skirt")):
        s0, dp = to_print(pc + dc * start), rot @ dc
        if dp[2] < 0:  # build the sleeve rising in print
            s0, dp = to_print(pc + dc * (start + length)), -dp
        if abs(dp[2]) > 1e-9:
            pieces.append(sloped_sleeve(s0, dp, length, r, skirt=float(skirt)))
        else:
            # A level arm (frame.knee_height puts the knee level with the core link): a D-section
            # sleeve from the bed, as the joints' level sockets. A bare cylinder stood 0.5 mm
            # above the seat plate there (bamboo, frame.knee_height 0.38), and the mount printed
            # in three pieces.
            pieces.append(dsleeve(s0, dp, length, float(s0[2]), r))
        through = 4 * (length + 2 * seat_r)
        cutters.append(cq.Solid.makeCylinder(bore / 2, 2 * through, vec(to_print(p - d * through)), vec(rot @ d)))
    body = above_bed(fuse_all(pieces))
    for c3, hr in holes:
        c = to_print(c3)
        cutters.append(cq.Solid.makeCylinder(hr, 200.0, cq.Vector(c[0], c[1], -1.0), cq.Vector(0, 0, 1)))
    for c3 in bolts:  # the heads' seats: up from `grip` as printed (down from the plate in the air)
        c = to_print(c3)
        cutters.append(cq.Solid.makeCylinder(cb_r, 200.0, cq.Vector(c[0], c[1], grip), cq.Vector(0, 0, 1)))
    shape = body.cut(fuse_all(cutters)).clean()
    solids = shape.Solids()
    if len(solids) != 1:
        raise RuntimeError(f"motor mount geometry produced {len(solids)} solids instead of 1")
    return Built(solids[0], m)

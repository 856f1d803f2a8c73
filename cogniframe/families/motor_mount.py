"""TPU motor mount: a flat seat for the motor that clips around the two arm rods.

Local frame: origin on the motor axis at the arm centreline, z up, the seat's top face at
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
  motor's thread (`motor_screw`).

The motor mount is symmetric about its arm, so one part serves every corner, turned to the actual
plan direction of each arm.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import Frame
from ..materials import MIN_THREAD_TURNS, SCREWS
from ..parts.joint import (
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
from ..spec import Spec
from .base import CORNER_ROTATION, FIT_TOL, Estimate, HardwareLine, PartSpec, Placement, Vec, rot_z, rounded

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


MOUNT_CLEAR = 0.2  # mm: the motor seat's sides stand this far outside its clip sleeves
HEAD_CLEAR = 0.3  # mm: a screw head's counterbore (and seat) is this much wider than the head, radially


def mount_hole_limits(spec: Spec, bore: float) -> tuple[float, float]:
    """(plan distance a motor hole keeps from a rod's axis so the hole leaves two extrusion lines
    of wall to the bore, plan distance its screw head's seat keeps from it), mm. The head's seat
    is a counterbore up to the plate's underside, cut through any clip sleeve or web below it, so
    the head bears on flat plate; it too leaves two extrusion lines to the bore."""
    screw = SCREWS[spec.motor.screw]
    wall = 2 * spec.printer.nozzle
    return bore / 2 + screw.clearance_d / 2 + wall, screw.head_d / 2 + HEAD_CLEAR + bore / 2 + wall


def mount_holes(spec: Spec, rods_local, bore: float) -> tuple[tuple[float, float], ...]:
    """The motor's holes the mount carries, (x, y) about the motor axis in the mount's local frame:
    the catalogue pattern (opposite holes across the shaft) turned so its first pair lies on the
    arm axis and its second pair across it, each pair kept when both its holes clear both rods
    (a hole through a sleeve would make the screw go through the rod). Raises the spec's error
    on frame.arm_spacing when no pair clears (the rods sit where every pair's screws would go)."""
    motor = spec.motor
    d0 = np.asarray(rods_local[0][1], float)
    turn = math.degrees(math.atan2(d0[1], d0[0]))
    pts = motor.hole_points(turn)
    bore_wall, head = mount_hole_limits(spec, bore)
    need = max(bore_wall, head)

    def clear(xy) -> bool:
        return all(_plan_distance(xy, p, d) >= need - 1e-9 for p, d in rods_local)

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
    return tuple((round(x, 6) + 0.0, round(y, 6) + 0.0) for x, y in kept)


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


def _motor_mount(spec: Spec, frame: Frame) -> PartSpec:
    m0 = frame.motors[0]
    motor = spec.motor
    axis = np.asarray(m0.axis)
    # Rod axis points through the mount's local origin (the motor axis on the arm centreline).
    rods_local = mount_rods(frame, m0)
    screw = SCREWS[motor.screw]
    holes = mount_holes(spec, rods_local, spec.bore)  # the bore the mount's sleeves are cut to (its `bore` param)
    reach = max(motor.holes) / 2
    # The seat carries the bell, reaches MOUNT_CLEAR past the arm pair's clips (flush with them, its
    # sides were tangent to the clip sleeves: 1 mm rods 26.4 mm apart gave a 1e-9 mm^2 sliver face and
    # an STL with a hole) and holds the motor's holes with a wall outside each (holes near its edge cut
    # its corners off: a 20 mm pattern).
    width = max(motor.bell_d + 4.0, spec.frame.arm_spacing + spec.bore + 2 * spec.joints.wall + 2 * MOUNT_CLEAR,
                2 * reach + screw.clearance_d + 2 * spec.joints.wall)
    seat_z = round(m0.seat_z - axis[2], 4)
    thick = spec.joints.wall + 1.5
    plate_t = min(thick, seat_z)
    length, grip, engagement = motor_screw(spec, plate_t)
    clip_len = width
    od = spec.bore + 2 * spec.joints.wall
    vol = width * width * thick + 2 * (math.pi / 4 * (od**2 - spec.bore**2) * clip_len)
    vol -= len(holes) * math.pi / 4 * screw.clearance_d**2 * thick + math.pi / 4 * (motor.shaft_boss_d + 1) ** 2 * thick
    vol -= len(holes) * math.pi / 4 * ((screw.head_d + 2 * HEAD_CLEAR) ** 2 - screw.clearance_d**2) * (plate_t - grip)
    est = Estimate(vol, 2 * width * width, 4 * width * thick + 2 * math.pi * od * clip_len, (width, width, thick + od))
    placements = tuple(Placement(m.name, _mount_rotation(frame, m0, m), rounded(m.axis)) for m in frame.motors)
    params = (("holes", holes), ("pattern", motor.holes), ("screw", screw.name), ("screw_clearance", screw.clearance_d),
              ("screw_length", length), ("grip", grip), ("engagement", engagement),
              ("counterbore_d", round(screw.head_d + 2 * HEAD_CLEAR, 4)),
              ("shaft_hole", motor.shaft_boss_d + 1.0), ("bell_d", motor.bell_d), ("seat_z", seat_z),
              ("arm_rods", tuple(rods_local)), ("arm_slope_deg", round(m0.arm_slope_deg, 4)), ("width", width),
              ("bore", round(spec.bore, 4)))
    hw = (HardwareLine(f"{screw.name} x {length:g} socket-head screw (motor to mount)", len(holes), screw.mass_of(length)),)
    return PartSpec("motor_mount", "motor_mount", "exoskeleton", spec.joints.material, 1.0, placements, (), spec.joints.wall,
                    est, params, hw)



# -- the assembly's words ------------------------------------------------------------------

def fitting(spec: Spec) -> str:
    """How the builder fits the motor mounts on the arms."""
    return ("Clip a motor mount onto each pair of arm rods (the two rods of one arm run parallel, "
            f"{spec.frame.arm_spacing:g} mm apart), then push both arm rods into the knee's arm sockets. Slide the mount "
            f"to {spec.motors.radius:g} mm from the frame centre. Leave the inner ends free.")


def screw_words(mount: PartSpec | None) -> str:
    """The motor screws as the builder needs them: how many, which, into what and how deep."""
    if mount is None or "holes" not in dict(mount.params):
        return "the screws that come with the motors, no longer than the seat plus the motor's thread"
    n = len(mount.param("holes"))
    which = "the pair of opposite holes on the arm's axis" if n == 2 else "all four holes"
    return (f"{n} {mount.param('screw')} x {mount.param('screw_length'):g} screws per motor, up through {which} "
            f"into the motor's thread ({mount.param('engagement'):g} mm deep; a longer screw reaches the windings)")


# -- the solid --------------------------------------------------------------------------------

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


def solid(part: PartSpec) -> Built:
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

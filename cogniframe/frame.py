"""Stage 2: Spec -> Frame, the graph every later stage derives from (pure numpy, no CAD).

Axes: x to the right, y to the front, z up; the ground plane is z = 0 (the underside of the
bottom corner joints, which are the feet). Corners: fl = (-x, +y), fr = (+x, +y),
rr = (+x, -y), rl = (-x, -y).

Layout (the paper's CogniFly): a square rod ring on top and one at the bottom
(`rod_cage_top_front` ...); at each corner an upper and a lower leg rod bow inwards to a
knee (`knee_fl`), giving the hourglass side; from each knee a pair of parallel arm rods
(`rod_arm_fl_1/2`) runs diagonally in to a TPU link on the core (`core_link_fl`) and carries a
motor mount; a damping strut (`rod_strut_fl`) runs from each bottom corner to the same core link.
With `frame.level_arms` (the authors' build) the core plate hangs at the knees' height on
standoffs above the battery holder, so the arms run level; without it the plate sits on the holder
and the arms climb to the knees.

A rod end sits at `seat` mm from its joint centre (the socket bottom) and goes `depth` mm into
the socket, so cut length = centre distance - seat_a - seat_b.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .materials import SCREWS, STACK_PATTERNS
from .spec import Spec

CORNERS = ("fl", "fr", "rr", "rl")
# The slot each side of a knee's living hinge (two 0.4 mm lines wide), mm: the knee CAD cuts it,
# and the seat rule below keeps the hinge web clear of it.
HINGE_GAP = 0.8
# Sign of x and y for each corner.
CORNER_SIGN = {"fl": (-1, 1), "fr": (1, 1), "rr": (1, -1), "rl": (-1, -1)}
# Ring sides: (name, from corner, to corner), going clockwise seen from above.
SIDES = (("front", "fl", "fr"), ("right", "fr", "rr"), ("rear", "rr", "rl"), ("left", "rl", "fl"))

Vec = tuple[float, float, float]


def _t(v) -> Vec:
    return (float(v[0]), float(v[1]), float(v[2]))


@dataclass(frozen=True)
class RodEnd:
    """One end of a rod: the joint it enters and where the socket is (mm)."""

    node: str
    port: Vec  # point on the rod axis level with the joint centre (node position + lateral offset; a pegged
              # link's strut: `pegged_strut_port`)
    seat: float  # distance from port to the rod end (socket bottom), mm
    depth: float  # how far the rod goes into the socket, mm


@dataclass(frozen=True)
class Rod:
    name: str
    role: str  # "cage" | "leg" | "arm" | "strut"
    a: RodEnd
    b: RodEnd
    diameter: float
    material: str

    def __post_init__(self) -> None:
        # the axis and the port distance, computed once (read by every later stage, many times):
        # not fields, so equality, hashing and repr are the dataclass's own
        d = np.subtract(self.b.port, self.a.port)
        dist = np.linalg.norm(d)
        axis = d / dist
        axis.flags.writeable = False  # shared by every caller
        object.__setattr__(self, "_axis", axis)
        object.__setattr__(self, "_centre_distance", float(dist))
        start = np.asarray(self.a.port) + axis * self.a.seat
        end = np.asarray(self.b.port) - axis * self.b.seat
        start.flags.writeable = end.flags.writeable = False
        object.__setattr__(self, "_start", start)
        object.__setattr__(self, "_end", end)

    @property
    def axis(self) -> np.ndarray:
        """Unit vector from end a to end b (read-only)."""
        return self._axis

    @property
    def centre_distance(self) -> float:
        return self._centre_distance

    @property
    def length(self) -> float:
        """Exact rod length between the two socket bottoms, mm."""
        return self.centre_distance - self.a.seat - self.b.seat

    @property
    def cut_length(self) -> float:
        """Length to cut, rounded to 0.5 mm, mm."""
        return round(self.length * 2) / 2

    @property
    def start(self) -> np.ndarray:
        """The rod's end in the socket of end a (read-only)."""
        return self._start

    @property
    def end(self) -> np.ndarray:
        return self._end

    def socket_direction(self, node: str) -> np.ndarray:
        """Unit vector pointing from `node` along this rod (out of the socket)."""
        return self.axis if node == self.a.node else -self.axis

    def end_at(self, node: str) -> RodEnd:
        return self.a if node == self.a.node else self.b


@dataclass(frozen=True)
class Node:
    name: str
    kind: str  # "corner_top" | "corner_bottom" | "knee" | "core_link"
    pos: Vec
    rods: tuple[str, ...]
    seat: float  # socket-bottom distance used by every rod at this joint, mm


@dataclass(frozen=True)
class Motor:
    name: str  # motor_fl
    corner: str
    arm: tuple[str, str]  # the two arm rods the mount clips onto
    axis: Vec  # motor axis point on the arm centreline (between the two rods), mm
    seat_z: float  # z of the mount's top face, where the motor sits, mm
    prop_z: float  # z of the propeller plane, mm
    arm_slope_deg: float  # how steeply the arm descends toward the core


@dataclass(frozen=True)
class Box:
    """Axis-aligned box: centre and full size (mm)."""

    name: str
    centre: Vec
    size: Vec

    @property
    def lo(self) -> np.ndarray:
        return np.asarray(self.centre) - np.asarray(self.size) / 2

    @property
    def hi(self) -> np.ndarray:
        return np.asarray(self.centre) + np.asarray(self.size) / 2


@dataclass(frozen=True)
class Core:
    plate: Box
    holder: Box  # battery holder outline (open at the front for sliding the pack)
    battery: Box
    stack: Box  # flight controller + ESC stack volume
    computer: Box | None
    spacer: Box | None = None  # sensor mount / spacer between holder and plate (the plate square only)
    flow_sensor: Box | None = None  # downward optical-flow + ToF board (under the sensor mount's rear pad)
    camera: Box | None = None  # camera board + lens, on the camera mount's upright (untilted envelope)
    camera_base: Box | None = None  # the camera mount's base plate, under the FC stack
    mouth: float = 0.0  # holder length in front of the pack (strap slots), mm
    hang: float = 0.0  # standoffs between the holder (or spacer) top and the plate's underside, mm

    @property
    def boxes(self) -> tuple[Box, ...]:
        return tuple(b for b in (self.plate, self.holder, self.stack, self.computer, self.spacer, self.flow_sensor,
                                 self.camera) if b is not None)


@dataclass(frozen=True)
class PropClearance:
    motor: str
    to_cage_mm: float  # nearest rod of the cage, legs or struts (surface to the propeller disc)
    to_core_mm: float  # nearest core box
    to_neighbour_mm: float  # gap between this disc and the nearest other disc, in plan


@dataclass(frozen=True)
class Frame:
    nodes: dict[str, Node]
    rods: dict[str, Rod]
    motors: tuple[Motor, ...]
    core: Core
    ground_z: float
    prop_clearances: tuple[PropClearance, ...] = field(default=())

    @property
    def clearance_mm(self) -> float:
        """Battery-holder underside above the ground plane: the payload travel on impact, mm."""
        return float(self.core.holder.lo[2] - self.ground_z)

    @property
    def min_prop_margin(self) -> float:
        return min(min(p.to_cage_mm, p.to_core_mm, p.to_neighbour_mm) for p in self.prop_clearances)

    def rods_of(self, role: str) -> list[Rod]:
        return [r for r in self.rods.values() if r.role == role]

    def bbox(self) -> tuple[np.ndarray, np.ndarray]:
        pts = np.array([n.pos for n in self.nodes.values()])
        return pts.min(axis=0), pts.max(axis=0)


# -- construction ----------------------------------------------------------------------------

def frame_of(spec: Spec) -> Frame:
    """Derive the frame graph from a validated spec. Raises UserError if the props do not clear."""
    f, j, c = spec.frame, spec.joints, spec.core
    d, bore = spec.rods.diameter, spec.bore
    inset = bore / 2 + j.wall  # joint outer wall flush with the box outside
    hx, hy = f.width / 2 - inset, f.depth / 2 - inset
    z_top, z_bot = f.height - inset, inset
    core = _core(spec)
    z_link = core.plate.centre[2] - peg_drop(spec)
    z_knee = z_link if f.level_arms else f.height * f.knee_height
    a_link = c.plate_size / 2 + inset  # link socket centre just outside the plate corner

    pos: dict[str, tuple[str, np.ndarray]] = {}
    for k, (sx, sy) in CORNER_SIGN.items():
        pos[f"corner_top_{k}"] = ("corner_top", np.array([sx * hx, sy * hy, z_top]))
        pos[f"corner_bottom_{k}"] = ("corner_bottom", np.array([sx * hx, sy * hy, z_bot]))
        link = np.array([sx * a_link, sy * a_link, z_link])
        pos[f"knee_{k}"] = ("knee", np.append(_knee_xy(np.array([sx * hx, sy * hy]), link[:2], f.knee_inset), z_knee))
        pos[f"core_link_{k}"] = ("core_link", link)

    # (name, role, node a, node b, lateral offset vector applied to both ports)
    edges: list[tuple[str, str, str, str, np.ndarray]] = []
    zero = np.zeros(3)
    for level in ("top", "bottom"):
        for side, ka, kb in SIDES:
            edges.append((f"rod_cage_{level}_{side}", "cage", f"corner_{level}_{ka}", f"corner_{level}_{kb}", zero))
    for k in CORNERS:
        edges.append((f"rod_leg_upper_{k}", "leg", f"corner_top_{k}", f"knee_{k}", zero))
        edges.append((f"rod_leg_lower_{k}", "leg", f"knee_{k}", f"corner_bottom_{k}", zero))
        lateral = _arm_lateral(pos[f"knee_{k}"][1], pos[f"core_link_{k}"][1])
        for i, s in ((1, 0.5), (2, -0.5)):
            edges.append((f"rod_arm_{k}_{i}", "arm", f"knee_{k}", f"core_link_{k}", lateral * s * f.arm_spacing))
        if f.struts:
            edges.append((f"rod_strut_{k}", "strut", f"corner_bottom_{k}", f"core_link_{k}", zero))

    incident: dict[str, list[int]] = {n: [] for n in pos}
    for i, e in enumerate(edges):
        incident[e[2]].append(i)
        incident[e[3]].append(i)

    seats = {n: _node_seat(n, pos, edges, incident[n], spec) for n in pos}
    nodes = {n: Node(n, kind, _t(p), tuple(edges[i][0] for i in incident[n]), seats[n]) for n, (kind, p) in pos.items()}
    # a pegged link takes the strut on its arch (`pegged_strut_port`): that end's port moves
    ports = {}
    if c.link == "pegs" and f.struts:
        for k in CORNERS:
            ln = f"core_link_{k}"
            ports[(f"rod_strut_{k}", ln)] = pegged_strut_port(pos[ln][1], pos[f"knee_{k}"][1], pos[f"corner_bottom_{k}"][1],
                                                              seats[ln], j.socket_depth, bore)
    rods = {}
    for name, role, na, nb, off in edges:
        ea = RodEnd(na, _t(ports.get((name, na), pos[na][1] + off)), seats[na], j.socket_depth)
        eb = RodEnd(nb, _t(ports.get((name, nb), pos[nb][1] + off)), seats[nb], j.socket_depth)
        rods[name] = Rod(name, role, ea, eb, d, spec.rods.material)

    for r in rods.values():
        if r.length < 2 * j.socket_depth + 5:
            deepest = (r.length - 5) / 2
            has = f"would be only {r.length:.1f} mm long" if r.length > 0 else "has no room at all between its joints"
            fix = (f"make joints.socket_depth at most {deepest:.1f}, or enlarge frame.width/frame.depth/frame.height"
                   if deepest >= 2 * spec.rods.diameter else
                   "enlarge frame.width/frame.depth/frame.height or reduce frame.knee_inset: this frame is too small "
                   f"for {spec.rods.diameter:g} mm rods in sockets at least two diameters deep")
            raise spec.error("joints.socket_depth", f"the {r.name} rod {has}, too short to sit in two "
                             f"{j.socket_depth:g} mm sockets", fix)

    motors = tuple(_motor(k, rods, spec) for k in CORNERS)
    frame = Frame(nodes, rods, motors, core, ground_z=0.0)
    clear = prop_clearances(frame, spec)
    frame = Frame(nodes, rods, motors, core, 0.0, clear)
    worst = min(clear, key=lambda p: min(p.to_cage_mm, p.to_core_mm, p.to_neighbour_mm))
    if frame.min_prop_margin < 0:
        raise spec.error(
            "motors.prop_diameter",
            f"the {spec.motors.prop_diameter:g} mm propeller of {worst.motor} hits the frame "
            f"(margin to cage {worst.to_cage_mm:.1f} mm, to core {worst.to_core_mm:.1f} mm, to the next propeller "
            f"{worst.to_neighbour_mm:.1f} mm)", "use a smaller motors.prop_diameter, change motors.radius, "
            "or make frame.width/frame.depth larger")
    if core.stack.hi[2] >= z_top - inset or (core.computer and core.computer.hi[2] >= z_top - inset):
        raise spec.error(
            "frame.height",
            f"the electronics on the core reach z = {max(b.hi[2] for b in core.boxes):.0f} mm, above the "
            f"top ring at {z_top:.0f} mm", "increase frame.height or lower core.battery_clearance")
    return frame


def _knee_xy(corner: np.ndarray, link: np.ndarray, inset: float) -> np.ndarray:
    """Plan position of a knee: `inset` in along x and y from its corner in a square box (on the
    corner's 45 deg diagonal, towards the core link). In a rectangle the corner's core link is off
    that diagonal, so the knee moves the same distance (inset x sqrt 2) straight towards the core
    link: the corner, its legs, the knee, the arm and the strut then stay in one vertical plane,
    as in a square, and every joint still prints flat with its sockets in that plane."""
    d = link - corner
    if abs(d[0]) == abs(d[1]):  # on the diagonal: the exact square-box numbers
        return np.array([corner[0] + np.sign(d[0]) * inset, corner[1] + np.sign(d[1]) * inset])
    return corner + d / math.hypot(d[0], d[1]) * (inset * math.sqrt(2))


def _arm_lateral(knee: np.ndarray, link: np.ndarray) -> np.ndarray:
    """Unit vector across an arm pair: horizontal and perpendicular to the arm in plan (knee to
    core link), so the two rods lie `arm_spacing` apart whatever the box's aspect ratio. Its sign
    is the old diagonal convention's: (-sy, sx) / sqrt 2 for a corner on the 45 deg diagonal
    (every square box, where the arm runs along the diagonal; those numbers are kept exactly)."""
    d = link[:2] - knee[:2]  # inwards, in plan
    if abs(d[0]) == abs(d[1]):  # on the diagonal: the exact constant
        return np.array([np.sign(d[1]), -np.sign(d[0]), 0.0]) / math.sqrt(2)
    return np.array([d[1], -d[0], 0.0]) / math.hypot(d[0], d[1])


def _node_seat(n: str, pos, edges, inc: list[int], spec: Spec) -> float:
    """Socket-bottom distance at a joint: the spec's seat, raised so no two bores meet, and at a
    knee so that its living hinge has room (`_hinge_seat`)."""
    j = spec.joints
    dirs, ports = [], []
    p0 = pos[n][1]
    for i in inc:
        _, _, na, nb, off = edges[i]
        other = pos[nb][1] if na == n else pos[na][1]
        v = other - p0
        dirs.append(v / np.linalg.norm(v))
        ports.append(p0 + off)
    need = j.seat
    r = spec.bore / 2 + j.wall / 2
    for i in range(len(dirs)):
        for k in range(i + 1, len(dirs)):
            if np.linalg.norm(ports[i] - ports[k]) >= spec.bore + 2 * j.wall:
                continue  # parallel arm rods: separate sockets side by side
            cosang = float(np.clip(np.dot(dirs[i], dirs[k]), -1, 1))
            half = math.acos(cosang) / 2
            if half > 1e-6:
                need = max(need, r / math.tan(half))
    if pos[n][0] == "knee":
        need = max(need, _hinge_seat(dirs, [edges[i][1] for i in inc], j.wall))
    return math.ceil(need * 100 - 1e-6) / 100  # up to 0.01 mm: rounded down, two bores could meet


def _hinge_seat(dirs: list[np.ndarray], roles: list[str], wall: float) -> float:
    """The least seat at a knee that leaves its living hinge room. The knee's arm block and the
    hinged leg's sleeve (the leg at the larger angle to the arms, parts/joint_solid.py) both start at
    seat - wall from the knee centre, and the leg is freed from the block by a `HINGE_GAP` slot;
    the hinge web runs from the centre of the leg's back face to the block's back face. That
    centre lies (seat - wall) (1 - cos angle) behind the block's back face: it must clear the
    slot and as much again, or the slot cuts off the end of the leg the web holds and the knee
    prints in two pieces (the seat at its minimum, or walls thick for the seat: joints.seat 0,
    or joints.wall 2.9 mm with the presets' 3 mm seat). The presets need 2.3 mm."""
    arm = next(d for d, role in zip(dirs, roles) if role == "arm")
    legs = [float(d @ arm) for d, role in zip(dirs, roles) if role == "leg"]
    if not legs:
        return 0.0
    return wall + 2 * HINGE_GAP / max(1.0 - min(legs), 1e-6)


# The pegged core link (core.link: pegs) presses each peg into an ABS tube on the core plate:
# the peg's diameter is the tube's bore, the authors' MainBase peg bore (6.8 mm; their connector's
# peg 6.79: docs/authors-parts.md), and the tube's wall three 0.4 mm lines.
PEG_D = 6.8  # mm
PEG_TUBE_WALL = 1.2  # mm
# The link's TPU round each socket (the authors' (6.79 - 3.19) / 2) and between a socket's floor
# and its peg (their 0.3).
PEG_COLUMN_WALL = 1.8  # mm
PEG_GAP = 0.3  # mm
# The link's arch, as the authors' connector has it: it joins the columns from their mouths down
# to PEG_ARCH_LIFT above the pegs' shoulder (clear of the core plate's bars, which end in the
# shoulder's plane), with an opening under its crown, PEG_ARCH_LEN below the mouths (their 2.8 mm
# crown under z 9 mouths). The strut hangs on the crown, as their third column does: its sleeve's
# back end lies in it, the lowest point PEG_SLEEVE_FLOOR above the crown's underside. No face only
# touches another (OCC fuses no tangent faces).
PEG_ARCH_LEN = 3.0  # mm
PEG_ARCH_LIFT = 0.5  # mm
PEG_SLEEVE_FLOOR = 0.5  # mm
PEG_SNAP = 0.2  # mm: a peg and its column closer than this in diameter are one cylinder, the peg's (no sliver shoulder)


def peg_column_r(bore: float, wall: float = PEG_COLUMN_WALL, peg_d: float = PEG_D) -> float:
    """The radius of a pegged link's columns (and the strut's sleeve): the socket's bore and its
    wall, or the peg's own radius when within PEG_SNAP / 2 of it (the peg is the core's bore, the
    press fit the plate's tubes and `peg_drop` are made for; the wall moves by under 0.1 mm)."""
    r = bore / 2 + wall
    return peg_d / 2 if abs(peg_d / 2 - r) < PEG_SNAP / 2 else r


def pegged_strut_port(link: np.ndarray, knee: np.ndarray, corner: np.ndarray, seat: float, depth: float,
                      bore: float) -> np.ndarray:
    """Where the strut's axis enters a pegged core link (its port, `seat` short of its socket's
    floor): the sleeve's back end (the column wall behind the floor) is centred on the arm pair's
    mid-line, in the arch's crown: its lowest point PEG_SLEEVE_FLOOR above the crown's underside,
    which lies PEG_ARCH_LEN inside the arms' mouths (`seat + depth` along the arms). The strut
    aims at its bottom corner from there: a fixed point (the sleeve's lean depends on the port),
    met to 1e-12 mm in a few steps since the port moves millimetres on a strut over 100 mm long."""
    d_a = (knee - link) / np.linalg.norm(knee - link)
    r = peg_column_r(bore)
    t0 = seat - PEG_COLUMN_WALL
    port = np.asarray(link, float).copy()
    for _ in range(100):
        d_s = (corner - port) / np.linalg.norm(corner - port)
        sin = math.sqrt(max(0.0, 1.0 - float(d_a @ d_s) ** 2))
        b = seat + depth - PEG_ARCH_LEN + PEG_SLEEVE_FLOOR + r * sin
        new = link + b * d_a - t0 * d_s
        if float(np.linalg.norm(new - port)) < 1e-12:
            return new
        port = new
    return port


def peg_drop(spec: Spec) -> float:
    """How far the core links' nodes (the arms' axes) lie below the core plate's mid-plane, mm:
    0 for the tab link. With pegs each tube hangs under the plate, its top flush with the plate's
    top: the plate prints upside down, its top and the tubes on the bed together."""
    if spec.core.link != "pegs":
        return 0.0
    return PEG_D / 2 + PEG_TUBE_WALL - spec.core.plate_thickness / 2


STACK_H = 16.0  # FC + 4-in-1 ESC on 8 mm standoffs, mm
STACK_BOTTOM = 3.0  # soft-mount grommets / nylon nuts under the ESC, mm: the core links' tabs keep below it
CAMERA_BASE_T = 2.0  # camera mount base plate under the stack, mm
SENSOR_GAP = 3.0  # holder rear face to the flow board's edge, mm
# The companion computer stands on nylon spacers this tall over its mount: the stack screws' 2 mm
# heads sit on the mount under the computer's board (fasteners.py), mm
COMPUTER_LIFT = 3.0


def strap_mouth(spec: Spec) -> float:
    """Holder length in front of the pack (mm): 1 mm gap, the 45 deg strap slot, 1.5 mm end wall."""
    return 1.0 + (spec.core.strap_width + 1.0 + 2.0) / math.sqrt(2) + 1.5


def _core(spec: Spec) -> Core:
    """The core stack, bottom up: battery holder (pack centred under the plate, open at the front,
    strap slots at the mouth), spacer / sensor mount, core plate, camera-mount base, FC stack,
    computer mount and computer. The flow board hangs under the sensor mount's rear pad, behind
    the holder; the camera stands on the plate's front edge. With level arms everything from the
    plate up is lifted `hang` mm onto standoffs, to the knees' height (with pegs, `peg_drop` above
    it: the arms run through the tubes under the plate)."""
    from .materials import BOARDS

    c, b = spec.core, spec.core.battery
    floor = wall = c.holder_wall
    holder_h = b.height + 2 * wall + 1.0  # floor + top wall, and 1 mm slack so the pack slides in
    holder_bottom = c.battery_clearance
    mouth = strap_mouth(spec)
    y0, y1 = -(b.length / 2 + wall), b.length / 2 + mouth  # back stop at the rear, mouth at the front
    holder = Box("battery_holder", (0.0, (y0 + y1) / 2, holder_bottom + holder_h / 2), (b.width + 2 * wall, y1 - y0, holder_h))
    battery = Box("battery", (0.0, 0.0, holder_bottom + floor + b.height / 2), (b.width, b.length, b.height))
    h_top = holder_bottom + holder_h
    spacer = flow = None
    if c.spacer_thickness > 0:
        spacer = Box("sensor_mount" if c.flow_sensor else "core_spacer", (0.0, 0.0, h_top + c.spacer_thickness / 2),
                     (c.plate_size, c.plate_size, c.spacer_thickness))
    if c.flow_sensor:
        fb = BOARDS[c.flow_sensor.model]
        fz = fb.size[2] + fb.parts_block[2]
        fy = y0 - SENSOR_GAP - fb.size[1] / 2
        flow = Box("flow_sensor", (0.0, fy, h_top - fz / 2), (fb.size[0], fb.size[1], fz))
    plate_z = h_top + c.spacer_thickness + c.plate_thickness / 2
    hang = 0.0
    if spec.frame.level_arms:
        # whole millimetres: M2 standoffs come in 1 mm steps; the knees then follow the plate
        z_knee = spec.frame.height * spec.frame.knee_height
        drop = peg_drop(spec)
        hang = float(round(z_knee + drop - plate_z))
        if hang < 0:
            where = "at the knees' height" if drop == 0 else f"{drop:.1f} mm above the knees' height (the pegs' tubes hang under it)"
            raise spec.error(
                "frame.knee_height",
                f"level arms need the core plate {where}, z = {z_knee + drop:.1f} mm, but the battery holder "
                f"({c.battery_clearance:g} mm clearance, {holder_h:.1f} mm tall) and the spacer already put it at "
                f"z = {plate_z:.1f} mm", f"raise frame.knee_height to at least {math.ceil((plate_z - drop) / spec.frame.height * 100) / 100:.2f}, "
                "or set frame.level_arms: false (the arms then climb from the plate to the knees)")
        plate_z += hang
    plate = Box("core_plate", (0.0, 0.0, plate_z), (c.plate_size, c.plate_size, c.plate_thickness))
    board = STACK_PATTERNS[c.stack_pattern][1]
    top = plate_z + c.plate_thickness / 2
    camera = base = None
    if c.camera:
        cb = BOARDS[c.camera.model]
        base = Box("camera_base", (0.0, 0.0, top + CAMERA_BASE_T / 2), (cb.size[0] + 2.0, c.plate_size, CAMERA_BASE_T))
        depth = cb.size[2] + (cb.lens[1] if cb.lens else 0.0)
        camera = Box("camera", (0.0, c.plate_size / 2 + depth / 2, top + CAMERA_BASE_T + 1.0 + cb.size[1] / 2),
                     (cb.size[0], depth, cb.size[1]))
        top += CAMERA_BASE_T
    stack = Box("fc_stack", (0.0, 0.0, top + STACK_H / 2), (board, board, STACK_H))
    computer = None
    if c.computer:
        w, h = c.computer.hole_spacing
        computer = Box("computer", (0.0, 0.0, top + STACK_H + 6.0 + COMPUTER_LIFT), (w + 7.0, h + 7.0, 5.0))
    return Core(plate, holder, battery, stack, computer, spacer, flow, camera, base, mouth, hang)


def _motor(k: str, rods: dict[str, Rod], spec: Spec) -> Motor:
    r1, r2 = rods[f"rod_arm_{k}_1"], rods[f"rod_arm_{k}_2"]
    pa = (np.asarray(r1.a.port) + np.asarray(r2.a.port)) / 2  # knee end
    pb = (np.asarray(r1.b.port) + np.asarray(r2.b.port)) / 2  # core end
    ra, rb = np.hypot(*pa[:2]), np.hypot(*pb[:2])
    t = _radius_along(pa, pb, ra, rb, spec.motors.radius)
    if not 0.0 < t < 1.0:
        raise spec.error(
            "motors.radius",
            f"{spec.motors.radius:g} mm puts the motors off their arms, which run from "
            f"{rb:.0f} to {ra:.0f} mm from the centre", f"set motors.radius between {rb + 10:.0f} and {ra - 10:.0f}")
    axis = pa + t * (pb - pa)
    slope = math.degrees(math.atan2(pa[2] - pb[2], ra - rb))
    # The motor screws come up through the seat from below: leave room for their heads
    # (ISO 4762 head height = d) above the rod clips, plus the seat plate itself.
    head = SCREWS[spec.motor.screw].d
    # motors.seat_raise lifts a bigger propeller over the core (the authors' taller motor bases)
    seat_z = float(axis[2]) + spec.sleeve_bore / 2 + spec.joints.wall + head + spec.joints.wall + spec.motors.seat_raise
    prop_z = seat_z + spec.motor.height
    return Motor(f"motor_{k}", k, (r1.name, r2.name), _t(axis), seat_z, prop_z, slope)


def _radius_along(pa: np.ndarray, pb: np.ndarray, ra: float, rb: float, radius: float) -> float:
    """Where along the arm centreline pa -> pb the motor axis is `radius` from the centre in plan
    (0 at pa, 1 at pb; outside [0, 1] when it is off the arm). An arm that points at the centre
    (a square box: on the diagonal) is linear in the radius; in a rectangle it passes beside the
    centre (the knee is off the diagonal, the core link on it), so solve |pa + t (pb - pa)| = radius."""
    u = pb[:2] - pa[:2]
    if abs(float(pa[0] * pb[1] - pa[1] * pb[0])) <= 1e-9 * ra * rb:
        return float((ra - radius) / (ra - rb))
    a, b, c = float(u @ u), 2.0 * float(pa[:2] @ u), float(pa[:2] @ pa[:2]) - radius**2
    disc = b * b - 4 * a * c
    if disc < 0:
        return math.inf  # the arm never comes that close to the centre
    return (-b - math.sqrt(disc)) / (2 * a)  # the first crossing going inwards from the knee


def prop_clearances(frame: Frame, spec: Spec) -> tuple[PropClearance, ...]:
    """Smallest gap (mm) between each propeller disc and the cage rods, the core and the other discs."""
    radius = spec.motors.prop_diameter / 2
    cage = _RodSamples([r for r in frame.rods.values() if r.role != "arm"])
    disc = _disc_grid(radius)
    out = []
    for m in frame.motors:
        centre = np.array([m.axis[0], m.axis[1], m.prop_z])
        to_cage = cage.min_to_disc(centre, radius)
        core = _boxes_to_disc(frame.core.boxes, centre, radius, disc)
        others = [np.hypot(o.axis[0] - m.axis[0], o.axis[1] - m.axis[1]) - 2 * radius for o in frame.motors if o is not m]
        out.append(PropClearance(m.name, round(to_cage, 2), round(core, 2), round(float(min(others)), 2)))
    return tuple(out)


def _rod_to_disc(rod: Rod, centre: np.ndarray, radius: float) -> float:
    """Distance from a rod's surface to a horizontal disc, sampled every 0.5 mm along the rod."""
    return float(_point_to_disc(_rod_points(rod), centre, radius).min() - rod.diameter / 2)


def _rod_points(rod: Rod) -> np.ndarray:
    """A rod's axis sampled every 0.5 mm (at least its two ends)."""
    n = max(2, int(rod.length / 0.5))
    return rod.start + np.outer(np.linspace(0, 1, n), rod.end - rod.start)


class _RodSamples:
    """Rods' axis samples (`_rod_points`), made once and measured against every propeller disc:
    min over the rods of `_rod_to_disc`, the same numbers, from one array."""

    def __init__(self, rods: list[Rod]):
        pts = [_rod_points(r) for r in rods]
        self.points = np.concatenate(pts)
        self.starts = np.cumsum([0] + [len(p) for p in pts[:-1]])
        self.radii = np.array([r.diameter / 2 for r in rods])

    def min_to_disc(self, centre: np.ndarray, radius: float) -> float:
        per_rod = np.minimum.reduceat(_point_to_disc(self.points, centre, radius), self.starts)
        return float((per_rod - self.radii).min())


def _point_to_disc(pts: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    dxy = np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1])
    dz = np.abs(pts[:, 2] - centre[2])
    return np.hypot(np.maximum(dxy - radius, 0.0), dz)


def _boxes_to_disc(boxes, centre: np.ndarray, radius: float, disc: tuple | None = None) -> float:
    """min(_box_to_disc) over `boxes`, the same number: a box whose exact distance bound (vertical
    gap and plan gap beyond the radius) already exceeds the nearest sampled one cannot be nearer
    (a sampled distance is never below the exact one), so it is not sampled. ``disc``: the
    radius's `_disc_grid`, when the caller has it."""
    def bound(b: Box) -> float:
        lo, hi = np.asarray(b.centre) - np.asarray(b.size) / 2, np.asarray(b.centre) + np.asarray(b.size) / 2
        gap = np.maximum(np.maximum(lo - centre, centre - hi), 0.0)
        return float(math.hypot(gap[2], max(math.hypot(gap[0], gap[1]) - radius, 0.0)))

    disc = _disc_grid(radius) if disc is None else disc
    best = math.inf
    for lb, i in sorted((bound(b), i) for i, b in enumerate(boxes)):
        if lb > best + 1e-9:
            break
        best = min(best, _box_to_disc(boxes[i], centre, radius, disc))
    return best


def _disc_grid(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) offsets from the centre of a disc's 1 mm polar grid (`_box_to_disc`)."""
    rr = np.linspace(0, radius, max(2, int(radius) + 1))
    th = np.linspace(0, 2 * math.pi, max(16, int(2 * math.pi * radius)), endpoint=False)
    R, T = np.meshgrid(rr, th)
    return (R * np.cos(T)).ravel(), (R * np.sin(T)).ravel()


def _box_to_disc(box: Box, centre: np.ndarray, radius: float, disc: tuple | None = None) -> float:
    """Distance from an axis-aligned box to a horizontal disc (disc sampled on a 1 mm polar grid,
    `_disc_grid`; ``disc``: that grid when the caller has it)."""
    dx, dy = _disc_grid(radius) if disc is None else disc
    half = np.asarray(box.size) / 2
    gx = np.maximum(np.abs(centre[0] + dx - box.centre[0]) - half[0], 0.0)
    gy = np.maximum(np.abs(centre[1] + dy - box.centre[1]) - half[1], 0.0)
    gz = max(abs(centre[2] - box.centre[2]) - half[2], 0.0)  # the disc is flat: one vertical gap
    # the points' gaps' norms (x^2 + y^2) + z^2, as np.linalg.norm sums a row; the least norm is
    # the root of the least sum (a rounded square root never reverses an order)
    return math.sqrt(float(((gx * gx + gy * gy) + gz * gz).min()))

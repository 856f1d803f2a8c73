"""Stage 3: Frame -> the printed parts: which distinct parts, how many, and where their sockets are.

Pure numpy, no CAD. Every part quantity and every socket comes from the frame graph, so the CAD,
the cut list, the mass budget and the stiffness model agree. Each part carries an analytic
estimate of its volume and surface (used by `cogniframe check`, which must not import CadQuery;
`build` replaces it with the CAD volume) and the BOM lines of the hardware it implies.

Local frames: a joint's local origin is its node; the prototype is the front-left (`fl`)
instance and the others are the prototype rotated about z by `Placement.rotation_deg`.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .frame import CORNERS, Frame
from .materials import SCREWS, STACK_PATTERNS
from .spec import Spec

Vec = tuple[float, float, float]
# Rotation about z taking the fl prototype to each corner (clockwise seen from above).
CORNER_ROTATION = {"fl": 0.0, "fr": -90.0, "rr": -180.0, "rl": 90.0}
# Two socket directions count as parallel (an arm pair) when their dot product exceeds 1 - this;
# directions are stored rounded to 6 decimals, so 1e-6 is too tight (~0.8 deg here).
PARALLEL_TOL = 1e-4


@dataclass(frozen=True)
class Socket:
    """A blind rod hole in a part's local frame (mm)."""

    rod: str  # rod name in the prototype instance
    port: Vec  # point on the rod axis level with the joint centre
    direction: Vec  # unit vector out of the socket, along the rod
    seat: float  # port -> socket bottom (where the rod ends)
    depth: float  # socket bottom -> mouth (rod insertion)
    bore: float  # hole diameter = rod diameter + fit clearance

    def bottom(self) -> np.ndarray:
        return np.asarray(self.port) + np.asarray(self.direction) * self.seat

    def mouth(self) -> np.ndarray:
        return np.asarray(self.port) + np.asarray(self.direction) * (self.seat + self.depth)


@dataclass(frozen=True)
class Placement:
    """Where one copy of a part goes: rotate the local frame about z, then move its origin to `origin`."""

    instance: str  # node or motor name, e.g. knee_fr
    rotation_deg: float
    origin: Vec

    def matrix(self) -> np.ndarray:
        """4x4 world-from-local transform."""
        a = math.radians(self.rotation_deg)
        m = np.eye(4)
        m[:2, :2] = [[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
        m[:3, 3] = self.origin
        return m


@dataclass(frozen=True)
class Estimate:
    """Analytic geometry of a part: volume (mm^3), horizontal and vertical surface (mm^2), envelope (mm)."""

    volume: float
    area_h: float
    area_v: float
    envelope: Vec  # a bounding box that fits it in print orientation


@dataclass(frozen=True)
class HardwareLine:
    item: str
    qty: int  # per copy of the part
    mass_g: float  # each


@dataclass(frozen=True)
class PartSpec:
    name: str  # distinct part, e.g. "knee"
    family: str  # parts/<family>.py builds it: joint | motor_mount | core_plate | battery_holder | computer_mount
    group: str  # mass-budget group: exoskeleton | core
    material: str
    infill: float
    placements: tuple[Placement, ...]
    sockets: tuple[Socket, ...]
    wall: float
    estimate: Estimate
    params: tuple[tuple[str, object], ...] = ()  # family-specific inputs, all the CAD may read
    hardware: tuple[HardwareLine, ...] = ()
    digest: str = field(default="")  # hash of everything above: the part's CAD cache key

    @property
    def qty(self) -> int:
        return len(self.placements)

    def param(self, key: str):
        return dict(self.params)[key]


def build(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    """All distinct printed parts of the design, in a stable order."""
    parts = [
        _joint(spec, frame, "corner_top", "corner_top"),
        _joint(spec, frame, "corner_bottom", "corner_bottom"),
        _joint(spec, frame, "knee", "knee"),
        _joint(spec, frame, "core_link", "core_link"),
        _motor_mount(spec, frame),
        _core_plate(spec, frame),
        _battery_holder(spec, frame),
    ]
    if spec.core.computer:
        parts.append(_computer_mount(spec, frame))
    return tuple(_with_digest(p) for p in parts)


# -- joints ----------------------------------------------------------------------------------

def _rot_z(v: np.ndarray, deg: float) -> np.ndarray:
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])


def _t(v) -> Vec:
    return (round(float(v[0]), 6), round(float(v[1]), 6), round(float(v[2]), 6))


def _joint(spec: Spec, frame: Frame, name: str, kind: str) -> PartSpec:
    proto = frame.nodes[f"{kind}_fl"]
    origin = np.asarray(proto.pos)
    sockets = []
    for rname in proto.rods:
        rod = frame.rods[rname]
        end = rod.end_at(proto.name)
        sockets.append(Socket(rname, _t(np.asarray(end.port) - origin), _t(rod.socket_direction(proto.name)),
                              end.seat, end.depth, round(spec.bore, 4)))
    placements = tuple(Placement(f"{kind}_{k}", CORNER_ROTATION[k], _t(frame.nodes[f"{kind}_{k}"].pos)) for k in CORNERS)
    hardware: tuple[HardwareLine, ...] = ()
    params: list[tuple[str, object]] = [("hinge_thickness", spec.joints.hinge_thickness)]
    if kind == "core_link":
        # The link bolts onto the top of the core plate corner with one screw.
        screw = SCREWS[spec.core.stack_screw]
        hole = _link_hole(spec)
        params += [("screw", screw.name), ("screw_clearance", screw.clearance_d),
                   # plate-corner hole and plate top, in the link's local frame (its node is at plate mid-height)
                   ("bolt_hole", _t(np.array([-hole, hole, 0.0]) - np.array([origin[0], origin[1], 0.0]))),
                   ("plate_top_z", round(spec.core.plate_thickness / 2, 4)), ("tab_thickness", spec.core.plate_thickness)]
        hardware = (HardwareLine(f"{screw.name} x 8 socket-head screw + nut (core link to plate)", 1, screw.mass_g + 0.1),)
    if kind == "corner_bottom":
        params.append(("foot", True))  # the bottom corners are the feet: flat pad on the ground side
    return PartSpec(name, "joint", "exoskeleton", spec.joints.material, 1.0, placements, tuple(sockets),
                    spec.joints.wall, _joint_estimate(spec, sockets, kind, dict(params)), tuple(params), hardware)


def _link_hole(spec: Spec) -> float:
    """Plate-corner bolt position for the core links, along x and y from the centre (mm)."""
    return spec.core.plate_size / 2 - max(4.0, spec.core.plate_thickness + 1.5)


def _joint_estimate(spec: Spec, sockets: list[Socket], kind: str, params: dict | None = None) -> Estimate:
    """Closed-form volume/areas of the joint as parts/joint.py builds it, in print orientation.

    Pieces (r = OD/2 = bore/2 + wall, L = seat + depth): a sleeve parallel to the bed is a D
    section (2r wide, flat on the bed up to its axis height h, round top: 2 r h + pi r^2 / 2); a
    steep one a cylinder; a sloped one half a cylinder on a 0.9 x OD web down to the bed. Corners
    add a round hub (and the foot pad), knee and core link stack the arm sockets in one block,
    the core link adds a hub between the sleeves and its bolt tab. Minus the bores.
    """
    params = params or {}
    j = spec.joints
    r = spec.bore / 2 + j.wall
    hole = math.pi / 4 * spec.bore**2
    dirs = np.array([s.direction for s in sockets], float)
    ports = np.array([s.port for s in sockets], float)
    L = np.array([s.seat + s.depth for s in sockets], float)

    def d_area(h: float) -> float:
        return 2 * r * h + math.pi * r**2 / 2

    vol = -sum(hole * s.depth for s in sockets)
    a_h = a_v = 0.0
    if kind in ("corner_top", "corner_bottom"):
        up = -1.0 if dirs[np.abs(dirs[:, 2]) > 1e-6, 2].sum() < 0 else 1.0
        vol += 2 * math.pi * r**3  # hub
        a_h += 2 * math.pi * r**2
        a_v += 4 * math.pi * r**2
        for d, n in zip(dirs, L):
            dz = d[2] * up
            if abs(dz) < 1e-6:
                vol += d_area(r) * n - math.pi * r**2 / 2 * (r + math.pi * r / 4)
                a_h += (2 * r + math.pi * r / 2) * n
                a_v += (2 * r + math.pi * r / 2) * n
            elif dz >= math.cos(math.radians(45)):
                vol += math.pi * r**2 * (n - r)
                a_v += 2 * math.pi * r * n
            else:
                run = n * math.sqrt(1 - dz * dz)
                h_mean = r + dz * n / 2
                vol += math.pi * r**2 / 2 * n + 1.8 * r * h_mean * run - math.pi * r**2 / 2 * r
                a_h += 1.8 * r * run + math.pi * r * n / 2
                a_v += 2 * h_mean * run + math.pi * r * n / 2
        if params.get("foot"):
            vol += 1.5 * math.pi * r**2 * j.wall
            a_h += 2.2 * math.pi * r**2
        ext = np.ptp(np.vstack([ports, ports + dirs * L[:, None]]), axis=0) + 2 * r
    else:
        _, _, vt = np.linalg.svd(dirs)
        w = vt[-1]
        zc = ports @ w
        z = zc - zc.min() + r  # axis heights in print orientation
        par = [i for i in range(len(sockets)) if sum(dirs[i] @ dirs[k] > 1 - PARALLEL_TOL for k in range(len(sockets))) > 1]
        rest = [i for i in range(len(sockets)) if i not in par]
        sleeve_l = [sockets[i].depth + j.wall for i in range(len(sockets))]
        blocks = [(z[par].max(), sleeve_l[par[0]])] + [(z[i], sleeve_l[i]) for i in rest]
        for h, n in blocks:
            vol += d_area(h) * n
            a_h += (2 * r + math.pi * r / 2) * n
            a_v += (2 * h + math.pi * r / 2) * n
        for i in (rest if kind == "core_link" else []):  # a sleeve leaving at a small angle to the arm block runs partly inside it
            sin_t = float(np.linalg.norm(np.cross(dirs[i], dirs[par[0]])))
            s0, s1 = sockets[i].seat - j.wall, sockets[i].seat + sockets[i].depth
            s_end = min(s1, 2 * r / sin_t) if sin_t > 1e-9 else s1
            if s_end > s0:
                overlap = 2 * r * (s_end - s0) - sin_t * (s_end**2 - s0**2) / 2
                vol -= overlap * (z[i] + math.pi * r / 4)
        top = float(z[rest].max() + r) if rest else float(z[par].max() + r)  # no strut: arm sockets only
        if kind == "knee":
            vol += j.hinge_thickness * 2.7 * top
            a_v += 2 * 2.7 * top
        else:
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
            hub_area = _hull_area(np.array([[p_ @ x, p_ @ y] for p_ in pts]))
            hub_h = max(top, tab_h)
            vol += hub_area * hub_h
            a_h += hub_area
            a_v += 2 * s_back * hub_h
        ext = np.array([np.ptp(np.vstack([ports, ports + dirs * L[:, None]]) @ np.eye(3), axis=0).max() + 2 * r,
                        2 * r + float(L.max()), float(z.max() + r)])
    a_v += sum(math.pi * spec.bore * s.depth for s in sockets)
    env = tuple(sorted(float(x) for x in ext))
    return Estimate(vol, a_h, a_v, (env[2], env[1], env[0]))


def _hull_area(pts: np.ndarray) -> float:
    """Area of the convex hull of 2-D points (monotone chain + shoelace)."""
    pts = sorted(map(tuple, np.round(pts, 9)))

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0]) <= 0:
                out.pop()
            out.append(p)
        return out[:-1]

    hull = np.array(half(pts) + half(pts[::-1]))
    x, y = hull[:, 0], hull[:, 1]
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2)


# -- motor mount -----------------------------------------------------------------------------

def _motor_mount(spec: Spec, frame: Frame) -> PartSpec:
    m0 = frame.motors[0]
    motor = spec.motor
    r1, r2 = frame.rods[m0.arm[0]], frame.rods[m0.arm[1]]
    axis = np.asarray(m0.axis)
    # Rod axis points through the mount's local origin (the motor axis on the arm centreline).
    rods_local = []
    for r in (r1, r2):
        p = r.start - axis
        d = r.axis
        t = -np.dot(p, d)
        rods_local.append((_t(p + t * d), _t(d)))
    screw = SCREWS[motor.screw]
    width = max(motor.bell_d + 4.0, spec.frame.arm_spacing + spec.bore + 2 * spec.joints.wall)
    thick = spec.joints.wall + 1.5
    clip_len = width
    od = spec.bore + 2 * spec.joints.wall
    vol = width * width * thick + 2 * (math.pi / 4 * (od**2 - spec.bore**2) * clip_len)
    vol -= 4 * math.pi / 4 * screw.clearance_d**2 * thick + math.pi / 4 * (motor.shaft_boss_d + 1) ** 2 * thick
    est = Estimate(vol, 2 * width * width, 4 * width * thick + 2 * math.pi * od * clip_len, (width, width, thick + od))
    placements = tuple(Placement(m.name, CORNER_ROTATION[m.corner], _t(m.axis)) for m in frame.motors)
    params = (("bolt_spacing", motor.bolt_spacing), ("screw", screw.name), ("screw_clearance", screw.clearance_d),
              ("shaft_hole", motor.shaft_boss_d + 1.0), ("bell_d", motor.bell_d), ("seat_z", round(m0.seat_z - axis[2], 4)),
              ("arm_rods", tuple(rods_local)), ("arm_slope_deg", round(m0.arm_slope_deg, 4)), ("width", width),
              ("bore", round(spec.bore, 4)))
    hw = (HardwareLine(f"{screw.name} x 6 screw (motor to mount)", 4, screw.mass_g),)
    return PartSpec("motor_mount", "motor_mount", "exoskeleton", spec.joints.material, 1.0, placements, (), spec.joints.wall,
                    est, params, hw)


# -- core ------------------------------------------------------------------------------------

def _plate_estimate(a: float, b: float, t: float, holes: list[float]) -> Estimate:
    hole_area = sum(math.pi / 4 * d**2 for d in holes)
    return Estimate(a * b * t - hole_area * t, 2 * (a * b - hole_area), 2 * (a + b) * t + sum(math.pi * d * t for d in holes),
                    (a, b, t))


def _core_plate(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    hole = _link_hole(spec)
    holes = [(sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1)]
    holes += [(sx * hole, sy * hole) for sx in (-1, 1) for sy in (-1, 1)]
    est = _plate_estimate(c.plate_size, c.plate_size, c.plate_thickness, [screw.clearance_d] * len(holes))
    params = (("size", c.plate_size), ("thickness", c.plate_thickness), ("holes", tuple(holes)), ("hole_d", screw.clearance_d))
    hw = (HardwareLine(f"{screw.name} x 20 screw + 8 mm nylon standoffs (FC/ESC stack through plate and holder)", 4, 1.0),)
    return PartSpec("core_plate", "core_plate", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t(frame.core.plate.centre)),), (), c.plate_thickness, est, params, hw)


def _battery_holder(spec: Spec, frame: Frame) -> PartSpec:
    c, b = spec.core, spec.core.battery
    h = frame.core.holder
    w, length, height = h.size
    t = c.holder_wall
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    # Open-ended sleeve (floor, top, two side walls) with a back stop, printed standing on the back
    # stop: the outer box minus the battery cavity (open at the front) minus the stack holes in the
    # top, whose thickness is what the outer height leaves around the cavity (parts/core.py).
    iw, il, ih = b.width, b.length, b.height + 1.0
    skin = (height - ih) / 2
    holes = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    vol = w * length * height - iw * il * ih - len(holes) * math.pi / 4 * screw.clearance_d**2 * skin
    # Walls are vertical when printed on end: outside and cavity faces; horizontal: the back stop
    # and the rim of the open end.
    area_v = 2 * (w + height) * length + 2 * (iw + ih) * il
    rim = w * height - iw * ih
    area_h = w * height + rim
    est = Estimate(vol, area_h, area_v, (w, height, length))
    params = (("inner", (b.width, b.length, b.height + 1.0)), ("wall", t), ("holes", holes), ("hole_d", screw.clearance_d),
              ("outer", (w, length, height)))
    return PartSpec("battery_holder", "battery_holder", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t(h.centre)),), (), t, est, params)


def _computer_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    comp = c.computer
    box = frame.core.computer
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    a, b = box.size[0], max(box.size[1], pitch + 8.0)
    t = 2.5
    screw_pi, screw_st = SCREWS[comp.screw], SCREWS[c.stack_screw]
    hw_, hh_ = comp.hole_spacing
    pi_holes = tuple((sx * hw_ / 2, sy * hh_ / 2) for sx in (-1, 1) for sy in (-1, 1))
    st_holes = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    est = _plate_estimate(a, b, t, [screw_pi.clearance_d] * 4 + [screw_st.clearance_d] * 4)
    params = (("size", (a, b)), ("thickness", t), ("computer_holes", pi_holes), ("computer_hole_d", screw_pi.clearance_d),
              ("stack_holes", st_holes), ("stack_hole_d", screw_st.clearance_d))
    hw = (HardwareLine(f"{screw_pi.name} x 6 screw + nut ({comp.name} to mount)", 4, screw_pi.mass_g + 0.15),)
    return PartSpec("computer_mount", "computer_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t((box.centre[0], box.centre[1], box.lo[2] - t / 2))),), (), t, est, params, hw)


def _with_digest(p: PartSpec) -> PartSpec:
    payload = json.dumps([p.name, p.family, p.material, p.infill, [s.__dict__ for s in p.sockets], p.wall,
                          [list(map(str, kv)) for kv in p.params]], sort_keys=True, default=str)
    return replace(p, digest=hashlib.sha256(payload.encode()).hexdigest()[:16])

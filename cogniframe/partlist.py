"""Stage 3: Frame -> the printed parts: which distinct parts, how many, and where their sockets are.

Pure numpy, no CAD. Every part quantity and every socket comes from the frame graph, so the CAD,
the cut list, the mass budget and the stiffness model agree. Each part carries an analytic
estimate of its volume and surface (used by `cogniframe check`, which must not import CadQuery;
`build` replaces it with the CAD volume) and the BOM lines of the hardware it implies.

Local frames: a joint's local origin is its node; the prototype is the front-left (`fl`)
instance and the others are the prototype rotated about z by `Placement.rotation_deg`.

Rectangular boxes. A corner's sockets are the rotation of the fl corner's only when they are
symmetric about the corner's 45 deg diagonal. In a square box they are (one part per kind); in a
rectangle the arms (knee -> core link) and the struts (bottom corner -> core link) run off the
diagonal, so the fr and rl corners are the MIRROR image of fl and rr (fl and rr are always a
180 deg rotation apart: the box is symmetric about both centre planes). Which corners a part
serves is tested on the frame graph itself (`_fit_error`): a kind whose fr corner is not the
rotation of its fl corner gets a second part `<kind>_mirrored` (params kind + mirror, prototype
fr) for fr and rl, as the core link always does. The motor mount is symmetric about its arm, so
one part serves every corner, turned to the actual plan direction of each arm.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .frame import CAMERA_BASE_T, CORNER_SIGN, CORNERS, STACK_BOTTOM, Frame
from .materials import BOARDS, CONNECTORS, MIN_THREAD_TURNS, SCREWS, STACK_PATTERNS
from .spec import Spec

Vec = tuple[float, float, float]
# Rotation about z taking the fl prototype to each corner (clockwise seen from above).
CORNER_ROTATION = {"fl": 0.0, "fr": -90.0, "rr": -180.0, "rl": 90.0}
# A corner's sockets coincide with the prototype's placed there when no port (mm) or direction
# (unit vector) differs by more than this; sockets are stored rounded to 1e-6.
FIT_TOL = 1e-5
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
        *_joints(spec, frame, "corner_top"),
        *_joints(spec, frame, "corner_bottom"),
        *_joints(spec, frame, "knee"),
        # The core links are chiral (printed on their side, D-section sleeves standing on the bed),
        # and the battery holder is a rectangle, not a square: a link rotated from fl to fr meets
        # the holder differently. So fr and rl get the mirror image of the fl/rr link.
        _joint(spec, frame, "core_link", "core_link", corners=("fl", "rr")),
        _joint(spec, frame, "core_link_mirrored", "core_link", proto="fr", corners=("fr", "rl")),
        _motor_mount(spec, frame),
        _core_plate(spec, frame),
        _battery_holder(spec, frame),
    ]
    if spec.core.spacer_thickness > 0:
        parts.append(_sensor_mount(spec, frame))
    if spec.core.camera:
        parts.append(_camera_mount(spec, frame))
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


def node_sockets(spec: Spec, frame: Frame, node: str) -> list[Socket]:
    """The sockets of a joint node, in the frame's axes with the node at the origin (from the graph)."""
    n = frame.nodes[node]
    origin = np.asarray(n.pos)
    sockets = []
    for rname in n.rods:
        rod = frame.rods[rname]
        end = rod.end_at(node)
        sockets.append(Socket(rname, _t(np.asarray(end.port) - origin), _t(rod.socket_direction(node)),
                              end.seat, end.depth, round(spec.bore, 4)))
    return sockets


def _fit_error(sockets, rotation_deg: float, target) -> float:
    """How far `sockets` turned about z by `rotation_deg` are from the sockets `target` (both in
    their node's axes): the worst port (mm) + direction error of the best one-to-one matching,
    inf when the counts or the seats, depths or bores differ."""
    if len(sockets) != len(target):
        return math.inf
    left = list(target)
    worst = 0.0
    for s in sockets:
        p, d = _rot_z(np.asarray(s.port, float), rotation_deg), _rot_z(np.asarray(s.direction, float), rotation_deg)
        errs = [float(np.linalg.norm(p - np.asarray(t.port)) + np.linalg.norm(d - np.asarray(t.direction)))
                if (t.seat, t.depth, t.bore) == (s.seat, s.depth, s.bore) else math.inf for t in left]
        i = int(np.argmin(errs))
        worst = max(worst, errs[i])
        left.pop(i)
    return worst


def _joints(spec: Spec, frame: Frame, kind: str) -> list[PartSpec]:
    """The part(s) of one joint kind: one for all four corners when each corner is the fl corner
    turned about z (a square box), else the part for fl and rr and its mirror image
    `<kind>_mirrored` for fr and rl (a rectangle: module docstring)."""
    fl = node_sockets(spec, frame, f"{kind}_fl")
    if all(_fit_error(fl, CORNER_ROTATION[k], node_sockets(spec, frame, f"{kind}_{k}")) <= FIT_TOL for k in CORNERS):
        return [_joint(spec, frame, kind, kind)]
    return [_joint(spec, frame, kind, kind, corners=("fl", "rr")),
            _joint(spec, frame, f"{kind}_mirrored", kind, proto="fr", corners=("fr", "rl"))]


def _joint(spec: Spec, frame: Frame, name: str, kind: str, proto: str = "fl", corners: tuple[str, ...] = CORNERS) -> PartSpec:
    """A joint part: the `proto` corner's node in its own axes, placed at `corners` by rotation about z.
    A prototype other than fl is the mirror image of the fl part (its side normal is mirrored too).
    Raises RuntimeError (a bug) if a placed copy's sockets miss the rods of its node."""
    corner = proto
    proto = frame.nodes[f"{kind}_{corner}"]
    origin = np.asarray(proto.pos)
    sockets = node_sockets(spec, frame, proto.name)
    base = CORNER_ROTATION[corner]
    placements = tuple(Placement(f"{kind}_{k}", (CORNER_ROTATION[k] - base + 180.0) % 360.0 - 180.0,
                                 _t(frame.nodes[f"{kind}_{k}"].pos)) for k in corners)
    for pl in placements:
        err = _fit_error(sockets, pl.rotation_deg, node_sockets(spec, frame, pl.instance))
        if err > FIT_TOL:
            raise RuntimeError(f"part {name}: its sockets placed at {pl.instance} miss the frame's rods by {err:.3g} mm")
    hardware: tuple[HardwareLine, ...] = ()
    params: list[tuple[str, object]] = [("hinge_thickness", spec.joints.hinge_thickness)]
    if name != kind:
        params += [("kind", kind), ("mirror", corner != "fl")]
    if kind == "core_link":
        # The link bolts onto the top of the core plate corner with one screw.
        screw = SCREWS[spec.core.stack_screw]
        hole = _link_hole(spec)
        sx, sy = CORNER_SIGN[corner]
        params += [("screw", screw.name), ("screw_clearance", screw.clearance_d),
                   # plate-corner hole and plate top, in the link's local frame (its node is at plate mid-height)
                   ("bolt_hole", _t(np.array([sx * hole, sy * hole, 0.0]) - np.array([origin[0], origin[1], 0.0]))),
                   ("plate_top_z", round(spec.core.plate_thickness / 2, 4)), ("tab_thickness", LINK_TAB),
                   # the plate corner the link seats against (its two edge faces), same frame
                   ("plate_corner", _t(np.array([sx, sy, 0.0]) * spec.core.plate_size / 2 - np.array([origin[0], origin[1], 0.0]))),
                   # the ESC board's footprint (its centre, at the height of its underside less
                   # 0.5 mm) and half-side, same frame: the tab keeps below the board
                   ("esc_keepout", _t(np.array([0.0, 0.0, float(frame.core.stack.lo[2]) + STACK_BOTTOM - 0.5]) - origin)),
                   ("esc_half", STACK_PATTERNS[spec.core.stack_pattern][1] / 2 + 0.5)]
        # tab + plate + spacer, nut in the spacer's nut trap: round up to a stock length
        grip = LINK_TAB + spec.core.plate_thickness + spec.core.spacer_thickness
        length = next((n for n in (8, 10, 12, 14, 16, 20) if n >= grip), 20)
        hardware = (HardwareLine(f"{screw.name} x {length} socket-head screw + nut (core link to plate)", 1, screw.mass_g * length / 6 + 0.1),)
    if kind == "corner_bottom":
        params.append(("foot", True))  # the bottom corners are the feet: flat pad on the ground side
    return PartSpec(name, "joint", "exoskeleton", spec.joints.material, 1.0, placements, tuple(sockets),
                    spec.joints.wall, _joint_estimate(spec, sockets, kind, dict(params)), tuple(params), hardware)


# The core link's tab: it carries an arm's thrust moment from the arm block, across the seat at
# the plate corner, onto the plate top. Its bending there is the hinge the bare arms hang on
# (cubic in its depth: at 3 mm the bare arms folded at full thrust; docs/stiffness-model.md).
LINK_TAB = 6.0  # mm


def _link_hole(spec: Spec) -> float:
    """Plate-corner bolt position for the core links, along x and y from the centre (mm): near the
    corner, because under thrust the tab lifts off the plate between the seat and the bolt head
    (an M2 clearance hole 3.5 mm from both edges keeps 2.3 mm of plate to each)."""
    return spec.core.plate_size / 2 - max(3.5, spec.core.plate_thickness + 0.5)


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
        _, sv, vt = np.linalg.svd(dirs)
        w = vt[-1]
        if sv[1] < 1e-6 * sv[0]:  # parallel arm sockets only (no strut): the SVD's normal is arbitrary;
            off = ports[1] - ports[0]  # use the one across the pair, as parts/joint.py prints it
            w = np.cross(dirs[0], np.cross(dirs[0], off))
            w /= np.linalg.norm(w)
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
            seat_area = _seat_area(params, ports[par], z[par], dirs[par[0]], sockets[par[0]].seat - j.wall, r,
                                   min(float(z[par].max() + r - 0.5), tab_h))
            vol += seat_area * 2 * v0
            a_v += 2 * seat_area
        ext = np.array([np.ptp(np.vstack([ports, ports + dirs * L[:, None]]) @ np.eye(3), axis=0).max() + 2 * r,
                        2 * r + float(L.max()), float(z.max() + r)])
    a_v += sum(math.pi * spec.bore * s.depth for s in sockets)
    env = tuple(sorted(float(x) for x in ext))
    return Estimate(vol, a_h, a_v, (env[2], env[1], env[0]))


def link_plate_corner(params: dict) -> tuple[np.ndarray, np.ndarray]:
    """The plate corner a core link seats against, in the link's local frame (x, y), and the
    signs (sx, sy) pointing out of the plate: the plate is {sx (x - cx) <= 0, sy (y - cy) <= 0}."""
    corner = np.asarray(params["plate_corner"], float)[:2]
    return corner, np.sign(corner - np.asarray(params["bolt_hole"], float)[:2])  # the bolt is inside the plate


def seat_plan(params: dict, ports, d: np.ndarray, s_back: float, r: float) -> list[np.ndarray]:
    """A core link's seat in plan, in its local frame, before the plate's corner is cut out and the
    print height clips it: the quadrilateral from 1 mm inside the arm block's back (the arm
    `ports`, direction `d`, sockets' backs `s_back` out) to past the plate corner, a millimetre
    past the block's width on both sides."""
    corner, _ = link_plate_corner(params)
    e_in = -np.array([d[0], d[1]]) / np.hypot(d[0], d[1])  # horizontal, toward the core
    e_w = np.array([-e_in[1], e_in[0]])
    u_b = min(float((np.asarray(p) + d * s_back)[:2] @ e_in) for p in ports) - 1.0
    w_half = max(abs(float(np.asarray(p)[:2] @ e_w)) for p in ports) + r + 1.0
    u_far = float(corner @ e_in) + w_half + 1.0
    return [e_in * u_b - e_w * w_half, e_in * u_far - e_w * w_half, e_in * u_far + e_w * w_half, e_in * u_b + e_w * w_half]


def _seat_area(params: dict, ports: np.ndarray, heights: np.ndarray, d: np.ndarray, s_back: float, r: float,
               height: float) -> float:
    """Plan area (mm^2) of a core link's seat as parts/joint.py builds it (`seat_plan`, less the
    plate's corner quadrant), from the bed up to `height` in print (the arm pair's two `ports`
    print at `heights`: print height runs across the pair)."""
    corner, sign = link_plate_corner(params)
    quad = seat_plan(params, ports, d, s_back, r)
    across = ports[1, :2] - ports[0, :2]
    g = across * (heights[1] - heights[0]) / float(across @ across)  # print height per mm in plan
    h0 = float(heights[0] - ports[0, :2] @ g)  # print height = h0 + p . g
    band = _clip(_clip(quad, -g, h0), g, height - h0)
    inside = _clip(_clip(band, np.array([sign[0], 0.0]), sign[0] * corner[0]), np.array([0.0, sign[1]]), sign[1] * corner[1])
    return _polygon_area(band) - _polygon_area(inside) if len(band) > 2 else 0.0


def _clip(poly, a: np.ndarray, b: float) -> list:
    """The part of a convex polygon where a . p <= b (Sutherland-Hodgman, one edge)."""
    out = []
    for i, p in enumerate(poly):
        q = poly[i - 1]
        fp, fq = float(a @ p) - b, float(a @ q) - b
        if fp <= 0:
            if fq > 0:
                out.append(q + (p - q) * fq / (fq - fp))
            out.append(p)
        elif fq <= 0:
            out.append(q + (p - q) * fq / (fq - fp))
    return out


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
        out.append((_t(p + t * d), _t(d)))
    return out


def _rods_fit(rods, rotation_deg: float, target) -> float:
    """Worst point + direction error of `rods` turned about z onto `target` (either pairing)."""
    turned = [(_rot_z(np.asarray(p, float), rotation_deg), _rot_z(np.asarray(d, float), rotation_deg)) for p, d in rods]

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
    placements = tuple(Placement(m.name, _mount_rotation(frame, m0, m), _t(m.axis)) for m in frame.motors)
    params = (("holes", holes), ("pattern", motor.holes), ("screw", screw.name), ("screw_clearance", screw.clearance_d),
              ("screw_length", length), ("grip", grip), ("engagement", engagement),
              ("counterbore_d", round(screw.head_d + 2 * HEAD_CLEAR, 4)),
              ("shaft_hole", motor.shaft_boss_d + 1.0), ("bell_d", motor.bell_d), ("seat_z", seat_z),
              ("arm_rods", tuple(rods_local)), ("arm_slope_deg", round(m0.arm_slope_deg, 4)), ("width", width),
              ("bore", round(spec.bore, 4)))
    hw = (HardwareLine(f"{screw.name} x {length:g} socket-head screw (motor to mount)", len(holes), screw.mass_of(length)),)
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


def _hexagon_area(length: float, width: float) -> float:
    """A window `length` long with 45 deg pointed ends across `width`: its area (mm^2)."""
    return length * width - width * width / 2


def holder_features(spec: Spec, frame: Frame) -> dict:
    """Holder windows, strap slots and lead exit in the holder's local frame (centre of its box), mm.

    Every opening prints without support with the holder standing on its back stop (local +y up):
    the lightening windows in the side walls and floor have 45 deg pointed ends along y, the strap
    slots run at 45 deg, and the lead exit is a notch in the top wall from the pack's front face to
    the mouth (open at the print's top). The lead leaves the pack's front, rises through the notch
    above the strap to the stack, and its plug stays at the front, clear of the flow sensor's view
    behind the holder; a swap unplugs it there.
    """
    c, b = spec.core, spec.core.battery
    h = frame.core.holder
    w, length, height = h.size
    t = c.holder_wall
    iw, ih = b.width, b.height + 1.0
    yb = -length / 2 + t  # cavity rear (inside face of the back stop)
    y_front_of_pack = yb + b.length
    ya, ye = yb + 4.0, y_front_of_pack - 4.0  # windows stay 4 mm clear of both ends of the pack
    side_h = ih - 5.0
    floor_w = iw - 8.0
    side = (ya, ye, side_h) if side_h >= 4.0 and ye - ya > side_h else None
    floor = (ya, ye, floor_w) if floor_w >= 4.0 and ye - ya > floor_w else None
    # Strap slot: 45 deg in the side wall, the strap's width + 1 mm long, 2 mm wide, just past the pack.
    s_len, s_w = c.strap_width + 1.0, 2.0
    ext = (s_len + s_w) / math.sqrt(2)
    strap = (y_front_of_pack + 1.0 + ext / 2, 0.0, s_len, s_w) if ext <= ih else None
    conn = CONNECTORS[b.connector]
    lead = (conn.width + 1.0, round(y_front_of_pack, 4))  # notch width, where it starts (to the mouth)
    return {"side_window": side, "floor_window": floor, "strap_slot": strap, "lead_exit": lead}


def _battery_holder(spec: Spec, frame: Frame) -> PartSpec:
    c, b = spec.core, spec.core.battery
    h = frame.core.holder
    w, length, height = h.size
    t = c.holder_wall
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    # Open-ended sleeve (floor, top, two side walls) with a back stop, printed standing on the back
    # stop: the outer box minus the battery cavity (open at the front) minus the stack holes in the
    # top, whose thickness is what the outer height leaves around the cavity (parts/core.py); minus
    # the lightening windows, the strap slots and the lead exit (holder_features).
    iw, il, ih = b.width, length - t, b.height + 1.0
    skin = (height - ih) / 2
    hy = h.centre[1]
    holes = tuple((sx * pitch / 2, sy * pitch / 2 - hy) for sx in (-1, 1) for sy in (-1, 1))
    f = holder_features(spec, frame)
    cut_side = 2 * _hexagon_area(f["side_window"][1] - f["side_window"][0], f["side_window"][2]) if f["side_window"] else 0.0
    cut_floor = _hexagon_area(f["floor_window"][1] - f["floor_window"][0], f["floor_window"][2]) if f["floor_window"] else 0.0
    cut_strap = 2 * f["strap_slot"][2] * f["strap_slot"][3] if f["strap_slot"] else 0.0
    cut_lead = f["lead_exit"][0] * (length / 2 - f["lead_exit"][1])  # notch in the top wall, over the mouth
    vol = (w * length * height - iw * il * ih - len(holes) * math.pi / 4 * screw.clearance_d**2 * skin
           - (cut_side + cut_strap) * t - cut_floor * skin - cut_lead * skin)
    # Walls are vertical when printed on end: outside and cavity faces; horizontal: the back stop
    # and the rim of the open end.
    area_v = 2 * (w + height) * length + 2 * (iw + ih) * il - 2 * (cut_side + cut_strap + cut_floor)
    rim = w * height - iw * ih
    area_h = w * height + rim - f["lead_exit"][0] * skin
    est = Estimate(vol, area_h, area_v, (w, height, length))
    params = (("inner", (b.width, il, b.height + 1.0)), ("wall", t), ("holes", holes), ("hole_d", screw.clearance_d),
              ("outer", (w, length, height)), *sorted(f.items()))
    # The strap runs across the mouth and round the holder's outside, closing on itself: the
    # holder's cross-section perimeter + 40 mm of overlap, rounded up to 10 mm; about 1 g per
    # 100 mm of 10 mm hook-and-loop.
    strap_len = math.ceil((2 * (w + height) + 40.0) / 10.0) * 10.0
    hw = (HardwareLine(f"hook-and-loop battery strap {c.strap_width:g} mm x {strap_len:g} mm", 1,
                       round(0.01 * strap_len * c.strap_width / 10.0, 2)),)
    return PartSpec("battery_holder", "battery_holder", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t(h.centre)),), (), t, est, params, hw)


ZIP_SLOT = (3.2, 1.8)  # zip-tie slot for 2.5 x 1.0 mm ties, mm


SPACER_RAIL = 7.0  # width of the spacer's diagonal rails, mm (carry the stack and link holes)
SPACER_NECK = 10.0  # width of the neck to the rear pad, mm


def _rect(p0, p1, width: float) -> tuple:
    d = np.subtract(p1, p0) / np.linalg.norm(np.subtract(p1, p0))
    n = np.array([-d[1], d[0]]) * width / 2
    return tuple(tuple(round(float(v), 4) for v in q) for q in (p0 - n, p1 - n, p1 + n, p0 + n))


def sensor_mount_outline(spec: Spec, frame: Frame) -> dict:
    """The sensor mount / spacer in its local frame (centre of the plate square, z = 0 its bottom): an X
    of two diagonal rails under the plate (the stack holes and the link bolts with their nut traps
    lie on the diagonals), a neck running back and a pad behind the holder (flow board underneath,
    zip-tie slots for the receiver, the antenna and the board). Each piece is a polygon (x, y)."""
    c = spec.core
    hole = _link_hole(spec)
    reach = hole + 3.5 / math.sqrt(2) + SPACER_RAIL / 2 / math.sqrt(2)
    rails = (_rect(np.array([-reach, -reach]), np.array([reach, reach]), SPACER_RAIL),
             _rect(np.array([reach, -reach]), np.array([-reach, reach]), SPACER_RAIL))
    rear = frame.core.holder.lo[1]
    flow = frame.core.flow_sensor
    if flow is not None:
        pad_half, pad_y0, pad_y1 = flow.size[0] / 2 + 3.0, rear - 1.5, flow.lo[1] - 2.0
    else:
        pad_half, pad_y0, pad_y1 = 10.0, rear - 1.5, rear - 12.0
    h = SPACER_NECK / 2
    neck = ((-h, pad_y0 - 1.0), (h, pad_y0 - 1.0), (h, 0.0), (-h, 0.0))
    pad = ((-pad_half, pad_y1), (pad_half, pad_y1), (pad_half, pad_y0), (-pad_half, pad_y0))
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    stack = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    links = tuple((sx * hole, sy * hole) for sx in (-1, 1) for sy in (-1, 1))
    yc = (pad_y0 + pad_y1) / 2
    sx_ = pad_half - 1.5 - ZIP_SLOT[1] / 2
    zips = ((-sx_, yc), (sx_, yc), (-3.5, pad_y1 + 2.5), (3.5, pad_y1 + 2.5))  # receiver + flow board; antenna
    pieces = tuple(tuple((round(float(x), 4), round(float(y), 4)) for x, y in poly) for poly in (*rails, neck, pad))
    area = 2 * SPACER_RAIL * 2 * reach * math.sqrt(2) - SPACER_RAIL**2 + SPACER_NECK * (-pad_y0 - SPACER_RAIL) + 2 * pad_half * (pad_y0 - pad_y1)
    return {"pieces": pieces, "stack_holes": stack, "link_holes": links,
            "zip_slots": tuple((round(x, 4), round(y, 4)) for x, y in zips), "pad": (pad_half, pad_y0, pad_y1), "area": area,
            "extent": (2 * max(reach + SPACER_RAIL / 2, pad_half), reach + SPACER_RAIL / 2 - pad_y1)}


def _polygon_area(pts) -> float:
    x = np.array([p[0] for p in pts])
    y = np.array([p[1] for p in pts])
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2)


def _polygon_perimeter(pts) -> float:
    p = np.asarray(pts, float)
    return float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).sum())


def _sensor_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    o = sensor_mount_outline(spec, frame)
    t = c.spacer_thickness
    screw = SCREWS[c.stack_screw]
    n_holes = len(o["stack_holes"]) + len(o["link_holes"])
    hole_a = math.pi / 4 * screw.clearance_d**2
    zip_a = ZIP_SLOT[0] * ZIP_SLOT[1]
    nut_a = math.sqrt(3) / 2 * (screw.nut_af + 0.4) ** 2
    area = o["area"] - n_holes * hole_a - len(o["zip_slots"]) * zip_a
    nut_depth = round(min(screw.d * 0.8 + 0.2, t - 0.6), 4)
    vol = area * t - len(o["link_holes"]) * (nut_a - hole_a) * nut_depth
    per = sum(_polygon_perimeter(p) for p in o["pieces"]) * 0.8 + n_holes * math.pi * screw.clearance_d + len(o["zip_slots"]) * 2 * sum(ZIP_SLOT)
    est = Estimate(vol, 2 * area, per * t, (o["extent"][0], o["extent"][1], t))
    box = frame.core.spacer
    name = "sensor_mount" if c.flow_sensor else "core_spacer"
    params = (("pieces", o["pieces"]), ("thickness", t), ("stack_holes", o["stack_holes"]), ("link_holes", o["link_holes"]),
              ("hole_d", screw.clearance_d), ("nut_af", screw.nut_af + 0.4), ("nut_depth", nut_depth),
              ("zip_slots", o["zip_slots"]), ("zip_slot", ZIP_SLOT))
    hw = (HardwareLine("zip tie 2.5 x 100 mm (receiver, antenna, flow board)", 2, 0.3),)
    return PartSpec(name, "sensor_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t((box.centre[0], box.centre[1], box.lo[2]))),), (), t, est, params, hw)


CAMERA_WALL = 1.6  # camera mount upright thickness, mm
CAMERA_SPINE = 3.0  # mm: the camera mount's base keeps at least this either side of its centre line up to the upright


def camera_mount_geometry(spec: Spec, frame: Frame) -> dict:
    """The camera bracket in its local frame (origin: plate top centre, axes as the frame): an L of a
    base plate under the FC stack and an upright at the plate's front edge, tilted back by tilt_deg
    about its bottom front edge. Printed on its side (local x up), so the L profile lies on the bed."""
    c = spec.core
    cb = BOARDS[c.camera.model]
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    width = cb.size[0]
    y_front = c.plate_size / 2
    y_back = -(pitch / 2 + 3.5)
    height = cb.size[1] + 2.0
    hx, hz = cb.holes[0] / 2, cb.holes[1]
    z_top = CAMERA_BASE_T + 1.0 + cb.size[1]  # camera board top edge (upright coordinates, untilted)
    cam_holes = tuple((sx * hx, round(z_top - 2.0 - dz, 4)) for sx in (-1, 1) for dz in (0.0, hz))
    stack = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    return {"width": width, "y_front": y_front, "y_back": y_back, "base_t": CAMERA_BASE_T, "wall": CAMERA_WALL,
            "height": height, "tilt_deg": c.camera.tilt_deg, "camera_holes": cam_holes, "camera_hole_d": cb.hole_d,
            "stack_holes": stack, "stack_hole_d": SCREWS[c.stack_screw].clearance_d,
            # the base's front corners are cut along |x| + y = corner_cut, clear of the core links' bolt tabs
            "corner_cut": round(2 * _link_hole(spec) - 7.0, 4)}


def _camera_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    g = camera_mount_geometry(spec, frame)
    screw = SCREWS[c.stack_screw]
    w, yf, yb, bt, wall, height = g["width"], g["y_front"], g["y_back"], g["base_t"], g["wall"], g["height"]
    k = g["corner_cut"] - (yf - wall)  # where each front corner cut (behind the upright) meets the upright's back face, |x|
    x0 = max(k, CAMERA_SPINE)  # never nearer the centre line (parts/core.py)
    corner = (max(0.0, w / 2 - k) ** 2 - max(0.0, min(x0, w / 2) - k) ** 2) / 2  # area of each corner cut off the base
    bw, hy = min(w / 2 - 4.0, 6.0), min(5.0, (yf - yb) / 2 - 8.0)
    base_win = _hexagon_area(2 * bw, 2 * hy) if bw > 2.0 and hy > 1.0 and bw >= hy else 0.0
    up_win = _hexagon_area(height - 12.0, 10.0) if height - 6.0 > 10.0 and abs(g["tilt_deg"]) <= 5.0 else 0.0
    base_a = w * (yf - yb) - 2 * corner - base_win - 4 * math.pi / 4 * screw.clearance_d**2
    up_a = w * height - up_win - 4 * math.pi / 4 * g["camera_hole_d"] ** 2
    vol = base_a * bt + up_a * wall
    # printed as it sits: the base's faces are horizontal, the upright's vertical
    area_v = 2 * up_a + 2 * (w + yf - yb) * bt
    est = Estimate(vol, 2 * base_a + w * wall, area_v, (w, yf - yb, height + bt))
    origin = (0.0, 0.0, frame.core.plate.hi[2])
    params = tuple((k, v) for k, v in g.items())
    hw = (HardwareLine("M2 x 6 screw + nut (camera to mount)", 4, SCREWS["M2"].mass_g + 0.1),)
    # not "camera_...": trimesh 5.2's 3MF export drops every scene node whose name starts with "camera"
    return PartSpec("front_camera_mount", "camera_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, _t(origin)),), (), g["wall"], est, params, hw)


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


def infill_by_material(parts) -> dict[str, float]:
    """The infill each material prints at (the slicer profile is per material): the densest of its
    parts' (the joints and motor mounts solid, the core parts at `core.infill`)."""
    out: dict[str, float] = {}
    for p in parts:
        out[p.material] = max(out.get(p.material, 0.0), p.infill)
    return dict(sorted(out.items()))


def _with_digest(p: PartSpec) -> PartSpec:
    payload = json.dumps([p.name, p.family, p.material, p.infill, [s.__dict__ for s in p.sockets], p.wall,
                          [list(map(str, kv)) for kv in p.params]], sort_keys=True, default=str)
    return replace(p, digest=hashlib.sha256(payload.encode()).hexdigest()[:16])

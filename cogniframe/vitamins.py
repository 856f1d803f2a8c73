"""Vitamins (NopSCADlib's word for bought parts): what flies on the frame, as simple but
dimensionally honest solids placed where they go.

Pure numpy: each vitamin is a list of primitives (boxes and cylinders in world coordinates, mm)
built from the data tables in `materials.py` (BOARDS, MOTOR_PRESETS, CONNECTORS) and the frame
graph's core boxes. `export/assembly.py` turns them into named, coloured STEP/GLB solids;
`analysis/clash.py` tests them against the printed parts and rods; `report/renders.py` draws them.

Masses: every vitamin names its line of the mass budget (`budget_line`): the motor and propeller
lines, the battery line, or the params' `components:` line whose `vitamin:` key names it. The
vitamin's own mass is that line's, so nothing is counted twice; the table's catalogue mass is
shown in the BOM only.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .frame import STACK_BOTTOM, Frame
from .materials import BOARDS, CONNECTORS, PROPS, STACK_PATTERNS, Board
from .numfmt import norm
from .spec import Spec

# Propeller disc: the volume the blades sweep, from the top of the motor bell (materials.PROPS
# gives each propeller's swept height; this is the fallback). A 2.5 in pitch blade at 75 % radius
# stands about 3 mm tall; the hub sits inside this slab.
PROP_DISC_T = 3.0  # mm
PROP_GAP = 0.5  # bell top to the underside of the blade disc, mm
SHAFT_D = 1.5  # motor shaft diameter (mm): 1.5 mm on the 11xx-15xx classes
SHAFT_ABOVE = 2.5  # shaft length above the bell (into the prop hub), mm
STANDOFF_D = 4.0  # nylon M2 grommet under the ESC across flats (drawn round), mm

COLOURS = {
    "motor": (0.62, 0.62, 0.66),
    "propeller": (0.55, 0.75, 0.95),
    "battery": (0.95, 0.78, 0.10),
    "fc": (0.10, 0.15, 0.45),
    "esc": (0.12, 0.12, 0.12),
    "computer": (0.10, 0.45, 0.20),
    "camera": (0.10, 0.55, 0.25),
    "flow_sensor": (0.40, 0.10, 0.50),
    "screw": (0.20, 0.20, 0.22),
    "nut": (0.75, 0.75, 0.78),
    "standoff": (0.93, 0.93, 0.88),  # white nylon
}


@dataclass(frozen=True)
class Prim:
    """A box (`size` x, y, z about `centre`, turned by `rot`) or a cylinder (`centre` = base centre,
    `axis` unit vector, `radius`, `length`). World coordinates, mm."""

    kind: str  # "box" | "cyl"
    centre: tuple[float, float, float]
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rot: tuple[tuple[float, float, float], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    radius: float = 0.0
    length: float = 0.0
    radius_end: float | None = None  # a cone: the radius at the far end (a countersunk head); None: a cylinder


@dataclass(frozen=True)
class Vitamin:
    name: str  # assembly name: motor_fl, propeller_fl, battery, flight_controller ...
    family: str  # motor | propeller | battery | fc | esc | computer | camera | flow_sensor | screw | nut | standoff
    bom: str  # the data table's description (what to buy)
    budget_line: str  # the mass budget item this vitamin's mass is in
    prims: tuple[Prim, ...]
    colour: tuple[float, float, float]
    disc: tuple[tuple[float, float, float], float, float] | None = None  # propeller: (centre, radius, thickness)
    view: tuple[tuple[float, float, float], tuple[float, float, float], float] | None = None  # sensor: (apex, direction, half-angle deg)
    stage: str = ""  # when it is fitted (fasteners.STAGES); "" = by its family (fasteners.VITAMIN_STAGES)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        pts = np.vstack([_prim_corners(p) for p in self.prims])
        return pts.min(axis=0), pts.max(axis=0)


def _t(v) -> tuple[float, float, float]:
    return (round(float(v[0]), 6), round(float(v[1]), 6), round(float(v[2]), 6))


def box(lo, hi) -> Prim:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return Prim("box", _t((lo + hi) / 2), _t(hi - lo))


def cyl(base, axis, radius: float, length: float, radius_end: float | None = None) -> Prim:
    a = np.asarray(axis, float)
    # a check draws ~100 of these for the mass properties: numfmt.norm, np.linalg.norm's bits
    return Prim("cyl", _t(base), axis=_t(a / norm(a)), radius=float(radius), length=float(length),
                radius_end=None if radius_end is None else float(radius_end))


def _prim_corners(p: Prim) -> np.ndarray:
    if p.kind == "box":
        s = np.asarray(p.size) / 2
        corners = np.array([[sx, sy, sz] for sx in (-s[0], s[0]) for sy in (-s[1], s[1]) for sz in (-s[2], s[2])])
        return corners @ np.asarray(p.rot).T + np.asarray(p.centre)
    a = np.asarray(p.axis)
    ends = np.array([p.centre, np.asarray(p.centre) + a * p.length])
    return np.vstack([ends - p.radius, ends + p.radius])


def _transform_prims(prims, m: np.ndarray) -> tuple[Prim, ...]:
    """Move primitives given in a local frame by the 4x4 world <- local `m`."""
    r, t = m[:3, :3], m[:3, 3]
    out = []
    for p in prims:
        if p.kind == "box":
            rot = r @ np.asarray(p.rot)
            out.append(Prim("box", _t(r @ np.asarray(p.centre) + t), p.size, tuple(_t(row) for row in rot)))
        else:
            out.append(Prim("cyl", _t(r @ np.asarray(p.centre) + t), axis=_t(r @ np.asarray(p.axis)), radius=p.radius, length=p.length,
                            radius_end=p.radius_end))
    return tuple(out)


# -- the families ------------------------------------------------------------------------------

def _budget_lines(spec: Spec) -> dict[str, str]:
    """vitamin key -> the components line that carries its mass."""
    return {c.vitamin: c.name for c in spec.components if c.vitamin}


def motor_vitamins(spec: Spec, frame: Frame) -> list[Vitamin]:
    """Each motor: stator base (the mounting foot), bell and shaft; its propeller disc above it."""
    m = spec.motor
    out = []
    shaft = SHAFT_D
    for mo in frame.motors:
        x, y, _ = mo.axis
        z0 = mo.seat_z
        base_h = 2.0
        prims = (cyl((x, y, z0), (0, 0, 1), m.bell_d * 0.4, base_h),  # stator base / mounting foot
                 cyl((x, y, z0 + base_h), (0, 0, 1), m.bell_d / 2, m.height - base_h),  # bell over the stator
                 cyl((x, y, z0 + m.height), (0, 0, 1), shaft / 2, PROP_GAP + SHAFT_ABOVE))
        out.append(Vitamin(f"motor_{mo.corner}", "motor", f"brushless motor {m.name} {_kv(spec)}KV ({m.pattern} {m.screw} across the shaft)",
                           f"motor {m.name}", prims, COLOURS["motor"]))
        r = spec.motors.prop_diameter / 2
        zc = mo.prop_z + PROP_GAP
        prop = PROPS.get(_prop(spec))
        t = prop.swept_height_mm if prop else PROP_DISC_T
        bom = f"{prop.bom}, {spec.motors.prop_diameter:g} mm" if prop else f"propeller {spec.motors.prop_diameter:g} mm"
        out.append(Vitamin(f"propeller_{mo.corner}", "propeller", bom,
                           f"propeller {spec.motors.prop_diameter:g} mm", (cyl((x, y, zc), (0, 0, 1), r, t),),
                           COLOURS["propeller"], disc=(_t((x, y, zc + t / 2)), r, t)))
    return out


def _kv(spec: Spec) -> str:
    return f"{spec.motors.kv}" if spec.motors.kv else "?"


def _prop(spec: Spec) -> str:
    """motors.prop, or the table propeller nearest motors.prop_diameter (as analysis/flight.py)."""
    if spec.motors.prop:
        return spec.motors.prop
    return min(PROPS.values(), key=lambda p: abs(p.diameter_mm - spec.motors.prop_diameter)).name


def battery_vitamin(spec: Spec, frame: Frame) -> Vitamin:
    b, box_ = spec.core.battery, frame.core.battery
    conn = CONNECTORS[b.connector]
    return Vitamin("battery", "battery", f"LiPo {b.cells}S {b.capacity_mah:g} mAh, {b.length:g} x {b.width:g} x {b.height:g} mm, {conn.name} lead",
                   "battery", (box(box_.lo, box_.hi),), COLOURS["battery"])


def _board_prims(board: Board, lo_z: float, centre_xy, parts_down: bool = False) -> list[Prim]:
    """A board lying flat with its bottom at lo_z (or its top at lo_z when parts face down)."""
    x, y = centre_xy
    bx, by, bt = board.size
    px, py, ph = board.parts_block
    if parts_down:
        return [box((x - bx / 2, y - by / 2, lo_z - bt), (x + bx / 2, y + by / 2, lo_z)),
                box((x - px / 2, y - py / 2, lo_z - bt - ph), (x + px / 2, y + py / 2, lo_z - bt))]
    return [box((x - bx / 2, y - by / 2, lo_z), (x + bx / 2, y + by / 2, lo_z + bt)),
            box((x - px / 2, y - py / 2, lo_z + bt), (x + px / 2, y + py / 2, lo_z + bt + ph))]


def stack_vitamins(spec: Spec, frame: Frame) -> list[Vitamin]:
    """FC and 4-in-1 ESC on the stack pattern: grommets, ESC, FC (bottom up); the nylon spacers
    between them are fasteners (families/core_plate.stack_plan)."""
    from .families.core_plate import STACK_SPACER

    lines = _budget_lines(spec)
    pitch, _ = STACK_PATTERNS[spec.core.stack_pattern]
    key = "20x20" if pitch < 25 else "30x30"
    esc_b, fc_b = BOARDS[f"esc_{key}"], BOARDS[f"fc_{key}"]
    z0 = float(frame.core.stack.lo[2])
    holes = [(sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1)]
    grommets = [cyl((x, y, z0), (0, 0, 1), STANDOFF_D / 2, STACK_BOTTOM) for x, y in holes]
    z_esc = z0 + STACK_BOTTOM
    esc = _board_prims(esc_b, z_esc, (0.0, 0.0))
    fc = _board_prims(fc_b, z_esc + esc_b.size[2] + STACK_SPACER, (0.0, 0.0))
    if "fc_esc_stack" in lines:
        return [Vitamin("fc_esc_stack", "fc", f"{fc_b.bom} + {esc_b.bom}", lines["fc_esc_stack"],
                        tuple(grommets + esc + fc), COLOURS["fc"])]
    out = []
    if "esc" in lines:
        out.append(Vitamin("esc", "esc", esc_b.bom, lines["esc"], tuple(grommets + esc), COLOURS["esc"]))
    if "fc" in lines:
        out.append(Vitamin("flight_controller", "fc", fc_b.bom, lines["fc"], tuple(fc), COLOURS["fc"]))
    return out


def computer_vitamin(spec: Spec, frame: Frame) -> Vitamin | None:
    lines = _budget_lines(spec)
    if frame.core.computer is None or "pi_zero" not in lines:
        return None
    b = BOARDS["pi_zero"]
    c = frame.core.computer
    return Vitamin("computer", "computer", b.bom, lines["pi_zero"], tuple(_board_prims(b, float(c.lo[2]), c.centre[:2])),
                   COLOURS["computer"])


def camera_vitamin(spec: Spec, frame: Frame) -> Vitamin | None:
    """The camera board on the camera mount's upright, lens forward, tilted with the upright."""
    from .families.camera_mount import camera_mount_geometry
    from .fasteners import camera_world

    if spec.core.camera is None:
        return None
    lines = _budget_lines(spec)
    b = BOARDS[spec.core.camera.model]
    g = camera_mount_geometry(spec, frame)
    bx, by, bt = b.size
    # upright frame: x across, y forward (lens), z up the upright from the base top
    lens_d, lens_h = b.lens or (8.5, 5.0)
    z_lens = 1.0 + by - 9.5  # lens centre 9.5 mm below the board's top edge
    local = [box((-bx / 2, 0.0, 1.0), (bx / 2, bt, 1.0 + by)),
             box((-lens_d / 2, bt, z_lens - lens_d / 2), (lens_d / 2, bt + lens_h, z_lens + lens_d / 2))]
    m = camera_world(frame, g)
    prims = _transform_prims(local, m)
    axis = m[:3, :3] @ np.array([0.0, 1.0, 0.0])
    apex = m[:3, :3] @ np.array([0.0, bt + lens_h, z_lens]) + m[:3, 3]
    return Vitamin("camera", "camera", b.bom, lines[spec.core.camera.model], prims, COLOURS["camera"],
                   view=(_t(apex), _t(axis), 31.0))  # Pi camera v2: 62.2 x 48.8 deg field of view


def flow_vitamin(spec: Spec, frame: Frame) -> Vitamin | None:
    """The flow/ToF board under the sensor mount's rear pad, sensors facing the ground."""
    if spec.core.flow_sensor is None or frame.core.flow_sensor is None:
        return None
    lines = _budget_lines(spec)
    b = BOARDS[spec.core.flow_sensor.model]
    box_ = frame.core.flow_sensor
    top = float(box_.hi[2])
    prims = tuple(_board_prims(b, top, box_.centre[:2], parts_down=True))
    apex = (box_.centre[0], box_.centre[1], top - b.size[2] - b.parts_block[2])
    return Vitamin("flow_sensor", "flow_sensor", b.bom, lines[spec.core.flow_sensor.model], prims, COLOURS["flow_sensor"],
                   view=(_t(apex), (0.0, 0.0, -1.0), 21.0))  # PMW3901: 42 deg field of view


def fastener_vitamins(spec: Spec, frame: Frame, parts=None, fasteners=None) -> list[Vitamin]:
    """Every screw, nut and standoff of the design (fasteners.py), drawn (`fastener_vitamin`);
    `fasteners`: `fasteners.fasteners` of the design when the caller has it."""
    if fasteners is None:
        from .fasteners import fasteners as fasteners_of

        if parts is None:
            from . import partlist

            parts = partlist.part_list(spec, frame)
        fasteners = fasteners_of(spec, frame, parts)
    return [fastener_vitamin(f) for f in fasteners]


def fastener_vitamin(f) -> Vitamin:
    """A screw as its head and its shank (the nominal diameter): a socket head (ISO 4762 head
    diameter and height) on the part's face behind `base`, a countersunk head (ISO 7046, a 90 deg
    cone) inside the part ahead of it; a nut as a cylinder across its flats; a standoff or spacer
    as a cylinder across its hex's flats."""
    from .materials import COUNTERSUNK, SCREWS

    sc = SCREWS[f.size]
    base, axis = np.asarray(f.base), np.asarray(f.axis)
    if f.kind == "screw" and f.head == "countersunk":
        dk, _ = COUNTERSUNK[f.size]
        prims = (cyl(base, axis, dk / 2, (dk - sc.d) / 2, sc.d / 2), cyl(base, axis, sc.d / 2, f.length))
    elif f.kind == "screw":
        prims = (cyl(base - axis * sc.head_h, axis, sc.head_d / 2, sc.head_h), cyl(base, axis, sc.d / 2, f.length))
    else:  # a nut, a standoff: across the flats of its hex
        prims = (cyl(base, axis, sc.nut_af / 2, f.length),)
    return Vitamin(f.name, f.kind, f.bom, f.budget_line, prims, COLOURS[f.kind], stage=f.stage)


def thread_pairs(spec: Spec, frame: Frame, parts=None) -> frozenset:
    """Each screw and the bought part it threads into (its motor, its nut), and each screw and the
    board it passes through by the board's mounting hole (the boards are drawn without holes):
    they share that volume by design, so the clash check does not test those pairs."""
    from .fasteners import fasteners

    if parts is None:
        from . import partlist

        parts = partlist.part_list(spec, frame)
    out = set()
    for f in fasteners(spec, frame, parts):
        if f.thread:
            out.add(frozenset((f.name, f.thread)))
        out.update(frozenset((f.name, b)) for b in f.boards)
    return frozenset(out)


def vitamins(spec: Spec, frame: Frame, parts=None, fasteners=None) -> tuple[Vitamin, ...]:
    """Every bought part drawn in the assembly, in a stable order; `parts`: the design's part list
    when the caller has it (the screws sit in its holes), else made here; `fasteners`: its
    `fasteners.fasteners` when the caller has them."""
    out = motor_vitamins(spec, frame)
    out.append(battery_vitamin(spec, frame))
    out += stack_vitamins(spec, frame)
    for v in (computer_vitamin(spec, frame), camera_vitamin(spec, frame), flow_vitamin(spec, frame)):
        if v is not None:
            out.append(v)
    out += fastener_vitamins(spec, frame, parts, fasteners)
    return tuple(out)


# -- meshes and CAD ----------------------------------------------------------------------------

def _prims_manifold(prims: tuple[Prim, ...], segments: int):
    import manifold3d as m3

    parts = []
    for p in prims:
        if p.kind == "box":
            s = m3.Manifold.cube(tuple(float(x) for x in p.size), True)
            mat = np.zeros((3, 4))
            mat[:, :3] = np.asarray(p.rot)
            mat[:, 3] = p.centre
            parts.append(s.transform(mat))
        else:
            r_end = p.radius if p.radius_end is None else p.radius_end
            s = m3.Manifold.cylinder(float(p.length), float(p.radius), float(r_end), segments)
            mat = np.zeros((3, 4))
            mat[:, :3] = _frame_z(np.asarray(p.axis))
            mat[:, 3] = p.centre
            parts.append(s.transform(mat))
    return m3.Manifold.batch_boolean(parts, m3.OpType.Add) if len(parts) > 1 else parts[0]


def mesh_arrays(v: Vitamin, segments: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """The vitamin's solid as (vertices, faces) arrays (read-only: they are shared), made once per
    process for the same primitives: the GLB, the renders and the report's 3D view all draw the
    vitamins, each used to union their primitives again (manifold3d)."""
    return _prims_arrays(v.prims, segments)


@functools.lru_cache(maxsize=256)
def _prims_arrays(prims: tuple[Prim, ...], segments: int) -> tuple[np.ndarray, np.ndarray]:
    mesh = _prims_manifold(prims, segments).to_mesh()
    verts = np.array(np.asarray(mesh.vert_properties)[:, :3], float)
    faces = np.array(mesh.tri_verts, np.int64)
    verts.flags.writeable = False
    faces.flags.writeable = False
    return verts, faces


def to_trimesh(v: Vitamin, segments: int = 48):
    import trimesh

    verts, faces = mesh_arrays(v, segments)
    return trimesh.Trimesh(verts.copy(), faces.copy(), process=True)


def to_cq(v: Vitamin):
    """The vitamin as one CadQuery compound (its primitives), for the assembly STEP/GLB."""
    import cadquery as cq

    solids = []
    for p in v.prims:
        if p.kind == "box":
            s = cq.Solid.makeBox(*p.size, cq.Vector(*(-np.asarray(p.size) / 2)))
            m = np.eye(4)
            m[:3, :3] = np.asarray(p.rot)
            m[:3, 3] = p.centre
            from .parts.joint_solid import apply

            solids.append(apply(s, m))
        elif p.radius_end is not None:
            solids.append(cq.Solid.makeCone(p.radius, p.radius_end, p.length, cq.Vector(*p.centre), cq.Vector(*p.axis)))
        else:
            solids.append(cq.Solid.makeCylinder(p.radius, p.length, cq.Vector(*p.centre), cq.Vector(*p.axis)))
    if len(solids) == 1:
        return solids[0]
    # one fused solid: a compound's colour does not survive the STEP round trip
    fused = solids[0].fuse(*solids[1:]).clean()
    parts = fused.Solids()
    return parts[0] if len(parts) == 1 else cq.Compound.makeCompound(parts)


def _frame_z(z: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector z."""
    z = z / np.linalg.norm(z)
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def bom_rows(spec: Spec, frame: Frame) -> list[tuple[str, int, str]]:
    """(what to buy, qty, the budget line its mass is in), grouped by description."""
    rows: dict[tuple[str, str], int] = {}
    for v in vitamins(spec, frame):
        rows[(v.bom, v.budget_line)] = rows.get((v.bom, v.budget_line), 0) + 1
    return [(bom, qty, line) for (bom, line), qty in rows.items()]

"""The sensor mount / core spacer (ABS/PLA): an X of two rails between the battery holder and
the core plate, with a neck back to a pad for the flow board and zip-tie slots, printed flat as it
sits (its local origin: the plate square's centre, z = 0 its bottom). Named core_spacer when the
design has no flow sensor. With pegs the plate hangs on standoffs and no link bolt needs a nut
trap: the X shrinks to a bar under the two rear standoffs with the pad (`rear_only`).
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts.blocks import prism_xy
from ..parts.joint_solid import Built
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import polygon_perimeter, rounded
from .joint_kinds.kinds import core_link

NAME = "sensor_mount"
SIZE_KEY = "core.spacer_thickness"
DOC = "ABS/PLA X spacer between holder and plate, with the flow board pad and zip-tie slots, printed flat"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_sensor_mount(spec, frame),) if frame.core.spacer is not None else ()

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
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    bar = rear_only(spec)
    bolts = core_link(spec).plate_bolts(spec)  # the links' (none with pegs, pressed into the plate's tubes)
    if bar:
        # one bar through the two rear stack holes, as far past them as the X's rails reach
        # past theirs
        reach = pitch / 2 + 3.5
        rails = (_rect(np.array([-reach, -pitch / 2]), np.array([reach, -pitch / 2]), SPACER_RAIL),)
    else:
        # the rails run out past the outermost holes on the diagonals: the links' bolts, or
        # without (pegs, pressed into the plate's tubes) the stack's
        hole = max(abs(x) for x, _ in bolts) if bolts else pitch / 2
        reach = hole + 3.5 / math.sqrt(2) + SPACER_RAIL / 2 / math.sqrt(2)
        rails = (_rect(np.array([-reach, -reach]), np.array([reach, reach]), SPACER_RAIL),
                 _rect(np.array([reach, -reach]), np.array([-reach, reach]), SPACER_RAIL))
    rear = frame.core.holder.lo[1]
    flow = frame.core.flow_sensor
    if flow is not None:
        pad_half, pad_y0, pad_y1 = flow.size[0] / 2 + 3.0, rear - 1.5, flow.lo[1] - 2.0
    elif bar:  # the receiver's pad right behind the bar, on the holder (no flow board to see past it)
        pad_half, pad_y0 = 10.0, -pitch / 2 - SPACER_RAIL / 2
        pad_y1 = pad_y0 - 10.5
    else:
        pad_half, pad_y0, pad_y1 = 10.0, rear - 1.5, rear - 12.0
    h = SPACER_NECK / 2
    neck_y = -pitch / 2 if bar else 0.0
    neck = ((-h, pad_y0 - 1.0), (h, pad_y0 - 1.0), (h, neck_y), (-h, neck_y))
    pad = ((-pad_half, pad_y1), (pad_half, pad_y1), (pad_half, pad_y0), (-pad_half, pad_y0))
    stack = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in ((-1,) if bar else (-1, 1)))
    links = tuple(bolts)
    yc = (pad_y0 + pad_y1) / 2
    sx_ = pad_half - 1.5 - ZIP_SLOT[1] / 2
    zips = ((-sx_, yc), (sx_, yc), (-3.5, pad_y1 + 2.5), (3.5, pad_y1 + 2.5))  # receiver + flow board; antenna
    if bar:  # a short holder: the pad reaches up to the bar, no further
        pad_y0 = min(pad_y0, -pitch / 2 - SPACER_RAIL / 2)
        pad = ((-pad_half, pad_y1), (pad_half, pad_y1), (pad_half, pad_y0), (-pad_half, pad_y0))
    neck_len = (-pitch / 2 - SPACER_RAIL / 2 - pad_y0) if bar else 0.0
    pieces = tuple(tuple((round(float(x), 4), round(float(y), 4)) for x, y in poly)
                   for poly in (*rails, *((neck,) if not bar or neck_len > 0 else ()), pad))
    if bar:
        area = 2 * reach * SPACER_RAIL + SPACER_NECK * neck_len + 2 * pad_half * (pad_y0 - pad_y1)
        extent = (2 * max(reach, pad_half), -pitch / 2 + SPACER_RAIL / 2 - pad_y1)
    else:
        area = 2 * SPACER_RAIL * 2 * reach * math.sqrt(2) - SPACER_RAIL**2 + SPACER_NECK * (-pad_y0 - SPACER_RAIL) + 2 * pad_half * (pad_y0 - pad_y1)
        extent = (2 * max(reach + SPACER_RAIL / 2, pad_half), reach + SPACER_RAIL / 2 - pad_y1)
    return {"pieces": pieces, "stack_holes": stack, "link_holes": links,
            "zip_slots": tuple((round(x, 4), round(y, 4)) for x, y in zips), "pad": (pad_half, pad_y0, pad_y1), "area": area,
            "extent": extent}


def rear_only(spec: Spec) -> bool:
    """Whether the sensor mount / spacer is a bar under the two rear stack standoffs only, with its
    pad (behind the holder on a neck for a flow board, else on the holder for the receiver): with
    pegs (level arms, no link bolt) the pad is all it carries, and the front standoffs stand on the
    holder, the spacer's thickness longer (whole millimetres: the standoffs' steps; else the X
    under all four)."""
    c = spec.core
    return not core_link(spec).plate_bolts(spec) and float(c.spacer_thickness).is_integer()


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
    per = sum(polygon_perimeter(p) for p in o["pieces"]) * 0.8 + n_holes * math.pi * screw.clearance_d + len(o["zip_slots"]) * 2 * sum(ZIP_SLOT)
    est = Estimate(vol, 2 * area, per * t, (o["extent"][0], o["extent"][1], t))
    box = frame.core.spacer
    name = "sensor_mount" if c.flow_sensor else "core_spacer"
    params = (("pieces", o["pieces"]), ("thickness", t), ("stack_holes", o["stack_holes"]), ("link_holes", o["link_holes"]),
              ("hole_d", screw.clearance_d), ("nut_af", screw.nut_af + 0.4), ("nut_depth", nut_depth),
              ("zip_slots", o["zip_slots"]), ("zip_slot", ZIP_SLOT))
    hw = (HardwareLine("zip tie 2.5 x 100 mm (receiver, antenna, flow board)", 2, 0.3),)
    return PartSpec(name, "sensor_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded((box.centre[0], box.centre[1], box.lo[2]))),), (), t, est, params, hw)



# -- the assembly's words ------------------------------------------------------------------

def fitting(spec: Spec) -> str:
    """How the builder fits the flow sensor and the receiver on the sensor mount."""
    return ("Zip-tie the Matek 3901-L0X under the sensor mount's rear pad, sensors facing the ground (the pad sits "
            "behind the battery holder, so nothing is in their view), with the receiver on top of the pad in the same "
            "two ties; tie the antenna leads through the two slots at the pad's rear edge.")

# -- the solid --------------------------------------------------------------------------------

def solid(part: PartSpec) -> Built:
    """The X-shaped spacer with its neck and rear pad, printed flat as it sits; link-bolt nut traps
    open on the bed side (their roofs are 4.4 mm bridges)."""
    import cadquery as cq

    t = float(part.param("thickness"))
    first, *rest = (prism_xy(poly, 0.0, t) for poly in part.param("pieces"))
    body = first.fuse(*rest) if rest else first
    d = float(part.param("hole_d"))
    cut = [cq.Solid.makeCylinder(d / 2, t + 2.0, cq.Vector(float(x), float(y), -1.0)) for x, y in
           (*part.param("stack_holes"), *part.param("link_holes"))]
    af, nd = float(part.param("nut_af")), float(part.param("nut_depth"))
    for x, y in part.param("link_holes"):
        hexagon = cq.Workplane("XY", origin=(float(x), float(y), -1.0)).polygon(6, af / np.cos(np.pi / 6)).extrude(nd + 1.0).val()
        cut.append(hexagon)
    zw, zl = (float(v) for v in part.param("zip_slot"))
    for x, y in part.param("zip_slots"):
        cut.append(cq.Solid.makeBox(zl, zw, t + 2.0, cq.Vector(float(x) - zl / 2, float(y) - zw / 2, -1.0)))
    body = body.cut(*cut)  # one boolean with all 16 tools: 0.09 s instead of 0.17 s one by one
    solids = body.clean().Solids()
    if len(solids) != 1:
        raise RuntimeError(f"{part.name} geometry produced {len(solids)} solids instead of 1")
    return Built(solids[0], transform(np.eye(3), (0.0, 0.0, 0.0)))


def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, 0.0))

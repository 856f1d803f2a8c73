"""The front camera's bracket (ABS/PLA): an L of a base frame under the FC stack and an upright at
the plate's front edge, tilted back by core.camera.tilt_deg; its local origin is the plate top's
centre, axes as the frame. Printed as it sits. The base is open between the stack holes and the
upright is two stiles carrying the camera's holes with a slot between them, open at the top: the
authors hold the camera on two small brackets (`CameraConnectorLeft`/`Right`), each a stile with
two of the camera's holes, and the board itself ties the stiles.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import CAMERA_BASE_T, Frame
from ..materials import BOARDS, SCREWS, STACK_PATTERNS
from ..parts.blocks import prism_xy
from ..parts.joint_solid import Built, apply
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import link_hole, rounded
from .computer_mount import BEARING_WALL, RAIL, bar_half_width

NAME = "camera_mount"
SIZE_KEY = "core.camera"
DOC = "ABS/PLA camera bracket (open base under the FC stack, tilted two-stile upright), printed as it sits"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_camera_mount(spec, frame),) if spec.core.camera else ()

CAMERA_WALL = 1.6  # camera mount upright thickness, mm
CAMERA_SPINE = 3.0  # mm: the camera mount's base keeps at least this either side of its centre line up to the upright
MIN_OPENING = 2.0  # mm: a narrower window or slot stays closed


def camera_mount_geometry(spec: Spec, frame: Frame) -> dict:
    """The camera bracket in its local frame (origin: plate top centre, axes as the frame): an L of a
    base under the FC stack and an upright at the plate's front edge, tilted back by tilt_deg about
    its bottom front edge. `base_window` (x0, y0, x1, y1) is the base's opening between the stack
    holes, `slot` the half width of the upright's opening between its stiles (0: none)."""
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
    corner_cut = round(2 * link_hole(spec) - 7.0, 4)
    # the base's window: inside the stack holes' bosses (a nut or head bears round each), a rail
    # from the base's sides, its back edge, the upright and the front corner cuts (|x| + y = corner_cut)
    inner = pitch / 2 - bar_half_width(c.stack_screw, spec.printer.nozzle)
    xw = min(inner, width / 2 - RAIL)
    y0 = max(-inner, y_back + RAIL)
    y1 = min(inner, y_front - CAMERA_WALL - RAIL, corner_cut - RAIL * math.sqrt(2) - xw)
    window = (round(-xw, 4), round(y0, 4), round(xw, 4), round(y1, 4)) if min(2 * xw, y1 - y0) >= MIN_OPENING else None
    # the upright's slot: between the camera holes' stiles, each as wide as the nut behind the
    # board (or the screw head) needs plus two perimeters
    sm = SCREWS["M2"]
    slot = hx - max(sm.head_d, sm.nut_af) / 2 - max(BEARING_WALL, 2 * spec.printer.nozzle)
    return {"width": width, "y_front": y_front, "y_back": y_back, "base_t": CAMERA_BASE_T, "wall": CAMERA_WALL,
            "height": height, "tilt_deg": c.camera.tilt_deg, "camera_holes": cam_holes, "camera_hole_d": cb.hole_d,
            "stack_holes": stack, "stack_hole_d": SCREWS[c.stack_screw].clearance_d,
            # the base's front corners are cut along |x| + y = corner_cut, clear of the core links' bolt tabs
            "corner_cut": corner_cut, "base_window": window, "slot": round(slot, 4) if 2 * slot >= MIN_OPENING else 0.0}


def _camera_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    g = camera_mount_geometry(spec, frame)
    screw = SCREWS[c.stack_screw]
    w, yf, yb, bt, wall, height = g["width"], g["y_front"], g["y_back"], g["base_t"], g["wall"], g["height"]
    k = g["corner_cut"] - (yf - wall)  # where each front corner cut (behind the upright) meets the upright's back face, |x|
    x0 = max(k, CAMERA_SPINE)  # never nearer the centre line (as `solid` cuts it)
    corner = (max(0.0, w / 2 - k) ** 2 - max(0.0, min(x0, w / 2) - k) ** 2) / 2  # area of each corner cut off the base
    bwin = g["base_window"]
    base_win = (bwin[2] - bwin[0]) * (bwin[3] - bwin[1]) if bwin else 0.0
    up_win = 2 * g["slot"] * height
    base_a = w * (yf - yb) - 2 * corner - base_win - 4 * math.pi / 4 * screw.clearance_d**2
    up_a = w * height - up_win - 4 * math.pi / 4 * g["camera_hole_d"] ** 2
    vol = base_a * bt + up_a * wall
    # printed as it sits: the base's faces are horizontal, the upright's vertical
    area_v = 2 * up_a + 2 * (w + yf - yb) * bt
    if bwin:
        area_v += 2 * (bwin[2] - bwin[0] + bwin[3] - bwin[1]) * bt
    # the upright's two ends and the slot's two sides; the holes' bores
    area_v += (4 if g["slot"] else 2) * height * wall
    area_v += 4 * math.pi * (screw.clearance_d * bt + g["camera_hole_d"] * wall)
    est = Estimate(vol, 2 * base_a + (w - 2 * g["slot"]) * wall, area_v, (w, yf - yb, height + bt))
    origin = (0.0, 0.0, frame.core.plate.hi[2])
    params = tuple((k, v) for k, v in g.items())
    hw = (HardwareLine("M2 x 6 screw + nut (camera to mount)", 4, SCREWS["M2"].mass_g + 0.1),)
    # not "camera_...": trimesh 5.2's 3MF export drops every scene node whose name starts with "camera"
    return PartSpec("front_camera_mount", "camera_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(origin)),), (), g["wall"], est, params, hw)



# -- the assembly's words ------------------------------------------------------------------

def fitting(spec: Spec) -> str:
    """How the builder fits the camera mount and the camera."""
    return (f"Set the camera mount's base on the core plate, its holes over the stack screws, so the upright stands "
            f"at the plate's front edge ({spec.core.camera.tilt_deg:g} deg tilt); the FC/ESC stack goes on top of the "
            "base. Screw the Pi camera v2 to the upright with its lens forward (4 x M2) and run the ribbon up to the computer.")

# -- the solid --------------------------------------------------------------------------------

def print_from_local(part: PartSpec) -> np.ndarray:
    """Printed as it sits: the base on the bed, the upright standing (leaning by tilt_deg <= 45)."""
    return transform(np.eye(3), (0.0, 0.0, 0.0))


def camera_upright_matrix(part_params: dict) -> np.ndarray:
    """4x4 local <- upright frame: the upright's bottom front edge is the x axis at (y_front, base_t);
    the upright leans back by tilt_deg (positive: the camera looks up)."""
    a = np.radians(float(part_params["tilt_deg"]))
    m = np.eye(4)
    # rotation about x by +a takes +y (the lens direction) up toward +z
    m[:3, :3] = [[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]]
    m[:3, 3] = (0.0, float(part_params["y_front"]), float(part_params["base_t"]))
    return m


def solid(part: PartSpec) -> Built:
    """Base under the FC stack + the camera upright at the plate's front edge (tilted), printed as
    it sits: the base's window is a vertical opening, the upright's slot is open at the top (no roof
    at any tilt) and the camera holes are 2.2 mm horizontal holes."""
    import cadquery as cq

    p = dict(part.params)
    w, yf, yb = float(p["width"]), float(p["y_front"]), float(p["y_back"])
    bt, wall, height = float(p["base_t"]), float(p["wall"]), float(p["height"])
    base = cq.Solid.makeBox(w, yf - yb, bt, cq.Vector(-w / 2, yb, 0.0))
    # the upright in its own frame: y from -wall to 0 (behind the camera), z from -bt (down into the
    # base, so the two fuse at any tilt) to height
    up = cq.Solid.makeBox(w, wall, height + bt, cq.Vector(-w / 2, -wall, -bt))
    hd = float(p["camera_hole_d"])
    tools = [cq.Solid.makeCylinder(hd / 2, wall + 2.0, cq.Vector(float(x), -wall - 1.0, float(z) - bt), cq.Vector(0, 1, 0))
             for x, z in p["camera_holes"]]
    slot = float(p["slot"])
    if slot > 0.0:
        # from the upright's foot (z 0: the base fills what lies below) out through its top
        tools.append(cq.Solid.makeBox(2 * slot, wall + 2.0, height + 1.0, cq.Vector(-slot, -wall - 1.0, 0.0)))
    up = apply(up.cut(*tools) if tools else up, camera_upright_matrix(p))
    body = base.fuse(up)
    # cut everything below the base (a tilted upright's heel) and, below the base top, in front of
    # the plate edge (the heel of an upright leaning back would hang there)
    tools = [cq.Solid.makeBox(4 * w, 4 * (yf - yb) + 4 * height, 4 * height, cq.Vector(-2 * w, -2 * (yf - yb) - height, -4 * height)),
             cq.Solid.makeBox(4 * w, 2 * height, bt + 1.0, cq.Vector(-2 * w, yf, -1.0))]
    cc = float(p["corner_cut"])
    y_cut = yf - wall  # behind the upright only, so the upright never overhangs the cut
    x0 = max(cc - y_cut, CAMERA_SPINE)  # where each cut starts across the base, from its centre line
    for sx in (-1.0, 1.0):  # front corners of the base, clear of the core links' tabs
        if x0 == cc - y_cut:
            tri = [(sx * (cc - y_cut), y_cut), (sx * (cc + 50.0), -50.0), (sx * (cc + 50.0), y_cut)]
        else:
            # A thick plate brings the link bolts in (base.link_hole) until the two 45 deg cuts
            # would meet on the centre line in front of the upright's back face and cut the upright
            # off the base (core.plate_thickness 6 mm on a 40 mm plate): each cut stops short of
            # the centre line, leaving the base a spine 2 x CAMERA_SPINE wide up to the upright.
            tri = [(sx * x0, y_cut), (sx * x0, cc - x0), (sx * (cc + 50.0), -50.0), (sx * (cc + 50.0), y_cut)]
        tools.append(prism_xy(tri, -1.0, bt))
    hole_d = float(p["stack_hole_d"])
    tools += [cq.Solid.makeCylinder(hole_d / 2, bt + 2.0, cq.Vector(float(x), float(y), -1.0)) for x, y in p["stack_holes"]]
    if p["base_window"]:
        x0, y0, x1, y1 = (float(v) for v in p["base_window"])
        tools.append(cq.Solid.makeBox(x1 - x0, y1 - y0, bt + 2.0, cq.Vector(x0, y0, -1.0)))
    body = body.cut(*tools)  # one boolean with every tool
    solids = body.clean().Solids()
    if len(solids) != 1:
        raise RuntimeError(f"camera_mount geometry produced {len(solids)} solids instead of 1")
    m = print_from_local(part)
    return Built(apply(solids[0], m), m)

"""The front camera's bracket (ABS/PLA): an L of a base plate under the FC stack and an upright at
the plate's front edge, tilted back by core.camera.tilt_deg; its local origin is the plate top's
centre, axes as the frame. Printed as it sits.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import CAMERA_BASE_T, Frame
from ..materials import BOARDS, SCREWS, STACK_PATTERNS
from ..parts.blocks import pointed, prism_xy
from ..parts.joint_solid import Built, apply
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import hexagon_area, link_hole, rounded

NAME = "camera_mount"
SIZE_KEY = "core.camera"
DOC = "ABS/PLA camera bracket (base under the FC stack, tilted upright), printed on its side"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_camera_mount(spec, frame),) if spec.core.camera else ()

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
            "corner_cut": round(2 * link_hole(spec) - 7.0, 4)}


def _camera_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    g = camera_mount_geometry(spec, frame)
    screw = SCREWS[c.stack_screw]
    w, yf, yb, bt, wall, height = g["width"], g["y_front"], g["y_back"], g["base_t"], g["wall"], g["height"]
    k = g["corner_cut"] - (yf - wall)  # where each front corner cut (behind the upright) meets the upright's back face, |x|
    x0 = max(k, CAMERA_SPINE)  # never nearer the centre line (as `solid` cuts it)
    corner = (max(0.0, w / 2 - k) ** 2 - max(0.0, min(x0, w / 2) - k) ** 2) / 2  # area of each corner cut off the base
    bw, hy = min(w / 2 - 4.0, 6.0), min(5.0, (yf - yb) / 2 - 8.0)
    base_win = hexagon_area(2 * bw, 2 * hy) if bw > 2.0 and hy > 1.0 and bw >= hy else 0.0
    up_win = hexagon_area(height - 12.0, 10.0) if height - 6.0 > 10.0 and abs(g["tilt_deg"]) <= 5.0 else 0.0
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
    """Base plate under the FC stack + the camera upright at the plate's front edge (tilted), printed
    as it sits: windows pointed along z, camera holes are 2.2 mm horizontal holes."""
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
    win_half = 5.0
    if height - 6.0 > 2 * win_half and abs(float(p["tilt_deg"])) <= 5.0:
        # window behind the board (its connector side), pointed along z; a tilted upright would
        # turn one of its 45 deg roofs into an overhang, so tilted uprights stay solid
        pts = [(a, z) for z, a in pointed(3.0, height - 9.0, win_half)]
        tools.append(cq.Workplane("XZ", origin=(0, 1.0, 0)).polyline(pts).close().extrude(wall + 2.0).val())
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
    bw, hy = min(w / 2 - 4.0, 6.0), min(5.0, (yf - yb) / 2 - 8.0)
    if bw > 2.0 and hy > 1.0 and 2 * bw >= 2 * hy:  # lightening window between the stack holes, pointed along x (print z)
        tools.append(prism_xy(pointed(-bw, bw, hy), -1.0, bt + 1.0))
    body = body.cut(*tools)  # one boolean with every tool
    solids = body.clean().Solids()
    if len(solids) != 1:
        raise RuntimeError(f"camera_mount geometry produced {len(solids)} solids instead of 1")
    m = print_from_local(part)
    return Built(apply(solids[0], m), m)

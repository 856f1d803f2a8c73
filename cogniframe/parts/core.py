"""Rigid core parts (ABS/PLA): core plate, battery holder, computer mount.

Local frames (partlist): each part is centred on its placement origin, axes as the frame.
* core_plate / computer_mount: flat plates printed as they sit (translate up by half the thickness).
* battery_holder: an open-ended rectangular sleeve (floor, top, two sides) closed by a back stop at
  the rear (-y); printed standing on the back stop (local +y -> print +z), so every wall is vertical
  and the stack holes in the top are short horizontal bridges. The frame gives the holder's outer
  height as floor + battery + 1 mm slack, so floor and top share what the outer box leaves around
  the cavity: (outer height - inner height) / 2 each.
"""

from __future__ import annotations

import numpy as np

from ..errors import UserError
from ..partlist import CAMERA_SPINE, PartSpec
from .joint import Built, apply, transform

MIN_SKIN = 0.8  # mm: thinner than two 0.4 mm lines does not print as a wall


def _plate(size_x: float, size_y: float, t: float, holes):
    import cadquery as cq

    wp = cq.Workplane("XY").box(size_x, size_y, t, centered=(True, True, False))
    for d, pts in holes:
        wp = wp.faces(">Z").workplane(origin=(0, 0, t)).pushPoints([tuple(map(float, p)) for p in pts]).hole(d)
    return wp.val()


def plate_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, float(part.param("thickness")) / 2))


def build_plate(part: PartSpec) -> Built:
    size = float(part.param("size"))
    t = float(part.param("thickness"))
    shape = _plate(size, size, t, [(float(part.param("hole_d")), part.param("holes"))])
    return Built(shape, plate_from_local(part))


def build_computer_mount(part: PartSpec) -> Built:
    a, b = (float(v) for v in part.param("size"))
    t = float(part.param("thickness"))
    shape = _plate(a, b, t, [(float(part.param("computer_hole_d")), part.param("computer_holes")),
                             (float(part.param("stack_hole_d")), part.param("stack_holes"))])
    return Built(shape, plate_from_local(part))


ROT_X_90 = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # local +y -> print +z


def holder_from_local(part: PartSpec) -> np.ndarray:
    w, length, h = (float(v) for v in part.param("outer"))
    return transform(ROT_X_90, (0.0, 0.0, length / 2))


def holder_skins(part: PartSpec) -> tuple[float, float]:
    """(floor = top thickness, back stop thickness), mm."""
    w, length, h = (float(v) for v in part.param("outer"))
    iw, il, ih = (float(v) for v in part.param("inner"))
    return (h - ih) / 2, length - il


def build_holder(part: PartSpec) -> Built:
    import cadquery as cq

    w, length, h = (float(v) for v in part.param("outer"))
    iw, il, ih = (float(v) for v in part.param("inner"))
    skin, back = holder_skins(part)
    if skin < MIN_SKIN or (w - iw) / 2 < MIN_SKIN or back < MIN_SKIN:
        raise UserError(
            f"battery_holder: the {w:g} x {length:g} x {h:g} mm outline leaves {min(skin, (w - iw) / 2, back):.2f} mm walls around "
            f"the {iw:g} x {il:g} x {ih:g} mm battery cavity (need {MIN_SKIN} mm). Fix: raise core.holder_wall or check core.battery.",
            key="core.holder_wall")
    outer = cq.Solid.makeBox(w, length, h, cq.Vector(-w / 2, -length / 2, -h / 2))
    # Cavity: open at the front (+y), the back stop at the rear.
    cavity = cq.Solid.makeBox(iw, il + 1.0, ih, cq.Vector(-iw / 2, -length / 2 + back, -h / 2 + skin))
    d = float(part.param("hole_d"))
    holes = [cq.Solid.makeCylinder(d / 2, skin + 2.0, cq.Vector(float(x), float(y), h / 2 - skin - 1.0)) for x, y in part.param("holes")]
    cutters = holder_cutters(part) if "lead_exit" in dict(part.params) else []
    shape = outer.cut(cavity, *holes, *cutters)  # one boolean with every tool: half the time of one per tool
    m = holder_from_local(part)
    placed = apply(shape.clean(), m)
    return Built(placed, m)



# -- the holder's openings, the sensor mount / spacer, the camera mount ------------

def _prism_xz(pts_yz, x0: float, x1: float):
    """A prism through a side wall: polygon in (y, z), extruded along x from x0 to x1."""
    import cadquery as cq

    wp = cq.Workplane("YZ", origin=(x0, 0, 0)).polyline([tuple(map(float, p)) for p in pts_yz]).close()
    return wp.extrude(x1 - x0).val()


def _prism_xy(pts_xy, z0: float, z1: float):
    import cadquery as cq

    return cq.Workplane("XY", origin=(0, 0, z0)).polyline([tuple(map(float, p)) for p in pts_xy]).close().extrude(z1 - z0).val()


def _pointed(y0: float, y1: float, half: float) -> list[tuple[float, float]]:
    """A window from y0 to y1, `half` across, with 45 deg pointed ends along y: (y, across) points."""
    return [(y0, 0.0), (y0 + half, -half), (y1 - half, -half), (y1, 0.0), (y1 - half, half), (y0 + half, half)]


def holder_cutters(part: PartSpec) -> list:
    """Windows, strap slots and the lead exit of the battery holder, in its local frame."""
    import cadquery as cq

    w, length, h = (float(v) for v in part.param("outer"))
    iw, il, ih = (float(v) for v in part.param("inner"))
    skin, back = holder_skins(part)
    out = []
    zc = -h / 2 + skin + ih / 2
    side = part.param("side_window")
    if side:
        ya, ye, hz = (float(v) for v in side)
        pts = [(y, zc + a) for y, a in _pointed(ya, ye, hz / 2)]
        out.append(_prism_xz(pts, -w / 2 - 1.0, w / 2 + 1.0))
    floor = part.param("floor_window")
    if floor:
        ya, ye, fw = (float(v) for v in floor)
        pts = [(a, y) for y, a in _pointed(ya, ye, fw / 2)]
        out.append(_prism_xy(pts, -h / 2 - 1.0, -h / 2 + skin + 0.5))
    strap = part.param("strap_slot")
    if strap:
        ys, _, s_len, s_w = (float(v) for v in strap)
        u = np.array([1.0, 1.0]) / np.sqrt(2)
        n = np.array([-1.0, 1.0]) / np.sqrt(2)
        c = np.array([ys, zc])
        pts = [c + su * u * s_len / 2 + sn * n * s_w / 2 for su, sn in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        out.append(_prism_xz(pts, -w / 2 - 1.0, w / 2 + 1.0))
    lw, y0 = (float(v) for v in part.param("lead_exit"))  # notch in the top wall, from y0 to the mouth
    out.append(cq.Solid.makeBox(lw, length / 2 - y0 + 1.0, skin + 1.5, cq.Vector(-lw / 2, y0, h / 2 - skin - 0.5)))
    return out


def build_sensor_mount(part: PartSpec) -> Built:
    """The X-shaped spacer with its neck and rear pad, printed flat as it sits; link-bolt nut traps
    open on the bed side (their roofs are 4.4 mm bridges)."""
    import cadquery as cq

    t = float(part.param("thickness"))
    first, *rest = (_prism_xy(poly, 0.0, t) for poly in part.param("pieces"))
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


def sensor_mount_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, 0.0))


def camera_mount_from_local(part: PartSpec) -> np.ndarray:
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


def build_camera_mount(part: PartSpec) -> Built:
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
        pts = [(a, z) for z, a in _pointed(3.0, height - 9.0, win_half)]
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
            # A thick plate brings the link bolts in (partlist._link_hole) until the two 45 deg cuts
            # would meet on the centre line in front of the upright's back face and cut the upright
            # off the base (core.plate_thickness 6 mm on a 40 mm plate): each cut stops short of
            # the centre line, leaving the base a spine 2 x CAMERA_SPINE wide up to the upright.
            tri = [(sx * x0, y_cut), (sx * x0, cc - x0), (sx * (cc + 50.0), -50.0), (sx * (cc + 50.0), y_cut)]
        tools.append(_prism_xy(tri, -1.0, bt))
    hole_d = float(p["stack_hole_d"])
    tools += [cq.Solid.makeCylinder(hole_d / 2, bt + 2.0, cq.Vector(float(x), float(y), -1.0)) for x, y in p["stack_holes"]]
    bw, hy = min(w / 2 - 4.0, 6.0), min(5.0, (yf - yb) / 2 - 8.0)
    if bw > 2.0 and hy > 1.0 and 2 * bw >= 2 * hy:  # lightening window between the stack holes, pointed along x (print z)
        tools.append(_prism_xy(_pointed(-bw, bw, hy), -1.0, bt + 1.0))
    body = body.cut(*tools)  # one boolean with every tool
    solids = body.clean().Solids()
    if len(solids) != 1:
        raise RuntimeError(f"camera_mount geometry produced {len(solids)} solids instead of 1")
    m = camera_mount_from_local(part)
    return Built(apply(solids[0], m), m)


def _matrix_of(m: np.ndarray):
    import cadquery as cq

    return cq.Matrix([[float(v) for v in row] for row in np.asarray(m)[:3]])

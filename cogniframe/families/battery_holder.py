"""The battery holder (ABS/PLA): an open-ended rectangular sleeve (floor, top, two sides) closed
by a back stop at the rear (-y), centred on its placement origin, axes as the frame. Printed
standing on the back stop (local +y -> print +z), so every wall is vertical and the stack holes
in the top are short horizontal bridges. The frame gives the holder's outer height as floor +
battery + 1 mm slack, so floor and top share what the outer box leaves around the cavity:
(outer height - inner height) / 2 each.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import UserError
from ..frame import Frame
from ..materials import CONNECTORS, COUNTERSINK_SLACK, COUNTERSUNK, SCREWS, STACK_PATTERNS
from ..parts.blocks import pointed, prism_xy, prism_xz
from ..parts.joint_solid import Built, apply
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import hexagon_area, rounded

NAME = "battery_holder"
SIZE_KEY = "core.battery"
DOC = "ABS/PLA open-ended battery sleeve, printed on its back stop"


# core.battery_lock: magnetic. Four axially magnetised 6 x 2 mm N38 neodymium discs (a catalogue
# size, e.g. Dhit MW 6x2 / N38, +-0.1 mm), each 0.42 g: its volume at sintered NdFeB's 7.5 g/cm^3
# (the catalogue's N38 data: density >= 7.4 g/cm^3). Each pocket is the disc + 0.2 mm across (its
# tolerance and the print's) and 0.1 mm deeper than it, glued flush; 1.2 mm of plastic (three
# 0.4 mm lines) round it and under it in the lid (LID_FLOOR).
MAGNET_D, MAGNET_H, MAGNET_G = 6.0, 2.0, 0.42
POCKET_D, POCKET_DEPTH = MAGNET_D + 0.2, MAGNET_H + 0.1
POCKET_WALL = 1.2
LID_FLOOR = 1.2
MAGNET_LINE = "6 x 2 mm N38 neodymium disc magnet, axially magnetised (e.g. Dhit MW 6x2 / N38), glued into its pocket"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    if spec.core.battery_lock == "magnetic":
        return (_battery_holder(spec, frame), _lid(spec, frame))
    return (_battery_holder(spec, frame),)


def magnet_bosses(spec: Spec, frame: Frame) -> dict:
    """The magnetic lock's two bosses, one on each side wall's outside at the mouth, in the
    holder's local frame (mm): each pocket's centre x (+-), its height zc (the cavity's middle),
    the boss's reach `out` past the wall, its length `back` from the mouth at full reach (then a
    45 deg slope back to the wall: the boss's underside as printed, standing on the back stop)
    and its height. The pocket keeps POCKET_WALL from the cavity and from the boss's outside and
    floor."""
    c, b = spec.core, spec.core.battery
    w, length, height = frame.core.holder.size
    ih = b.height + 1.0
    skin = (height - ih) / 2
    r = POCKET_D / 2
    x = b.width / 2 + POCKET_WALL + r
    out = round(x + r + POCKET_WALL - w / 2, 6)
    return {"x": round(x, 6), "zc": round(-height / 2 + skin + ih / 2, 6), "out": out,
            "back": POCKET_DEPTH + POCKET_WALL, "height": POCKET_D + 2 * POCKET_WALL, "mouth": round(length / 2, 6)}


def _boss_area(m: dict) -> float:
    """One boss's profile in the holder's xy (a trapezoid: full reach `back` long, then 45 deg)."""
    return m["out"] * m["back"] + m["out"] ** 2 / 2

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
    strap = (y_front_of_pack + 1.0 + ext / 2, 0.0, s_len, s_w) if ext <= ih and c.battery_lock == "strap" else None
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
    # top, whose thickness is what the outer height leaves around the cavity (`solid`); minus
    # the lightening windows, the strap slots and the lead exit (holder_features).
    iw, il, ih = b.width, length - t, b.height + 1.0
    skin = (height - ih) / 2
    hy = h.centre[1]
    holes = tuple((sx * pitch / 2, sy * pitch / 2 - hy) for sx in (-1, 1) for sy in (-1, 1))
    f = holder_features(spec, frame)
    cut_side = 2 * hexagon_area(f["side_window"][1] - f["side_window"][0], f["side_window"][2]) if f["side_window"] else 0.0
    cut_floor = hexagon_area(f["floor_window"][1] - f["floor_window"][0], f["floor_window"][2]) if f["floor_window"] else 0.0
    cut_strap = 2 * f["strap_slot"][2] * f["strap_slot"][3] if f["strap_slot"] else 0.0
    cut_lead = f["lead_exit"][0] * (length / 2 - f["lead_exit"][1])  # notch in the top wall, over the mouth
    # each stack hole's countersink in the cavity's ceiling: the countersunk screw's head sits flush
    # in it, so the pack slides under it (fasteners.py): a 90 deg cone from the head's diameter
    # (+ slack) at the ceiling to the hole, a frustum less the hole's own cylinder
    csk_d = COUNTERSUNK[c.stack_screw][0] + COUNTERSINK_SLACK
    r1, r0 = csk_d / 2, screw.clearance_d / 2
    csk_h = r1 - r0
    csk_vol = math.pi * csk_h / 3 * (r1 * r1 + r1 * r0 + r0 * r0) - math.pi * r0 * r0 * csk_h
    vol = (w * length * height - iw * il * ih - len(holes) * (math.pi / 4 * screw.clearance_d**2 * skin + csk_vol)
           - (cut_side + cut_strap) * t - cut_floor * skin - cut_lead * skin)
    mag = magnet_bosses(spec, frame) if c.battery_lock == "magnetic" else None
    if mag:  # two bosses, each less its pocket (inside the boss and the side wall)
        vol += 2 * (_boss_area(mag) * mag["height"] - math.pi / 4 * POCKET_D**2 * POCKET_DEPTH)
    # Walls are vertical when printed on end: outside and cavity faces; horizontal: the back stop
    # and the rim of the open end.
    area_v = 2 * (w + height) * length + 2 * (iw + ih) * il - 2 * (cut_side + cut_strap + cut_floor)
    rim = w * height - iw * ih
    area_h = w * height + rim - f["lead_exit"][0] * skin
    if mag:  # the bosses' sides stand vertical as printed; their tops and 45 deg undersides count as horizontal
        area_v += 2 * (2 * _boss_area(mag) + mag["back"] * mag["height"])
        area_h += 2 * (mag["out"] * (1 + math.sqrt(2)) * mag["height"])
    est = Estimate(vol, area_h, area_v, (w + (2 * mag["out"] if mag else 0.0), height, length))
    params = (("inner", (b.width, il, b.height + 1.0)), ("wall", t), ("holes", holes), ("hole_d", screw.clearance_d),
              ("countersink_d", round(csk_d, 4)), ("outer", (w, length, height)), *sorted(f.items()))
    if mag:
        params += (("magnet_bosses", tuple(sorted(mag.items()))), ("pocket", (POCKET_D, POCKET_DEPTH)))
    # The strap runs across the mouth and round the holder's outside, closing on itself: the
    # holder's cross-section perimeter + 40 mm of overlap, rounded up to 10 mm; about 1 g per
    # 100 mm of 10 mm hook-and-loop.
    strap_len = math.ceil((2 * (w + height) + 40.0) / 10.0) * 10.0
    hw = (HardwareLine(f"hook-and-loop battery strap {c.strap_width:g} mm x {strap_len:g} mm", 1,
                       round(0.01 * strap_len * c.strap_width / 10.0, 2)),)
    if mag:
        hw = (HardwareLine(f"{MAGNET_LINE} (battery holder's mouth)", 2, MAGNET_G),)
    return PartSpec("battery_holder", "battery_holder", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(h.centre)),), (), t, est, params, hw)


# -- the solid --------------------------------------------------------------------------------

MIN_SKIN = 0.8  # mm: thinner than two 0.4 mm lines does not print as a wall


ROT_X_90 = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # local +y -> print +z


def print_from_local(part: PartSpec) -> np.ndarray:
    if part.name == "battery_lid":
        return transform(ROT_X_M90, (0.0, 0.0, float(part.param("size")[1]) / 2))
    w, length, h = (float(v) for v in part.param("outer"))
    return transform(ROT_X_90, (0.0, 0.0, length / 2))


def holder_skins(part: PartSpec) -> tuple[float, float]:
    """(floor = top thickness, back stop thickness), mm."""
    w, length, h = (float(v) for v in part.param("outer"))
    iw, il, ih = (float(v) for v in part.param("inner"))
    return (h - ih) / 2, length - il


def solid(part: PartSpec) -> Built:
    import cadquery as cq

    if part.name == "battery_lid":
        return _lid_solid(part)
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
    csk = dict(part.params).get("countersink_d")
    if csk:  # the countersinks, from 0.5 mm inside the cavity (no face on the ceiling's) to the hole at 45 deg
        r1 = float(csk) / 2 + 0.5
        holes += [cq.Solid.makeCone(r1, d / 2, r1 - d / 2, cq.Vector(float(x), float(y), h / 2 - skin - 0.5), cq.Vector(0, 0, 1))
                  for x, y in part.param("holes")]
    cutters = holder_cutters(part) if "lead_exit" in dict(part.params) else []
    mag = dict(part.params).get("magnet_bosses")
    if mag:
        bosses, pockets = _boss_solids(dict(mag))
        outer = outer.fuse(*bosses).clean()
        cutters += pockets
    shape = outer.cut(cavity, *holes, *cutters)  # one boolean with every tool: half the time of one per tool
    m = print_from_local(part)
    placed = apply(shape.clean(), m)
    return Built(placed, m)


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
        pts = [(y, zc + a) for y, a in pointed(ya, ye, hz / 2)]
        out.append(prism_xz(pts, -w / 2 - 1.0, w / 2 + 1.0))
    floor = part.param("floor_window")
    if floor:
        ya, ye, fw = (float(v) for v in floor)
        pts = [(a, y) for y, a in pointed(ya, ye, fw / 2)]
        out.append(prism_xy(pts, -h / 2 - 1.0, -h / 2 + skin + 0.5))
    strap = part.param("strap_slot")
    if strap:
        ys, _, s_len, s_w = (float(v) for v in strap)
        u = np.array([1.0, 1.0]) / np.sqrt(2)
        n = np.array([-1.0, 1.0]) / np.sqrt(2)
        c = np.array([ys, zc])
        pts = [c + su * u * s_len / 2 + sn * n * s_w / 2 for su, sn in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        out.append(prism_xz(pts, -w / 2 - 1.0, w / 2 + 1.0))
    lw, y0 = (float(v) for v in part.param("lead_exit"))  # notch in the top wall, from y0 to the mouth
    out.append(cq.Solid.makeBox(lw, length / 2 - y0 + 1.0, skin + 1.5, cq.Vector(-lw / 2, y0, h / 2 - skin - 0.5)))
    return out


def _boss_solids(m: dict) -> tuple[list, list]:
    """The magnetic lock's two bosses (holder's local frame) and their pockets, which open on the
    mouth's face (local +y; up as printed)."""
    import cadquery as cq

    y1, out, back = m["mouth"], m["out"], m["back"]
    z0, z1 = m["zc"] - m["height"] / 2, m["zc"] + m["height"] / 2
    bosses, pockets = [], []
    for sx in (-1.0, 1.0):
        # from 0.5 mm inside the side wall (no face on its outside), out, back, then 45 deg back in
        x_in, x_out = sx * (m["x"] - POCKET_D / 2 - POCKET_WALL - 0.5), sx * (m["x"] + POCKET_D / 2 + POCKET_WALL)
        x_wall = sx * (abs(x_out) - out)
        pts = [(x_in, y1), (x_out, y1), (x_out, y1 - back), (x_wall, y1 - back - out), (x_in, y1 - back - out)]
        bosses.append(prism_xy(pts, z0, z1))
        pockets.append(cq.Solid.makeCylinder(POCKET_D / 2, POCKET_DEPTH + 1.0, cq.Vector(sx * m["x"], y1 - POCKET_DEPTH, m["zc"]),
                                             cq.Vector(0, 1, 0)))
    return bosses, pockets


# -- the lid (core.battery_lock: magnetic) ----------------------------------------------------

def _lid(spec: Spec, frame: Frame) -> PartSpec:
    """A plate across the holder's mouth and its bosses, POCKET_DEPTH + LID_FLOOR thick, its two
    pockets facing the holder's; the magnets hold it on. Local frame: centred on its box, axes as
    the frame; it prints lying on its outer face, the pockets up."""
    c = spec.core
    h = frame.core.holder
    w, length, height = h.size
    m = magnet_bosses(spec, frame)
    a, t = w + 2 * m["out"], POCKET_DEPTH + LID_FLOOR
    xs = (-m["x"], m["x"])
    vol = a * height * t - 2 * math.pi / 4 * POCKET_D**2 * POCKET_DEPTH
    est = Estimate(vol, 2 * a * height, 2 * (a + height) * t + 2 * math.pi * POCKET_D * POCKET_DEPTH, (a, height, t))
    centre = (h.centre[0], h.centre[1] + length / 2 + t / 2, h.centre[2])
    params = (("size", (a, t, height)), ("pockets", tuple((x, m["zc"]) for x in xs)), ("pocket", (POCKET_D, POCKET_DEPTH)))
    hw = (HardwareLine(f"{MAGNET_LINE} (battery lid; poles opposite the holder's)", 2, MAGNET_G),)
    return PartSpec("battery_lid", NAME, "core", c.material, c.infill, (Placement("battery_lid", 0.0, rounded(centre)),), (), LID_FLOOR,
                    est, params, hw)


# local -y (the face on the holder's mouth) -> print +z: the pockets open upwards
ROT_X_M90 = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])


def _lid_solid(part: PartSpec) -> Built:
    import cadquery as cq

    a, t, height = (float(v) for v in part.param("size"))
    d, depth = (float(v) for v in part.param("pocket"))
    body = cq.Solid.makeBox(a, t, height, cq.Vector(-a / 2, -t / 2, -height / 2))
    pockets = [cq.Solid.makeCylinder(d / 2, depth + 1.0, cq.Vector(float(x), -t / 2 - 1.0, float(z)), cq.Vector(0, 1, 0))
               for x, z in part.param("pockets")]
    m = transform(ROT_X_M90, (0.0, 0.0, t / 2))
    return Built(apply(body.cut(*pockets).clean(), m), m)

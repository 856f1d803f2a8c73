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


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_battery_holder(spec, frame),)

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
    # Walls are vertical when printed on end: outside and cavity faces; horizontal: the back stop
    # and the rim of the open end.
    area_v = 2 * (w + height) * length + 2 * (iw + ih) * il - 2 * (cut_side + cut_strap + cut_floor)
    rim = w * height - iw * ih
    area_h = w * height + rim - f["lead_exit"][0] * skin
    est = Estimate(vol, area_h, area_v, (w, height, length))
    params = (("inner", (b.width, il, b.height + 1.0)), ("wall", t), ("holes", holes), ("hole_d", screw.clearance_d),
              ("countersink_d", round(csk_d, 4)), ("outer", (w, length, height)), *sorted(f.items()))
    # The strap runs across the mouth and round the holder's outside, closing on itself: the
    # holder's cross-section perimeter + 40 mm of overlap, rounded up to 10 mm; about 1 g per
    # 100 mm of 10 mm hook-and-loop.
    strap_len = math.ceil((2 * (w + height) + 40.0) / 10.0) * 10.0
    hw = (HardwareLine(f"hook-and-loop battery strap {c.strap_width:g} mm x {strap_len:g} mm", 1,
                       round(0.01 * strap_len * c.strap_width / 10.0, 2)),)
    return PartSpec("battery_holder", "battery_holder", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(h.centre)),), (), t, est, params, hw)


# -- the solid --------------------------------------------------------------------------------

MIN_SKIN = 0.8  # mm: thinner than two 0.4 mm lines does not print as a wall


ROT_X_90 = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # local +y -> print +z


def print_from_local(part: PartSpec) -> np.ndarray:
    w, length, h = (float(v) for v in part.param("outer"))
    return transform(ROT_X_90, (0.0, 0.0, length / 2))


def holder_skins(part: PartSpec) -> tuple[float, float]:
    """(floor = top thickness, back stop thickness), mm."""
    w, length, h = (float(v) for v in part.param("outer"))
    iw, il, ih = (float(v) for v in part.param("inner"))
    return (h - ih) / 2, length - il


def solid(part: PartSpec) -> Built:
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
    csk = dict(part.params).get("countersink_d")
    if csk:  # the countersinks, from 0.5 mm inside the cavity (no face on the ceiling's) to the hole at 45 deg
        r1 = float(csk) / 2 + 0.5
        holes += [cq.Solid.makeCone(r1, d / 2, r1 - d / 2, cq.Vector(float(x), float(y), h / 2 - skin - 0.5), cq.Vector(0, 0, 1))
                  for x, y in part.param("holes")]
    cutters = holder_cutters(part) if "lead_exit" in dict(part.params) else []
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

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
from ..partlist import PartSpec
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
    shape = outer.cut(cavity)
    d = float(part.param("hole_d"))
    holes = [cq.Solid.makeCylinder(d / 2, skin + 2.0, cq.Vector(float(x), float(y), h / 2 - skin - 1.0)) for x, y in part.param("holes")]
    for hole in holes:
        shape = shape.cut(hole)
    m = holder_from_local(part)
    placed = apply(shape.clean(), m)
    return Built(placed, m)


"""The rear net (frame.rear_net): the authors' thin TPU web, a flat 0.5 mm part of the joints'
filament stretched across the cage's rear face, its long rims along the rear top and bottom cage
rods (tied to them with cable ties, as the authors' bill of materials lists), its round window in
the middle of the face. The rear, because the battery slides in through the front face (the
holder's open end; the fit check's slide path finds a net there). On a bed smaller than the net (the
paper's 120 x 120 mm printer) it prints as two halves, each with a rim along its cut, tied
together there.

The authors publish the net (thecognifly/CogniFly-STL, CogniFly_v8_Crash_Tests/Flex_net_thin.stl)
but their assembly does not place it; its size does: 162 x 102 mm is a face of their cage,
102 = the 106.6 mm between the top and bottom rods' axes less a rod and 0.8 mm a side, and
162 = the 174.4 mm between the knees' axes (204.4 less twice the 15 mm inset) less 6.2 mm a side.
The pattern, measured in that STL at mid-thickness: lines 1.0 mm wide, the rim too; rings about
a 68 mm round opening, centred at radii 34.5, 50, 65 and 80 mm; 22 spokes (every 360/22 deg from
the +x axis) from the opening to the rim.
cogniframe draws the same pattern on its own cage's rear face: at the authors' 162 x 102 its
area is theirs within 0.2 % (tests/test_frame_options.py).

Its local frame is the face's: x along the face, z up, y out of the cage (a half turn about z
places it on the rear face); it prints lying flat.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import Frame
from ..parts.joint_plan import transform
from ..parts.joint_solid import Built
from ..parts.record import Estimate, PartSpec, Placement
from ..spec import Spec
from .base import rounded

NAME = "net"
SIZE_KEY = "frame.width"
DOC = "TPU net (0.5 mm) across the cage's rear face, a round window in its middle"

THICKNESS = 0.5  # mm, the authors' Flex_net_thin
LINE = 1.0  # mm, every ring and spoke
RIM = 1.0  # mm, the rim all round
OPENING_D = 68.0  # mm, the round window inside the first ring
RING_PITCH, FIRST_OUTER_RING = 15.0, 50.0  # mm: ring centres at 34.5 (round the window), then 50, 65, 80 (to the short rims)
SPOKES = 22
ROD_GAP = 0.8  # mm between a long rim and its rod's surface (the authors' 102 in 106.6 less a 3 mm rod)
WAIST_GAP = 6.2  # mm between an end of the net and a knee's axis, seen square on (the authors' 162 in 174.4)
SEAM_GAP = 0.2  # mm between the two halves' seam rims (a bed too small for the whole net): the ties close it
SEGMENTS = 256  # a ring's polygon: its area within 1e-4 of the circle's


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_net(spec, frame),) if spec.frame.rear_net else ()


def face(frame: Frame) -> tuple[float, float, float, float, float]:
    """The rear face (-y): the top and bottom rear cage rods' axes (y, z_bottom, z_top), the
    knees' half-width in x, the waist, and the rods' diameter (mm)."""
    top, bottom = frame.rods["rod_cage_top_rear"], frame.rods["rod_cage_bottom_rear"]
    y = float(top.a.port[1])
    waist = min(abs(float(n.pos[0])) for n in frame.nodes.values() if n.name.startswith("knee") and n.pos[1] < 0)
    return y, float(bottom.a.port[2]), float(top.a.port[2]), waist, float(top.diameter)


def size(spec: Spec, frame: Frame) -> tuple[float, float]:
    y, z0, z1, waist, rod_d = face(frame)
    return round(2 * (waist - WAIST_GAP), 6), round(z1 - z0 - rod_d - 2 * ROD_GAP, 6)


def outline(w: float, h: float):
    """The net in its plane (x along the face, second coordinate up), as a manifold3d
    CrossSection: the rim, the rings clipped to the rectangle, the spokes from the window to the
    rim, less the window. manifold3d's 2-D booleans are exact on the polygons; the rings are
    SEGMENTS-gons."""
    import manifold3d as m3

    rect = m3.CrossSection.square((w, h), center=True)
    inner = m3.CrossSection.square((w - 2 * RIM, h - 2 * RIM), center=True)
    pieces = [rect - inner]
    r_open = OPENING_D / 2
    reach = math.hypot(w, h) / 2
    radii = [r_open + LINE / 2]
    r = FIRST_OUTER_RING
    while r + LINE / 2 <= max(w, h) / 2:  # the authors' last ring (80) meets the short rims, none in the corners
        radii.append(r)
        r += RING_PITCH
    for rc in radii:
        pieces.append(m3.CrossSection.circle(rc + LINE / 2, SEGMENTS) - m3.CrossSection.circle(rc - LINE / 2, SEGMENTS))
    for k in range(SPOKES):
        a = 2 * math.pi * k / SPOKES
        spoke = m3.CrossSection.square((reach + LINE, LINE)).translate((0.0, -LINE / 2)).rotate(math.degrees(a))
        pieces.append(spoke)
    web = m3.CrossSection.batch_boolean(pieces, m3.OpType.Add) - m3.CrossSection.circle(r_open, SEGMENTS)
    return web ^ rect


def halved(spec: Spec, w: float, h: float) -> bool:
    """Whether the net prints as two halves: when the whole does not fit the bed (the paper's
    Monoprice Mini v2 has 120 x 120 mm; the net on the authors' cage is 162 x 102)."""
    bx, by, _ = spec.printer.bed
    return max(w, h) > max(bx, by) or min(w, h) > min(bx, by)


def half(web, w: float, h: float):
    """The right half (x >= SEAM_GAP / 2) of the web with a rim LINE wide along its cut: one
    closed piece that, turned over about the face's vertical axis, is the left half (the pattern
    is symmetric under a half turn: the rectangle, the rings and 22 spokes, an even number)."""
    import manifold3d as m3

    g = SEAM_GAP / 2
    keep = m3.CrossSection.square((w / 2 - g, h)).translate((g, -h / 2))
    seam = m3.CrossSection.square((LINE, h)).translate((g, -h / 2))
    return (web ^ keep) + seam


def _net(spec: Spec, frame: Frame) -> PartSpec:
    w, h = size(spec, frame)
    web = outline(w, h)
    two = halved(spec, w, h)
    if two:
        web = half(web, w, h)
    area = web.area()
    loops = [np.asarray(p, float) for p in web.to_polygons()]
    per = sum(float(np.sum(np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1))) for p in loops)
    lo, hi = np.min(np.vstack(loops), axis=0), np.max(np.vstack(loops), axis=0)
    est = Estimate(area * THICKNESS, 2 * area, per * THICKNESS, (float(hi[0] - lo[0]), float(hi[1] - lo[1]), THICKNESS))
    y, z0, z1, _, _ = face(frame)
    origin = rounded((0.0, y, (z0 + z1) / 2))
    # local +y out of the rear face: a half turn about z. The halves: the left one (seen from behind)
    # so placed, the right one the same part turned over about the face's vertical axis
    placements = ((Placement("rear_net_left", 180.0, origin), Placement("rear_net_right", 0.0, origin)) if two
                  else (Placement("rear_net", 180.0, origin),))
    params = (("size", (w, h)), ("thickness", THICKNESS), ("line", LINE), ("opening_d", OPENING_D), ("spokes", SPOKES),
              ("halves", two))
    return PartSpec("rear_net", NAME, "exoskeleton", spec.joints.material, 1.0, placements, (), LINE, est, params)


# -- the solid --------------------------------------------------------------------------------

# local (x along the face, y out of the cage, z up) -> print (x, y on the bed, z = the thickness)
_LIE_FLAT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(_LIE_FLAT, (0.0, 0.0, float(part.param("thickness")) / 2))


def solid(part: PartSpec) -> Built:
    """The web extruded THICKNESS on the bed: one face, its outer loop the rectangle and every
    cell and the window holes in it."""
    import cadquery as cq

    w, h = (float(v) for v in part.param("size"))
    t = float(part.param("thickness"))
    web = outline(w, h)
    if part.param("halves"):
        web = half(web, w, h)
    loops = [np.asarray(p, float) for p in web.to_polygons()]
    # in print, local z (up the face) runs along -y: the web's second coordinate flips
    wires = [cq.Wire.makePolygon([cq.Vector(float(x), -float(v), 0.0) for x, v in p], close=True) for p in loops]
    areas = [0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])) for p in loops]
    outer = [wr for wr, a in zip(wires, areas) if a > 0]
    if len(outer) != 1:
        raise RuntimeError(f"the rear net's outline came out as {len(outer)} pieces instead of one")
    holes = [wr for wr, a in zip(wires, areas) if a < 0]
    shape = cq.Solid.extrudeLinear(cq.Face.makeFromWires(outer[0], holes), cq.Vector(0.0, 0.0, t))
    return Built(shape, print_from_local(part))

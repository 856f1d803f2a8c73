"""The companion computer's mount (ABS/PLA): an open frame over the FC/ESC stack, printed as it sits.
A bar runs across the plate under each column of holes (the computer's and the stack's), wide enough
for the nut or screw head bearing on it; two rails along the plate's long edges tie the bars, and the
plate between them is open, the way the authors' own support (`RPI_Support_new`) is a frame of
bars between its holes rather than a plate.
"""

from __future__ import annotations

import math

import numpy as np

from ..frame import COMPUTER_LIFT, Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts.blocks import plate
from ..parts.joint_solid import Built
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import Estimate, HardwareLine, PartSpec, Placement
from .base import rounded

NAME = "computer_mount"
SIZE_KEY = "core.computer.hole_spacing"
DOC = "ABS/PLA open frame for the companion computer over the stack"

COMPUTER_T = 2.0  # mm, the frame's thickness: the authors' RPI_Support_new is 2.0 thick (the 6 mm screws still fill the nut)
RAIL = 2.4  # mm, a rail beside a window: two lines of the widest nozzle the spec allows (1.2 mm)
BEARING_WALL = 1.2  # mm of frame beyond a nut's or head's flats: at least two lines of the printer's nozzle
MIN_WINDOW = 3.0  # mm: a narrower gap between bars stays closed (a sliver of window saves nothing)


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_computer_mount(spec, frame),) if spec.core.computer else ()


def bar_half_width(screw_name: str, nozzle: float) -> float:
    """Half the width of the bar under a column of holes: the larger of the nut and the screw head
    bears on it, plus two lines of the nozzle (at least BEARING_WALL)."""
    s = SCREWS[screw_name]
    return max(s.head_d, s.nut_af) / 2 + max(BEARING_WALL, 2 * nozzle)


def windows(a: float, b: float, columns: list[tuple[float, float]]) -> tuple[tuple[float, float, float, float], ...]:
    """The frame's openings (x0, y0, x1, y1): the gaps across the plate between the bars (each bar
    is (x, half width), cut to the plate), between the two rails."""
    spans = sorted((max(-a / 2, x - h), min(a / 2, x + h)) for x, h in columns)
    merged: list[list[float]] = []
    for lo, hi in spans:
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    edges = [-a / 2] + [v for m in merged for v in m] + [a / 2]
    y = b / 2 - RAIL
    if y * 2 < MIN_WINDOW:
        return ()
    out = []
    for x0, x1 in zip(edges[0::2], edges[1::2]):
        # the plate's short edges are no bar: a gap reaching one keeps a rail's width there
        x0 = x0 + RAIL if x0 == -a / 2 else x0
        x1 = x1 - RAIL if x1 == a / 2 else x1
        if x1 - x0 >= MIN_WINDOW:
            out.append((round(x0, 4), round(-y, 4), round(x1, 4), round(y, 4)))
    return tuple(out)


def _computer_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    comp = c.computer
    box = frame.core.computer
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    a, b = box.size[0], max(box.size[1], pitch + 8.0)
    t = COMPUTER_T
    screw_pi, screw_st = SCREWS[comp.screw], SCREWS[c.stack_screw]
    hw_, hh_ = comp.hole_spacing
    pi_holes = tuple((sx * hw_ / 2, sy * hh_ / 2) for sx in (-1, 1) for sy in (-1, 1))
    st_holes = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    nozzle = spec.printer.nozzle
    columns = [(x, bar_half_width(comp.screw, nozzle)) for x in sorted({x for x, _ in pi_holes})]
    columns += [(x, bar_half_width(c.stack_screw, nozzle)) for x in sorted({x for x, _ in st_holes})]
    wins = windows(a, b, columns)
    # closed form: the plate less its windows and its holes (every hole lies in a bar, clear of the windows)
    hole_d = [screw_pi.clearance_d] * 4 + [screw_st.clearance_d] * 4
    hole_a = sum(np.pi / 4 * d**2 for d in hole_d)
    win_a = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in wins)
    win_p = sum(2 * (x1 - x0 + y1 - y0) for x0, y0, x1, y1 in wins)
    area = a * b - win_a - hole_a
    est = Estimate(area * t, 2 * area, (2 * (a + b) + win_p + sum(np.pi * d for d in hole_d)) * t, (a, b, t))
    params = (("size", (a, b)), ("thickness", t), ("computer_holes", pi_holes), ("computer_hole_d", screw_pi.clearance_d),
              ("stack_holes", st_holes), ("stack_hole_d", screw_st.clearance_d), ("windows", wins))
    # the board stands on nylon spacers over the stack screws' heads: the screw passes board,
    # spacer and frame and fills its nut (the shortest stock length that does)
    from ..materials import BOARDS

    grip = BOARDS["pi_zero"].size[2] + COMPUTER_LIFT + t
    length = float(next((L for L in screw_pi.lengths if L >= grip + screw_pi.nut_m - 1e-9), screw_pi.lengths[-1]))
    # M2.5 nylon spacer: a 5 mm hexagon less its 2.5 mm bore, PA66 at 1.14 g/cm^3
    spacer_g = round((math.sqrt(3) / 2 * screw_pi.nut_af**2 - math.pi / 4 * screw_pi.d**2) * COMPUTER_LIFT * 1.14e-3, 3)
    hw = (HardwareLine(f"{screw_pi.name} x {length:g} screw + nut ({comp.name} to mount)", 4, round(screw_pi.mass_of(length) + 0.15, 3)),
          HardwareLine(f"{screw_pi.name} x {COMPUTER_LIFT:g} mm nylon spacer ({comp.name} over the stack screws' heads)", 4,
                       spacer_g))
    return PartSpec("computer_mount", "computer_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded((box.centre[0], box.centre[1], box.lo[2] - COMPUTER_LIFT - t / 2))),), (), t, est,
                    params, hw)


# -- the solid --------------------------------------------------------------------------------

def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, float(part.param("thickness")) / 2))


def solid(part: PartSpec) -> Built:
    import cadquery as cq

    a, b = (float(v) for v in part.param("size"))
    t = float(part.param("thickness"))
    shape = plate(a, b, t, [(float(part.param("computer_hole_d")), part.param("computer_holes")),
                             (float(part.param("stack_hole_d")), part.param("stack_holes"))])
    tools = [cq.Solid.makeBox(x1 - x0, y1 - y0, t + 2.0, cq.Vector(x0, y0, -1.0)) for x0, y0, x1, y1 in part.param("windows")]
    if tools:
        shape = shape.cut(*tools).clean()
    return Built(shape, print_from_local(part))

"""The companion computer's mount (ABS/PLA): a flat plate over the FC/ESC stack with the
computer's holes and the stack holes, printed as it sits.
"""

from __future__ import annotations

import numpy as np

from ..frame import Frame
from ..materials import SCREWS, STACK_PATTERNS
from ..parts.blocks import plate
from ..parts.joint_solid import Built
from ..parts.joint_plan import transform
from ..spec import Spec
from ..parts.record import HardwareLine, PartSpec, Placement
from .base import plate_estimate, rounded

NAME = "computer_mount"
SIZE_KEY = "core.computer.hole_spacing"
DOC = "ABS/PLA plate for the companion computer over the stack"


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_computer_mount(spec, frame),) if spec.core.computer else ()

def _computer_mount(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    comp = c.computer
    box = frame.core.computer
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    a, b = box.size[0], max(box.size[1], pitch + 8.0)
    t = 2.5
    screw_pi, screw_st = SCREWS[comp.screw], SCREWS[c.stack_screw]
    hw_, hh_ = comp.hole_spacing
    pi_holes = tuple((sx * hw_ / 2, sy * hh_ / 2) for sx in (-1, 1) for sy in (-1, 1))
    st_holes = tuple((sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1))
    est = plate_estimate(a, b, t, [screw_pi.clearance_d] * 4 + [screw_st.clearance_d] * 4)
    params = (("size", (a, b)), ("thickness", t), ("computer_holes", pi_holes), ("computer_hole_d", screw_pi.clearance_d),
              ("stack_holes", st_holes), ("stack_hole_d", screw_st.clearance_d))
    hw = (HardwareLine(f"{screw_pi.name} x 6 screw + nut ({comp.name} to mount)", 4, screw_pi.mass_g + 0.15),)
    return PartSpec("computer_mount", "computer_mount", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded((box.centre[0], box.centre[1], box.lo[2] - t / 2))),), (), t, est, params, hw)


# -- the solid --------------------------------------------------------------------------------

def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, float(part.param("thickness")) / 2))


def solid(part: PartSpec) -> Built:
    a, b = (float(v) for v in part.param("size"))
    t = float(part.param("thickness"))
    shape = plate(a, b, t, [(float(part.param("computer_hole_d")), part.param("computer_holes")),
                             (float(part.param("stack_hole_d")), part.param("stack_holes"))])
    return Built(shape, print_from_local(part))

"""The core plate (ABS/PLA): a flat plate with the FC/ESC stack holes and the core links' bolt
holes, printed as it sits (translated up by half its thickness); its local frame is centred on
its placement origin, axes as the frame.
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
from .base import link_hole, plate_estimate, rounded

NAME = "core_plate"
SIZE_KEY = "core.plate_size"
DOC = "ABS/PLA core plate with stack and core-link holes"


# An M2 hex nylon standoff (4 mm across flats, threaded through): PA66 at 1.14 g/cm^3 over the
# hexagon less the M2 thread's core, about 11.8 mm^2.
NYLON_STANDOFF_G_PER_MM = 0.0135


def plan(spec: Spec, frame: Frame) -> tuple[PartSpec, ...]:
    return (_core_plate(spec, frame),)

def _core_plate(spec: Spec, frame: Frame) -> PartSpec:
    c = spec.core
    pitch, _ = STACK_PATTERNS[c.stack_pattern]
    screw = SCREWS[c.stack_screw]
    hole = link_hole(spec)
    holes = [(sx * pitch / 2, sy * pitch / 2) for sx in (-1, 1) for sy in (-1, 1)]
    holes += [(sx * hole, sy * hole) for sx in (-1, 1) for sy in (-1, 1)]
    est = plate_estimate(c.plate_size, c.plate_size, c.plate_thickness, [screw.clearance_d] * len(holes))
    params = (("size", c.plate_size), ("thickness", c.plate_thickness), ("holes", tuple(holes)), ("hole_d", screw.clearance_d))
    hang = frame.core.hang
    if hang > 0:
        # level arms: the plate stands on four standoffs on the holder; the stack screws end in
        # their tops, short screws come up through the holder (and spacer) into their bottoms
        hw = (HardwareLine(f"{screw.name} x 20 screw + 8 mm nylon standoffs (FC/ESC stack onto the plate)", 4, 1.0),
              HardwareLine(f"{screw.name} x {hang:g} mm nylon standoff, female-female (plate on the battery holder)", 4,
                           round(NYLON_STANDOFF_G_PER_MM * hang, 3)),
              HardwareLine(f"{screw.name} x 6 screw (battery holder to standoff)", 4, screw.mass_of(6)))
    else:
        hw = (HardwareLine(f"{screw.name} x 20 screw + 8 mm nylon standoffs (FC/ESC stack through plate and holder)", 4, 1.0),)
    return PartSpec("core_plate", "core_plate", "core", c.material, c.infill,
                    (Placement("core", 0.0, rounded(frame.core.plate.centre)),), (), c.plate_thickness, est, params, hw)


# -- the solid --------------------------------------------------------------------------------

def print_from_local(part: PartSpec) -> np.ndarray:
    return transform(np.eye(3), (0.0, 0.0, float(part.param("thickness")) / 2))


def solid(part: PartSpec) -> Built:
    size = float(part.param("size"))
    t = float(part.param("thickness"))
    shape = plate(size, size, t, [(float(part.param("hole_d")), part.param("holes"))])
    return Built(shape, print_from_local(part))

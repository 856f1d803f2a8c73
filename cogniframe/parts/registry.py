"""Family name -> CAD build function and print transform.

`build(part)` returns a `Built` (solid in print orientation, bed at z = 0, plus the 4x4
print <- local transform); `print_from_local(part)` gives the transform alone, with no CAD import.
Unknown families raise ValueError listing the valid ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..partlist import PartSpec
from . import core, joint, motor_mount


@dataclass(frozen=True)
class Family:
    name: str
    build: Callable[[PartSpec], joint.Built]
    print_from_local: Callable[[PartSpec], np.ndarray]
    size_key: str  # the params key that drives this part's size (for "does not fit the bed" errors)
    doc: str


FAMILIES: dict[str, Family] = {f.name: f for f in (
    Family("joint", joint.build, joint.print_from_local, "joints.socket_depth",
           "TPU joint (corner_top, corner_bottom, knee, core_link) generated from its sockets"),
    Family("motor_mount", motor_mount.build, motor_mount.print_from_local, "motors.model",
           "TPU motor seat clipped around the two arm rods"),
    Family("core_plate", core.build_plate, core.plate_from_local, "core.plate_size",
           "ABS/PLA core plate with stack and core-link holes"),
    Family("battery_holder", core.build_holder, core.holder_from_local, "core.battery",
           "ABS/PLA open-ended battery sleeve, printed on its back stop"),
    Family("sensor_mount", core.build_sensor_mount, core.sensor_mount_from_local, "core.spacer_thickness",
           "ABS/PLA X spacer between holder and plate, with the flow board pad and zip-tie slots, printed flat"),
    Family("camera_mount", core.build_camera_mount, core.camera_mount_from_local, "core.camera",
           "ABS/PLA camera bracket (base under the FC stack, tilted upright), printed on its side"),
    Family("computer_mount", core.build_computer_mount, core.plate_from_local, "core.computer.hole_spacing",
           "ABS/PLA plate for the companion computer over the stack"),
)}


def get(name: str) -> Family:
    try:
        return FAMILIES[name]
    except KeyError:
        raise ValueError(f"unknown part family {name!r}; valid families: {', '.join(sorted(FAMILIES))}") from None


def families() -> tuple[str, ...]:
    """The family names, sorted."""
    return tuple(sorted(FAMILIES))


def sizes() -> dict[str, str]:
    """Family name -> one-line description (the `sizes()`-like listing)."""
    return {name: FAMILIES[name].doc for name in families()}


def build(part: PartSpec) -> joint.Built:
    return get(part.family).build(part)


def print_from_local(part: PartSpec) -> np.ndarray:
    return get(part.family).print_from_local(part)

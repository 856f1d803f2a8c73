"""The registered part families, in part-list order, and lookups by family name.

A family module provides `NAME`, `SIZE_KEY` (the params key that drives its size, for "does not
fit the bed" errors), `DOC`, `plan(spec, frame)` (its parts, none when the design has no such
part; a family placed from an earlier family's parts says so with `PLANS_FROM_EARLIER = True`,
and `partlist.part_list` then gives it the parts planned before it, `plan(spec, frame, earlier)`:
the core plate's peg tubes come from the joint family's core links, not planned again), `solid(part)` (a `parts.joint_solid.Built`: the solid in print orientation, bed at z = 0, and the
4x4 print <- local transform) and `print_from_local(part)` (the transform alone, no CAD import).
Adding a family: its module, one line in `FAMILIES`, and its params section in spec.py.
"""

from __future__ import annotations

from types import ModuleType

import numpy as np

from . import battery_holder, camera_mount, computer_mount, core_plate, joint, motor_mount, net, sensor_mount
from ..parts.record import PartSpec

FAMILIES: tuple[ModuleType, ...] = (joint, motor_mount, core_plate, battery_holder, sensor_mount, camera_mount,
                                    computer_mount, net)


def get(name: str) -> ModuleType:
    """The family module called `name`; ValueError listing the valid names when there is none."""
    for f in FAMILIES:
        if f.NAME == name:
            return f
    raise ValueError(f"unknown part family {name!r}; valid families: {', '.join(families())}")


def families() -> tuple[str, ...]:
    """The family names, sorted."""
    return tuple(sorted(f.NAME for f in FAMILIES))


def sizes() -> dict[str, str]:
    """Family name -> one-line description."""
    return {name: get(name).DOC for name in families()}


def solid(part: PartSpec):
    """The part's solid in print orientation (a `parts.joint_solid.Built`)."""
    return get(part.family).solid(part)


def print_from_local(part: PartSpec) -> np.ndarray:
    return get(part.family).print_from_local(part)

"""The screws, nuts and inserts that hold the aircraft together, each at its hole (NopSCADlib's
screws and nuts as vitamins).

Pure numpy, from the part list: a part that is screwed to something says so in its plan (the
motor mount's `holes`, `screw`, `screw_length`, `grip`), and this module places one `Fastener`
per hole of every placed copy, in world coordinates. `vitamins.py` draws them, the BOM counts
them, the clash check tests them and `analysis/fit_check.py` checks that each passes through the
holes it joins and engages its thread by a sensible length without reaching past it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .materials import SCREWS

Vec = tuple[float, float, float]


@dataclass(frozen=True)
class Fastener:
    """One screw (or nut) in the assembly.

    `base`: the point on the screw's axis where its head bears on the part (a nut: its bearing
    face); `axis`: unit vector from the head toward the tip. `joins`: the part copies it passes
    through and their clearance hole (name, hole diameter); `grip`: their thickness under the
    head (mm). `thread`: the copy or vitamin whose thread it engages (`motor_fl`, or a nut's name),
    `engagement` how far into it (mm) and `thread_depth` the most it may enter (None: a through
    nut)."""

    name: str  # screw_motor_fl_1, nut_core_link_fl
    kind: str  # screw | nut
    size: str  # M2
    length: float  # screw: length under the head; nut: thickness
    base: Vec
    axis: Vec
    joins: tuple[tuple[str, float], ...]
    grip: float
    thread: str
    engagement: float
    thread_depth: float | None
    bom: str
    budget_line: str  # the mass budget's hardware line that holds its mass

    def tip(self) -> np.ndarray:
        return np.asarray(self.base) + np.asarray(self.axis) * self.length


def _t(v) -> Vec:
    return (round(float(v[0]), 6) + 0.0, round(float(v[1]), 6) + 0.0, round(float(v[2]), 6) + 0.0)


def motor_screws(spec, parts) -> list[Fastener]:
    """The motor's mounting screws: up through each hole of each motor mount into the motor's base."""
    mount = next((p for p in parts if p.family == "motor_mount"), None)
    if mount is None or "holes" not in dict(mount.params):
        return []
    motor = spec.motor
    size = str(mount.param("screw"))
    length, grip = float(mount.param("screw_length")), float(mount.param("grip"))
    seat_z = float(mount.param("seat_z"))
    hole_d = float(mount.param("screw_clearance"))
    line = next((h.item for h in mount.hardware if "screw" in h.item), "")
    out = []
    for pl in mount.placements:
        m = pl.matrix()
        corner = pl.instance.split("_")[-1]
        for i, (x, y) in enumerate(mount.param("holes"), start=1):
            base = m[:3, :3] @ np.array([x, y, seat_z - grip]) + m[:3, 3]
            out.append(Fastener(f"screw_motor_{corner}_{i}", "screw", size, length, _t(base), (0.0, 0.0, 1.0),
                                ((f"motor_mount_{corner}", hole_d),), grip, f"motor_{corner}", round(length - grip, 4),
                                motor.thread_depth, f"{size} x {length:g} socket-head screw (ISO 4762)", line))
    return out


def fasteners(spec, frame, parts) -> tuple[Fastener, ...]:
    """Every screw and nut of the design, in a stable order."""
    return tuple(motor_screws(spec, parts))


def screw_of(f: Fastener):
    return SCREWS[f.size]

"""The screws, nuts and inserts that hold the aircraft together, each at its hole (NopSCADlib's
screws and nuts as vitamins).

Pure numpy, from the part list: a part that is screwed to something says so in its plan (the
motor mount's `holes`, `screw`, `screw_length`, `grip`), and this module places one `Fastener`
per hole of every placed copy, in world coordinates. `vitamins.py` draws them, the BOM counts
them, the clash check tests them and `analysis/fit_check.py` checks that each passes through the
holes it joins and engages its thread by a sensible length without reaching past it.
"""

from __future__ import annotations

import math
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
    boards: tuple[str, ...] = ()  # bought boards it passes through by their mounting holes (drawn without holes)

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


def _screw_and_nut(name: str, size: str, length: float, head, axis, layers, part: str, hole_d: float,
                   board: str, board_hole: float, line: str) -> list[Fastener]:
    """A screw through a bought board and a printed part, held by a nut on the far side: `head` the
    head's bearing point, `layers` the thicknesses under it (board, part)."""
    sc = SCREWS[size]
    head, axis = np.asarray(head, float), np.asarray(axis, float)
    grip = float(sum(layers))
    nut = f"nut_{name}"
    return [Fastener(f"screw_{name}", "screw", size, length, _t(head), _t(axis), ((board, board_hole), (part, hole_d)), grip,
                     nut, round(length - grip, 4), None, f"{size} x {length:g} socket-head screw (ISO 4762)", line, (board,)),
            Fastener(nut, "nut", size, sc.nut_m, _t(head + axis * grip), _t(axis), (), 0.0, "", 0.0, None,
                     f"{size} hex nut (ISO 4032)", line)]


def _line(part, word: str) -> str:
    return next((h.item for h in part.hardware if word in h.item), "")


def camera_screws(spec, frame, parts) -> list[Fastener]:
    """The camera board's screws: from its front face through the board and the mount's upright,
    nuts behind the upright."""
    from .materials import BOARDS
    from .families.camera_mount import CAMERA_WALL

    mount = next((p for p in parts if p.family == "camera_mount"), None)
    if mount is None or spec.core.camera is None:
        return []
    g = dict(mount.params)
    board = BOARDS[spec.core.camera.model]
    m = camera_world(frame, g)
    length = _length_of(_line(mount, "camera"), 6.0)
    out = []
    for i, (x, z) in enumerate(g["camera_holes"], start=1):
        # the vitamin's frame: z from the base top (the mount's upright coordinates less the base)
        head = m[:3, :3] @ np.array([x, board.size[2], z - g["base_t"]]) + m[:3, 3]
        axis = m[:3, :3] @ np.array([0.0, -1.0, 0.0])
        out += _screw_and_nut(f"camera_{i}", "M2", length, head, axis, (board.size[2], CAMERA_WALL), "front_camera_mount",
                              float(g["camera_hole_d"]), "camera", board.hole_d, _line(mount, "camera"))
    return out


def camera_world(frame, g: dict) -> np.ndarray:
    """4x4 world <- camera-upright frame (families/camera_mount.camera_upright_matrix raised onto the core
    plate): where the camera board's screws go here and where `vitamins` draws the board."""
    a = math.radians(float(g["tilt_deg"]))
    m = np.eye(4)
    m[:3, :3] = [[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]]
    m[:3, 3] = (0.0, float(g["y_front"]), float(frame.core.plate.hi[2]) + float(g["base_t"]))
    return m


def computer_screws(spec, frame, parts) -> list[Fastener]:
    """The companion computer's screws: down through the board and the mount plate, nuts under it."""
    from .materials import BOARDS

    mount = next((p for p in parts if p.family == "computer_mount"), None)
    if mount is None or frame.core.computer is None or spec.core.computer is None:
        return []
    board = BOARDS["pi_zero"]
    size = spec.core.computer.screw
    line = _line(mount, "screw")
    length = _length_of(line, 6.0)
    c = frame.core.computer
    t = float(mount.param("thickness"))
    out = []
    for i, (x, y) in enumerate(mount.param("computer_holes"), start=1):
        head = (c.centre[0] + x, c.centre[1] + y, float(c.lo[2]) + board.size[2])
        out += _screw_and_nut(f"computer_{i}", size, length, head, (0.0, 0.0, -1.0), (board.size[2], t), "computer_mount",
                              float(mount.param("computer_hole_d")), "computer", board.hole_d, line)
    return out


def _length_of(item: str, default: float) -> float:
    """The screw length a hardware line names ("M2 x 6 screw ..." -> 6)."""
    import re

    m = re.search(r"\bM\d+(?:\.\d+)?\s*x\s*(\d+(?:\.\d+)?)", item)
    return float(m.group(1)) if m else default


def fasteners(spec, frame, parts) -> tuple[Fastener, ...]:
    """Every screw and nut of the design, in a stable order."""
    return tuple(motor_screws(spec, parts) + camera_screws(spec, frame, parts) + computer_screws(spec, frame, parts))


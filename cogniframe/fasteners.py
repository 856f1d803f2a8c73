"""The screws, nuts and standoffs that hold the aircraft together, each at its hole (NopSCADlib's
screws, nuts and spacers as vitamins).

Pure numpy, from the part list: a part that is screwed to something says so in its plan (the
motor mount's `holes`, `screw`, `screw_length`, `grip`; the battery holder's and the core plate's
stack holes), and this module places one `Fastener` per hole of every placed copy, in world
coordinates. Every screw, nut and standoff of the mass budget's hardware lines is one here (its
`budget_line` names the line): `vitamins.py` draws them, the BOM counts them, the clash check
tests them and `analysis/fit_check.py` checks that each passes through the holes it joins,
engages its thread by a sensible length without reaching past it, can be turned by its driver
and keeps out of the battery's slide path.

The core's stack, bottom up (level arms): four countersunk screws from inside the battery holder
(their heads flush with the cavity's ceiling, so the pack slides under them; driven from below
through the holder's floor window) up through the holder's top wall (and the spacer's bar) into
the bottom of four female-female standoffs; the core plate on the standoffs; the camera mount's
base, the ESC on its grommets, the 8 mm spacers, the FC (and, with a companion computer, the
spacers and the computer mount on top), clamped by four socket-head screws from the top into the
standoffs' tops. Without level arms the plate sits on the holder: one long countersunk screw per
hole from inside the holder up through everything, a nut on top.

`stage` says when a fastener goes in (`STAGES`, the assembly guide's order): its driver must
clear what is already built then, not what comes later.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .materials import SCREWS

Vec = tuple[float, float, float]

# When each thing is fitted, in the assembly guide's order (report/assembly_steps.py follows it):
# the cage with its arms (the motors are screwed onto their mounts while the mounts' sleeves are
# threaded on the arm rods), the struts, the core off the frame, the camera and flow sensor, the
# FC/ESC stack (and the computer mount it clamps), the computer, and last the propellers and the
# battery. A fastener's driver must clear everything fitted at its stage or before.
STAGES = ("frame", "struts", "core", "sensors", "stack", "computer", "last")



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
    head: str = "socket"  # screw: socket (ISO 4762, on the part's face) | countersunk (ISO 7046, flush in it); else ""
    stage: str = "frame"  # when it goes in (STAGES)

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
                   board: str, board_hole: float, line: str, stage: str, boards: tuple[str, ...] = ()) -> list[Fastener]:
    """A screw through a bought board and a printed part, held by a nut on the far side: `head` the
    head's bearing point, `layers` the thicknesses under it (board, part, and any spacer between:
    `boards` names those)."""
    sc = SCREWS[size]
    head, axis = np.asarray(head, float), np.asarray(axis, float)
    grip = round(float(sum(layers)), 4)
    nut = f"nut_{name}"
    return [Fastener(f"screw_{name}", "screw", size, length, _t(head), _t(axis), ((board, board_hole), (part, hole_d)), grip,
                     nut, round(length - grip, 4), None, f"{size} x {length:g} socket-head screw (ISO 4762)", line,
                     (board, *boards), stage=stage),
            Fastener(nut, "nut", size, sc.nut_m, _t(head + axis * grip), _t(axis), (), 0.0, "", 0.0, None,
                     f"{size} hex nut (ISO 4032)", line, head="", stage=stage)]


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
                              float(g["camera_hole_d"]), "camera", board.hole_d, _line(mount, "camera"), "sensors")
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
    """The companion computer's screws: down through the board, a nylon spacer (the board stands
    `frame.COMPUTER_LIFT` over the mount, clear of the stack screws' heads) and the mount plate,
    nuts under it."""
    from .frame import COMPUTER_LIFT
    from .materials import BOARDS

    mount = next((p for p in parts if p.family == "computer_mount"), None)
    if mount is None or frame.core.computer is None or spec.core.computer is None:
        return []
    board = BOARDS["pi_zero"]
    size = spec.core.computer.screw
    line = _line(mount, "screw")
    spacer_line = _line(mount, "spacer")
    length = _length_of(line, 6.0)
    c = frame.core.computer
    t = float(mount.param("thickness"))
    out = []
    for i, (x, y) in enumerate(mount.param("computer_holes"), start=1):
        head = (c.centre[0] + x, c.centre[1] + y, float(c.lo[2]) + board.size[2])
        out += _screw_and_nut(f"computer_{i}", size, length, head, (0.0, 0.0, -1.0), (board.size[2], COMPUTER_LIFT, t),
                              "computer_mount", float(mount.param("computer_hole_d")), "computer", board.hole_d, line, "computer",
                              (f"spacer_computer_{i}",))
        out.append(_standoff(f"spacer_computer_{i}", size, (head[0], head[1], float(c.lo[2]) - COMPUTER_LIFT), COMPUTER_LIFT,
                             spacer_line, "computer"))
    return out


def _standoff(name: str, size: str, base, length: float, line: str, stage: str, boards: tuple[str, ...] = ()) -> Fastener:
    """A nylon standoff or spacer standing on `base`, `length` tall (drawn across its hex's flats);
    `boards`: the bought boards it bears on round their mounting holes (drawn with their parts as
    one block over the holes: the pair shares that volume by design)."""
    return Fastener(name, "standoff", size, float(length), _t(base), (0.0, 0.0, 1.0), (), 0.0, "", 0.0, None,
                    line.split(" (")[0], line, boards, head="", stage=stage)


def _corner_of(name: str) -> str:
    return name.rsplit("_", 1)[-1]


def stack_fasteners(spec, frame, parts) -> list[Fastener]:
    """The core stack's screws, spacers and standoffs (families/core_plate.stack_plan; this module's
    docstring tells the order). Level arms: a standoff under the plate at each stack hole, a
    countersunk screw from inside the holder into its bottom and a socket-head screw from the top
    of the stack into its top; else one long countersunk screw from inside the holder through
    everything, a nut on top."""
    from .families.core_plate import stack_plan

    if not any(p.name == "core_plate" for p in parts):
        return []
    plan = stack_plan(spec, frame)
    sc = SCREWS[plan.screw]
    lines = {h.item for p in parts for h in p.hardware}

    def line(word: str) -> str:
        return next(h for h in sorted(lines) if word in h)

    budget = _budget_lines(spec)
    boards = ("fc_esc_stack",) if "fc_esc_stack" in budget else tuple(n for k, n in (("esc", "esc"), ("fc", "flight_controller"))
                                                                     if k in budget)
    out = []
    for g in plan.legs:
        x, y = g.xy
        spacers = []
        for z0, length, item in plan.spacers:
            kind = "esc" if "ESC" in item else "computer_mount"
            spacers.append(_standoff(f"spacer_{kind}_{g.corner}", plan.screw, (x, y, z0), length, item, "stack", boards))
        out += spacers
        if plan.level:
            standoff = f"standoff_{g.corner}"
            out.append(_standoff(standoff, plan.screw, (x, y, g.z0), g.standoff, line(f"{g.standoff:g} mm nylon standoff"), "core"))
            out.append(Fastener(f"screw_holder_{g.corner}", "screw", plan.screw, plan.holder_screw, _t((x, y, plan.ceiling)),
                                (0.0, 0.0, 1.0), g.under, g.grip, standoff, round(plan.holder_screw - g.grip, 4), g.standoff / 2,
                                f"{plan.screw} x {plan.holder_screw:g} countersunk screw (ISO 7046)", line("countersunk"),
                                head="countersunk", stage="core"))
            out.append(Fastener(f"screw_stack_{g.corner}", "screw", plan.screw, plan.stack_screw, _t((x, y, plan.head_z)),
                                (0.0, 0.0, -1.0), plan.through, plan.stack_grip, standoff,
                                round(plan.stack_screw - plan.stack_grip, 4), g.standoff / 2,
                                f"{plan.screw} x {plan.stack_screw:g} socket-head screw (ISO 4762)", line("socket-head"),
                                boards + tuple(s.name for s in spacers), stage="stack"))
        else:
            nut = f"nut_stack_{g.corner}"
            grip = round(plan.head_z - plan.ceiling, 4)
            out.append(Fastener(f"screw_stack_{g.corner}", "screw", plan.screw, plan.holder_screw, _t((x, y, plan.ceiling)),
                                (0.0, 0.0, 1.0), g.under + plan.through, grip, nut, round(plan.holder_screw - grip, 4), None,
                                f"{plan.screw} x {plan.holder_screw:g} countersunk screw (ISO 7046)", line("countersunk"),
                                boards + tuple(s.name for s in spacers), head="countersunk", stage="stack"))
            out.append(Fastener(nut, "nut", plan.screw, sc.nut_m, _t((x, y, plan.head_z)), (0.0, 0.0, 1.0), (), 0.0, "", 0.0, None,
                                f"{plan.screw} hex nut (ISO 4032)", line("countersunk"), head="", stage="stack"))
    return out


def link_screws(spec, frame, parts) -> list[Fastener]:
    """The bolted core links' screws (core.link: tab): down through each link's tab and the plate's
    corner hole, the nut in the spacer's hex trap under it (the plate on the holder) or under the
    plate (the plate on standoffs)."""
    from .families.joint_kinds.core_link_tab import LINK_TAB
    from .families.joint_kinds.kinds import core_link

    bolts = core_link(spec).plate_bolts(spec)
    links = [p for p in parts if p.family == "joint" and p.name.startswith("core_link")]
    if not bolts or not links:
        return []
    size = spec.core.stack_screw
    line = next(h.item for p in links for h in p.hardware if "core link to plate" in h.item)
    length = _length_of(line, 10.0)
    core = frame.core
    sc = SCREWS[size]
    spacer = next((p for p in parts if p.family == "sensor_mount"), None)
    out = []
    for x, y in bolts:
        corner = {(-1, 1): "fl", (1, 1): "fr", (-1, -1): "rl", (1, -1): "rr"}[(int(np.sign(x)), int(np.sign(y)))]
        xy = np.asarray(core.plate.centre[:2], float) + (x, y)
        head = (xy[0], xy[1], float(core.plate.hi[2]) + LINK_TAB)
        joins = ((f"core_link_{corner}", sc.clearance_d), ("core_plate", sc.clearance_d))
        if core.hang == 0 and spacer is not None:  # the nut in the trap at the spacer's underside
            nut_z = float(core.spacer.lo[2]) + float(spacer.param("nut_depth"))
            joins += ((spacer.name, float(spacer.param("hole_d"))),)
        else:
            nut_z = float(core.plate.lo[2])
        grip = round(head[2] - nut_z, 4)
        nut = f"nut_link_{corner}"
        out += [Fastener(f"screw_link_{corner}", "screw", size, length, _t(head), (0.0, 0.0, -1.0), joins, grip, nut,
                         round(length - grip, 4), None, f"{size} x {length:g} socket-head screw (ISO 4762)", line, stage="core"),
                Fastener(nut, "nut", size, sc.nut_m, _t((xy[0], xy[1], nut_z)), (0.0, 0.0, -1.0), (), 0.0, "", 0.0, None,
                         f"{size} hex nut (ISO 4032)", line, head="", stage="core")]
    return out


def _budget_lines(spec) -> dict[str, str]:
    """vitamin key -> the components line that carries its mass (as vitamins.py's)."""
    return {c.vitamin: c.name for c in spec.components if c.vitamin}


def _length_of(item: str, default: float) -> float:
    """The screw length a hardware line names ("M2 x 6 screw ..." -> 6)."""
    import re

    m = re.search(r"\bM\d+(?:\.\d+)?\s*x\s*(\d+(?:\.\d+)?)", item)
    return float(m.group(1)) if m else default


def fasteners(spec, frame, parts) -> tuple[Fastener, ...]:
    """Every screw, nut and standoff of the design, in a stable order."""
    return tuple(motor_screws(spec, parts) + stack_fasteners(spec, frame, parts) + link_screws(spec, frame, parts)
                 + camera_screws(spec, frame, parts) + computer_screws(spec, frame, parts))


# -- when each thing is fitted ----------------------------------------------------------------

# A printed part family's stage (STAGES); a core link joint is fitted with the core.
PART_STAGES = {"joint": "frame", "motor_mount": "frame", "battery_holder": "core", "core_plate": "core",
               "sensor_mount": "core", "camera_mount": "sensors", "computer_mount": "stack"}
VITAMIN_STAGES = {"motor": "frame", "propeller": "last", "battery": "last", "fc": "stack", "esc": "stack",
                  "computer": "computer", "camera": "sensors", "flow_sensor": "sensors"}


def part_stage(part) -> str:
    """When a printed part is fitted (a family not listed: with the frame, the earliest)."""
    if part.family == "joint" and part.name.startswith("core_link"):
        return "core"
    return PART_STAGES.get(part.family, "frame")


def rod_stage(rod) -> str:
    return "struts" if rod.role == "strut" else "frame"


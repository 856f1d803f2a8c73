"""The frozen record every flight file is written from: the design's mass properties, its rotors
and their constants, the pack and the frame's vibration against the motors. Each output format is
a pure function of one `Vehicle` (inav.py, betaflight.py, ardupilot.py, px4.py, gazebo.py,
rotorpy_params.py, campbell.py).

Axes: the record keeps the frame's (x right, y front, z up, SI). The formats turn them into their
own: FRD body axes (x front, y right, z down) for INAV, Betaflight, ArduPilot and PX4, FLU (x
front, y left, z up) for Gazebo and rotorpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.massprops import MassProps
from ..analysis.resonance import Resonance
from ..analysis.rotors import Rotor, RotorModel

# Motor order of the quad-X mixers: Betaflight's and INAV's (1 rear right, 2 front right, 3 rear
# left, 4 front left), ArduPilot's quad X (1 front right, 2 rear left, 3 front left, 4 rear
# right: libraries/SITL/SIM_Frame.cpp quad_x_motors) and PX4's quad X (the same as ArduPilot's,
# ROMFS airframes 4001_quad_x).
BF_ORDER = ("rr", "fr", "rl", "fl")
AP_ORDER = ("fr", "rl", "fl", "rr")
PX4_ORDER = AP_ORDER


@dataclass(frozen=True)
class Vehicle:
    name: str
    mass: MassProps
    rotors: tuple[Rotor, ...]
    rotor: RotorModel
    cells: int
    voltage_v: float
    capacity_mah: float
    usable_fraction: float
    resonance: Resonance
    motor: str  # e.g. "1104 6000KV"
    prop: str  # e.g. "3025"
    props_out: bool
    hover_current_a: float  # battery current at hover, motors and avionics (analysis/flight.py)
    imu_m: tuple[float, float, float]  # the flight controller's board centre relative to the centre of gravity
    cage_m: tuple[tuple[float, float, float], tuple[float, float, float]]  # the cage's joint centres' box (min, max) from the centre of gravity

    def rotor_at(self, corner: str) -> Rotor:
        return next(r for r in self.rotors if r.corner == corner)

    def ordered(self, order) -> list[Rotor]:
        return [self.rotor_at(c) for c in order]

    @property
    def hover_thrust_fraction(self) -> float:
        """Each rotor's thrust at hover over its full-throttle thrust, (w_hover / w_max)^2: what
        ArduPilot (MOT_THST_HOVER, SITL's hoverThrOut, INS_HNTCH_REF) and PX4 (MPC_THR_HOVER) mean
        by hover "throttle"; the ESC's raw throttle at hover is `rotor.hover_throttle`."""
        return (self.rotor.omega_hover / self.rotor.omega_max) ** 2

    @property
    def rotor_centre_m(self) -> np.ndarray:
        """The rotors' hubs' centroid relative to the centre of gravity (frame axes)."""
        return np.mean([r.position_m for r in self.rotors], axis=0)


def frd(v) -> tuple[float, float, float]:
    """Frame axes (x right, y front, z up) -> FRD body axes (x front, y right, z down)."""
    return (float(v[1]) + 0.0, float(v[0]) + 0.0, -float(v[2]) + 0.0)


def flu(v) -> tuple[float, float, float]:
    """Frame axes -> FLU body axes (x front, y left, z up)."""
    return (float(v[1]) + 0.0, -float(v[0]) + 0.0, float(v[2]) + 0.0)


def inertia_in(axes: str, inertia: np.ndarray) -> np.ndarray:
    """The inertia tensor in FRD or FLU body axes (R I R^T with R the axis change)."""
    rows = {"frd": [[0, 1, 0], [1, 0, 0], [0, 0, -1]], "flu": [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]}[axes]
    r = np.asarray(rows, float)
    out = r @ np.asarray(inertia, float) @ r.T
    return out + 0.0  # no negative zeros in the files


def vehicle_of(spec, design, budget, mass: MassProps, resonance: Resonance) -> Vehicle:
    from ..analysis import flight
    from ..analysis import rotors as rotors_mod

    rot = rotors_mod.rotors(spec, design.frame, mass.cg_m)
    model = rotors_mod.model(spec, mass.mass_kg, len(rot))
    b = spec.core.battery
    kv = spec.motors.kv or flight.default_kv(spec.motor.name)
    fr = flight.evaluate(spec, mass.mass_kg * 1000.0, len(rot))
    imu = np.asarray(design.frame.core.stack.centre, float) / 1000.0 - np.asarray(mass.cg_m)
    lo, hi = (np.asarray(c, float) / 1000.0 - np.asarray(mass.cg_m) for c in design.frame.bbox())
    return Vehicle(spec.name, mass, rot, model, b.cells, b.cells * flight.CELL_V, b.capacity_mah, b.usable_fraction,
                   resonance, f"{spec.motor.name} {kv}KV", flight.prop_name(spec), bool(spec.motors.props_out),
                   fr.hover_current_a, (float(imu[0]), float(imu[1]), float(imu[2])),
                   (tuple(float(x) for x in lo), tuple(float(x) for x in hi)))

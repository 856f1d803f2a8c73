"""px4/sih.params and px4/10090_sihsim_cogniframe (a PX4 airframe).

sih.params: PX4's Simulation-In-Hardware vehicle (PX4/PX4-Autopilot
src/modules/simulation/simulator_sih/sih_params.yaml, main at 676c4b0): SIH_MASS (kg), SIH_IXX ..
SIH_IYZ (kg m^2, FRD body axes), SIH_T_MAX and SIH_Q_MAX (one propeller's thrust, N, and torque,
N m, at full speed), SIH_L_ROLL and SIH_L_PITCH (half the left-right and the front-rear distance
between the motors, m), SIH_KDV and SIH_KDW (linear drag and angular damping, `drag`), SIH_T_TAU
(thruster time constant, s), SIH_VEHICLE_TYPE 0 (quadcopter). QGroundControl's parameter file
format: vehicle id, component id, name, value, MAVLink type (9 float, 6 int32), tab separated.

SIH's rotors are linear in the command (sih.cpp `generate_force_and_torques`: thrust = -SIH_T_MAX
(u0 + u1 + u2 + u3)), so under SIH the thrust model factor THR_MDL_FAC is 0 and the hover thrust
MPC_THR_HOVER is mass g / (4 SIH_T_MAX) = `Vehicle.hover_thrust_fraction`. On the real aircraft
the ESC's curve is the flight table's (THR_MDL_FAC = its expo: PX4's rel_thrust = f u^2 + (1 - f) u,
the form `RotorModel.thrust_expo` fits), and MPC_THR_HOVER, a normalised thrust after that
linearisation, is the same fraction.

The airframe is an init.d-posix airframe as PX4's own 10040_sihsim_quadx
(ROMFS/px4fmu_common/init.d-posix/airframes, d6e5981): the number prefix makes PX4 list it (copy
it there and `make px4_sitl sihsim_cogniframe`), PX4_SIMULATOR=sihsim, the simulated sensors, the
control allocation (src/modules/control_allocator/module.yaml: CA_AIRFRAME 0 multirotor,
CA_ROTOR_COUNT, CA_ROTORn_PX / _PY / _PZ in m, FRD, from the centre of gravity, CA_ROTORn_KM torque
per thrust, positive for a counter-clockwise rotor), the motor outputs (PWM_MAIN_FUNCn and
SIM_GZ_EC_FUNCn = 101 .. 104, Motor 1 .. 4), the SIH vehicle, the hover thrust and the gyro filters
(IMU_GYRO_CUTOFF, IMU_DGYRO_CUTOFF, src/modules/sensors/vehicle_angular_velocity). Rotor numbers
follow PX4's quad X (4001_quad_x): 0 front right, 1 rear left, 2 front left, 3 rear right.
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis.constants import RHO_AIR
from .vehicle import PX4_ORDER, Vehicle, frd, inertia_in

AIRFRAME_ID = 10090  # after PX4's own SIH airframes (10040 .. 10047); any unused number works
AIRFRAME_NAME = "sihsim_cogniframe"
AIRFRAME_FILE = f"px4/{AIRFRAME_ID}_{AIRFRAME_NAME}"
MOTOR_FUNCTION = 101  # PX4's output function "Motor 1" (mixer_module output_functions.yaml); Motor n is 100 + n
# Drag coefficient of the cage falling flat: a flat plate across the flow is 1.17; the open cage
# lets air through, the propeller discs inside it hold it back: 1.0 stands for the two.
CAGE_CD = 1.0


def drag(v: Vehicle) -> tuple[float, float]:
    """(SIH_KDV N/(m/s), SIH_KDW N m/(rad/s)) for this aircraft. SIH's drag is linear, D = -KDV v,
    so its freefall speed is m g / KDV (sih_params.yaml); the cage's quadratic drag
    1/2 rho CAGE_CD A v^2 (A its plan area) gives a terminal speed v_t = sqrt(2 m g / (rho CAGE_CD A)).
    Equal freefall speeds: KDV = m g / v_t = sqrt(m g rho CAGE_CD A / 2). The same drag per unit
    speed at the rotors' distance L from the centre of gravity, where a turn at w moves them at
    w L, gives the damping moment KDV L^2 w: KDW = KDV L^2."""
    from ..analysis.constants import G

    (x0, y0, _), (x1, y1, _) = v.cage_m
    area = (x1 - x0) * (y1 - y0)
    kdv = math.sqrt(v.mass.mass_kg * G * RHO_AIR * CAGE_CD * area / 2)
    arm = float(np.mean([math.hypot(*r.position_m[:2]) for r in v.rotors]))
    return kdv, kdv * arm**2


def sih_values(v: Vehicle) -> list[tuple[str, float | int]]:
    i = inertia_in("frd", v.mass.inertia)
    pos = np.array([frd(r.position_m) for r in v.rotors])
    kdv, kdw = drag(v)
    return [("SIH_VEHICLE_TYPE", 0), ("SIH_MASS", round(v.mass.mass_kg, 5)),
            ("SIH_IXX", float(f"{i[0, 0]:.6g}")), ("SIH_IYY", float(f"{i[1, 1]:.6g}")), ("SIH_IZZ", float(f"{i[2, 2]:.6g}")),
            ("SIH_IXY", float(f"{i[0, 1]:.6g}")), ("SIH_IXZ", float(f"{i[0, 2]:.6g}")), ("SIH_IYZ", float(f"{i[1, 2]:.6g}")),
            ("SIH_T_MAX", round(v.rotor.thrust_max_n, 4)), ("SIH_Q_MAX", float(f"{v.rotor.torque_max_nm:.6g}")),
            ("SIH_L_ROLL", round(float(np.abs(pos[:, 1]).mean()), 5)), ("SIH_L_PITCH", round(float(np.abs(pos[:, 0]).mean()), 5)),
            ("SIH_KDV", float(f"{kdv:.4g}")), ("SIH_KDW", float(f"{kdw:.4g}")),
            ("SIH_T_TAU", v.rotor.tau_m)]


def sih_params(v: Vehicle) -> str:
    lines = [f"# PX4 SIH parameters for {v.name}, written by cogniframe (`cogniframe fly`).",
             "# Load in QGroundControl: Vehicle Setup > Parameters > Tools > Load from file.",
             "# SIH's thrust is linear in the command: THR_MDL_FAC 0 and MPC_THR_HOVER = hover thrust / SIH_T_MAX.",
             "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    values = [*sih_values(v), ("THR_MDL_FAC", 0.0), ("MPC_THR_HOVER", round(v.hover_thrust_fraction, 3))]
    for name, val in values:
        t = 6 if isinstance(val, int) else 9
        lines.append(f"1\t1\t{name}\t{val}\t{t}")
    return "\n".join(lines) + "\n"


def airframe_values(v: Vehicle) -> list[tuple[str, float | int]]:
    r = v.resonance
    out: list[tuple[str, float | int]] = [("SENS_EN_GPSSIM", 1), ("SENS_EN_BAROSIM", 1), ("SENS_EN_MAGSIM", 1),
                                          ("CA_AIRFRAME", 0), ("CA_ROTOR_COUNT", len(v.rotors))]
    for n, rot in enumerate(v.ordered(PX4_ORDER)):
        x, y, z = frd(rot.position_m)
        km = v.rotor.km_over_kt if rot.spin == "ccw" else -v.rotor.km_over_kt
        out += [(f"CA_ROTOR{n}_PX", round(x, 4) + 0.0), (f"CA_ROTOR{n}_PY", round(y, 4) + 0.0),
                (f"CA_ROTOR{n}_PZ", round(z, 4) + 0.0), (f"CA_ROTOR{n}_KM", round(km, 5))]
    for n in range(len(v.rotors)):
        out += [(f"PWM_MAIN_FUNC{n + 1}", MOTOR_FUNCTION + n)]
    for n in range(len(v.rotors)):
        out += [(f"SIM_GZ_EC_FUNC{n + 1}", MOTOR_FUNCTION + n)]
    out += [(k, val) for k, val in sih_values(v)]
    out += [("THR_MDL_FAC", 0.0), ("MPC_THR_HOVER", round(v.hover_thrust_fraction, 3)),
            ("IMU_GYRO_CUTOFF", float(r.filter("gyro_lpf_hz"))), ("IMU_DGYRO_CUTOFF", float(r.filter("dterm_lpf_hz")))]
    flags = [f for f in r.flags if f.band.startswith("rotor")]
    if flags:
        out += [("IMU_GYRO_NF0_FRQ", round(flags[0].hz, 1)), ("IMU_GYRO_NF0_BW", round(flags[0].hz * 0.3, 1))]
    return out


def airframe(v: Vehicle) -> str:
    lines = ["#!/bin/sh", "#", f"# @name {v.name} (cogniframe) for SIH", "#", "# @type Quadrotor x", "# @class Copter", "#",
             f"# Written by cogniframe (`cogniframe fly`): {v.motor} motors, {v.prop} propellers,",
             f"# all-up mass {v.mass.mass_kg * 1000:.1f} g. Rotor positions from the centre of gravity, FRD, metres.",
             f"# Copy to ROMFS/px4fmu_common/init.d-posix/airframes/ and run `make px4_sitl {AIRFRAME_NAME}`.",
             "# SIH's thrust is linear in the command, hence THR_MDL_FAC 0 here; on the aircraft itself set",
             f"# THR_MDL_FAC {round(v.rotor.thrust_expo, 2)} (the flight table's thrust curve) and keep MPC_THR_HOVER "
             "(hover thrust / full thrust).",
             "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(v.resonance.advice)["px4"]]
    lines += ["", ". ${R}etc/init.d/rc.mc_defaults", "", "PX4_SIMULATOR=${PX4_SIMULATOR:=sihsim}",
              f"PX4_SIM_MODEL=${{PX4_SIM_MODEL:={AIRFRAME_NAME}}}", ""]
    lines += [f"param set-default {k} {val}" for k, val in airframe_values(v)]
    return "\n".join(lines) + "\n"

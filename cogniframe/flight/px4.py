"""px4/sih.params and px4/airframe.

sih.params: PX4's Simulation-In-Hardware vehicle (src/modules/simulation/simulator_sih/
sih_params.yaml): SIH_MASS (kg), SIH_IXX .. SIH_IYZ (kg m^2, FRD body axes), SIH_T_MAX and SIH_Q_MAX
(one propeller's thrust, N, and torque, N m, at full speed), SIH_L_ROLL and SIH_L_PITCH (half the
left-right and the front-rear distance between the motors, m), SIH_T_TAU (thruster time constant,
s), SIH_VEHICLE_TYPE 0 (quadcopter). QGroundControl's parameter file format: vehicle id,
component id, name, value, MAVLink type (9 float, 6 int32), tab separated.

airframe: the control allocation of an airframe script (ROMFS/px4fmu_common/init.d/airframes,
parameters from src/modules/control_allocator/module.yaml): CA_AIRFRAME 0 (multirotor),
CA_ROTOR_COUNT, CA_ROTORn_PX / _PY / _PZ (m, FRD, from the centre of gravity), CA_ROTORn_KM
(torque per thrust, positive for a counter-clockwise rotor); MPC_THR_HOVER
(the mc_pos_control module), THR_MDL_FAC (thrust curve),
and the gyro filters IMU_GYRO_CUTOFF, IMU_DGYRO_CUTOFF (src/modules/sensors/vehicle_angular_velocity).
Rotor numbers follow PX4's quad X (4001_quad_x): 0 front right, 1 rear left, 2 front left, 3 rear right.
"""

from __future__ import annotations

import numpy as np

from .vehicle import PX4_ORDER, Vehicle, frd, inertia_in


def sih_values(v: Vehicle) -> list[tuple[str, float | int]]:
    i = inertia_in("frd", v.mass.inertia)
    pos = np.array([frd(r.position_m) for r in v.rotors])
    return [("SIH_VEHICLE_TYPE", 0), ("SIH_MASS", round(v.mass.mass_kg, 5)),
            ("SIH_IXX", float(f"{i[0, 0]:.6g}")), ("SIH_IYY", float(f"{i[1, 1]:.6g}")), ("SIH_IZZ", float(f"{i[2, 2]:.6g}")),
            ("SIH_IXY", float(f"{i[0, 1]:.6g}")), ("SIH_IXZ", float(f"{i[0, 2]:.6g}")), ("SIH_IYZ", float(f"{i[1, 2]:.6g}")),
            ("SIH_T_MAX", round(v.rotor.thrust_max_n, 4)), ("SIH_Q_MAX", float(f"{v.rotor.torque_max_nm:.6g}")),
            ("SIH_L_ROLL", round(float(np.abs(pos[:, 1]).mean()), 5)), ("SIH_L_PITCH", round(float(np.abs(pos[:, 0]).mean()), 5)),
            ("SIH_T_TAU", v.rotor.tau_m)]


def sih_params(v: Vehicle) -> str:
    lines = [f"# PX4 SIH parameters for {v.name}, written by cogniframe (`cogniframe fly`).",
             "# Load in QGroundControl: Vehicle Setup > Parameters > Tools > Load from file.",
             "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    for name, val in sih_values(v):
        t = 6 if isinstance(val, int) else 9
        lines.append(f"1\t1\t{name}\t{val}\t{t}")
    return "\n".join(lines) + "\n"


def airframe_values(v: Vehicle) -> list[tuple[str, float | int]]:
    r = v.resonance
    out: list[tuple[str, float | int]] = [("CA_AIRFRAME", 0), ("CA_ROTOR_COUNT", len(v.rotors))]
    for n, rot in enumerate(v.ordered(PX4_ORDER)):
        x, y, z = frd(rot.position_m)
        km = v.rotor.km_over_kt if rot.spin == "ccw" else -v.rotor.km_over_kt
        out += [(f"CA_ROTOR{n}_PX", round(x, 4) + 0.0), (f"CA_ROTOR{n}_PY", round(y, 4) + 0.0),
                (f"CA_ROTOR{n}_PZ", round(z, 4) + 0.0), (f"CA_ROTOR{n}_KM", round(km, 5))]
    out += [("MPC_THR_HOVER", round(v.rotor.hover_throttle, 3)), ("THR_MDL_FAC", round(v.rotor.thrust_expo, 2)),
            ("IMU_GYRO_CUTOFF", float(r.filter("gyro_lpf_hz"))), ("IMU_DGYRO_CUTOFF", float(r.filter("dterm_lpf_hz")))]
    flags = [f for f in r.flags if f.band.startswith("rotor")]
    if flags:
        out += [("IMU_GYRO_NF0_FRQ", round(flags[0].hz, 1)), ("IMU_GYRO_NF0_BW", round(flags[0].hz * 0.3, 1))]
    return out


def airframe(v: Vehicle) -> str:
    lines = ["#!/bin/sh", "#", f"# @name {v.name} (cogniframe)", "#", "# @type Quadrotor x", "# @class Copter", "#",
             f"# Written by cogniframe (`cogniframe fly`): {v.motor} motors, {v.prop} propellers,",
             f"# all-up mass {v.mass.mass_kg * 1000:.1f} g. Rotor positions from the centre of gravity, FRD, metres.",
             "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(v.resonance.advice)["px4"]]
    lines += ["", ". ${R}etc/init.d/rc.mc_defaults", ""]
    lines += [f"param set-default {k} {val}" for k, val in airframe_values(v)]
    return "\n".join(lines) + "\n"

"""gazebo/model.sdf and gazebo/model.config: a gz-sim (Harmonic) model of the aircraft written as
PX4's own x500 is (PX4/PX4-gazebo-models models/x500_base and x500): a base_link with the mass
properties about the centre of gravity (the model's origin), an IMU and an air-pressure sensor on
it, a collision box as big as the cage (its joints' centres, `Vehicle.cage_m`), one link per
propeller on a revolute joint about z, and per rotor gz-sim's multicopter motor model system
(`gz-sim-multicopter-motor-model-system`, gz::sim::systems::MulticopterMotorModel: turningDirection,
timeConstantUp/Down, maxRotVelocity, motorConstant = k_eta, momentConstant = k_m / k_eta,
motorNumber, rotorDragCoefficient, rollingMomentCoefficient, commandSubTopic, motorType). PX4's
gz bridge drives motor n with SIM_GZ_EC_FUNCn (px4.py writes 101 .. 104). Axes FLU (x front, y
left, z up), SI. Motor numbers as PX4's quad X (px4.py).

Only gz-sim is written: Gazebo Classic (libgazebo_motor_model.so) reached its end of life in
January 2025 and PX4's current SITL targets (gz_x500 and kin) run on gz-sim.

Rotor drag (gz's motor model: F = -|w| rotorDragCoefficient v_perp, M = -|w|
rollingMomentCoefficient v_perp): the propeller's profile H-force from blade-element theory,
H = (sigma Cd0 / 4) rho A (w R)^2 mu with mu = v / (w R), so rotorDragCoefficient =
sigma Cd0 rho A R / 4, with a small propeller's solidity sigma = 0.1 and profile drag Cd0 = 0.02
(ROTOR_SOLIDITY, ROTOR_CD0); the rolling moment as a lever of a tenth of the radius on that force,
the ratio of PX4's x500 (rollingMomentCoefficient 1e-06 over rotorDragCoefficient 8.06428e-05 for
its 0.127 m propellers).
"""

from __future__ import annotations

import math
from xml.sax.saxutils import escape

import numpy as np

from ..analysis.constants import RHO_AIR
from .vehicle import PX4_ORDER, Vehicle, flu, inertia_in

SDF_VERSION = "1.9"
ROTOR_SOLIDITY, ROTOR_CD0 = 0.1, 0.02
ROLLING_LEVER_OVER_RADIUS = 0.1
# x500's sensors: IMU at 250 Hz, barometer at 50 Hz (x500_base/model.sdf)
IMU_HZ, BARO_HZ = 250, 50


def _g(x: float) -> str:
    return f"{x + 0.0:.6g}"


def _inertial(mass: float, inertia: np.ndarray, indent: str) -> list[str]:
    i = inertia
    return [f"{indent}<inertial>", f"{indent}  <mass>{_g(mass)}</mass>", f"{indent}  <inertia>",
            f"{indent}    <ixx>{_g(i[0, 0])}</ixx>", f"{indent}    <ixy>{_g(i[0, 1])}</ixy>", f"{indent}    <ixz>{_g(i[0, 2])}</ixz>",
            f"{indent}    <iyy>{_g(i[1, 1])}</iyy>", f"{indent}    <iyz>{_g(i[1, 2])}</iyz>", f"{indent}    <izz>{_g(i[2, 2])}</izz>",
            f"{indent}  </inertia>", f"{indent}</inertial>"]


def rotor_drag(v: Vehicle) -> tuple[float, float]:
    """(rotorDragCoefficient N/((rad/s)(m/s)), rollingMomentCoefficient N m/((rad/s)(m/s)))."""
    r = v.rotor.prop_diameter_m / 2
    drag = ROTOR_SOLIDITY * ROTOR_CD0 * RHO_AIR * math.pi * r**2 * r / 4
    return drag, drag * ROLLING_LEVER_OVER_RADIUS * r


def cage_box(v: Vehicle) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(centre, size) of the cage's box in FLU from the centre of gravity."""
    lo, hi = (np.asarray(c) for c in v.cage_m)
    centre, size = flu((lo + hi) / 2), (hi[1] - lo[1], hi[0] - lo[0], hi[2] - lo[2])
    return centre, tuple(float(s) for s in size)


def model_sdf(v: Vehicle) -> str:
    rm = v.rotor
    prop_kg = rm.rotor_inertia_kg_m2 * 12 / rm.prop_diameter_m**2  # the propeller's mass (slender bar)
    prop_i = np.diag([rm.rotor_inertia_kg_m2 / 2, rm.rotor_inertia_kg_m2 / 2, rm.rotor_inertia_kg_m2])
    body_kg = v.mass.mass_kg - len(v.rotors) * prop_kg
    # the propellers' own share leaves base_link (their mass and inertia about the centre of gravity)
    body_i = inertia_in("flu", v.mass.inertia)
    for r in v.rotors:
        p = np.asarray(flu(r.position_m))
        body_i = body_i - prop_i - prop_kg * (float(p @ p) * np.eye(3) - np.outer(p, p))
    centre, size = cage_box(v)
    box = f"{_g(size[0])} {_g(size[1])} {_g(size[2])}"
    drag, rolling = rotor_drag(v)
    out = ['<?xml version="1.0"?>',
           f"<!-- {escape(v.name)}: written by cogniframe (`cogniframe fly`). Mass properties about the centre of gravity",
           "     (the model origin), FLU axes; gz-sim (Harmonic) multicopter motor model per rotor, as PX4's x500. -->",
           f'<sdf version="{SDF_VERSION}">', f'  <model name="{escape(v.name)}">', "    <pose>0 0 0.1 0 0 0</pose>",
           "    <self_collide>false</self_collide>", "    <static>false</static>",
           '    <link name="base_link">', "      <pose>0 0 0 0 0 0</pose>"]
    out += _inertial(body_kg, body_i, "      ")
    out += ['      <collision name="base_link_collision">', f"        <pose>{_g(centre[0])} {_g(centre[1])} {_g(centre[2])} 0 0 0</pose>",
            f"        <geometry><box><size>{box}</size></box></geometry>", "      </collision>",
            '      <visual name="base_link_visual">', f"        <pose>{_g(centre[0])} {_g(centre[1])} {_g(centre[2])} 0 0 0</pose>",
            f"        <geometry><box><size>{box}</size></box></geometry>", "      </visual>",
            '      <sensor name="imu_sensor" type="imu">', "        <always_on>1</always_on>",
            f"        <update_rate>{IMU_HZ}</update_rate>", f"        <pose>{' '.join(_g(c) for c in flu(v.imu_m))} 0 0 0</pose>",
            "      </sensor>",
            '      <sensor name="air_pressure_sensor" type="air_pressure">', "        <always_on>1</always_on>",
            f"        <update_rate>{BARO_HZ}</update_rate>",
            "        <air_pressure><pressure><noise type=\"gaussian\"><mean>0</mean><stddev>3</stddev></noise></pressure></air_pressure>",
            "      </sensor>", "    </link>"]
    for n, r in enumerate(v.ordered(PX4_ORDER)):
        x, y, z = flu(r.position_m)
        radius = rm.prop_diameter_m / 2
        out += [f'    <link name="rotor_{n}">', f"      <pose>{_g(x)} {_g(y)} {_g(z)} 0 0 0</pose>"]
        out += _inertial(prop_kg, prop_i, "      ")
        out += [f'      <visual name="rotor_{n}_visual">',
                f"        <geometry><cylinder><length>0.005</length><radius>{_g(radius)}</radius></cylinder></geometry>",
                "      </visual>", "    </link>",
                f'    <joint name="rotor_{n}_joint" type="revolute">', f"      <child>rotor_{n}</child>",
                "      <parent>base_link</parent>", "      <axis>", "        <xyz>0 0 1</xyz>",
                "        <limit><lower>-1e+16</lower><upper>1e+16</upper></limit>", "      </axis>", "    </joint>"]
    for n, r in enumerate(v.ordered(PX4_ORDER)):
        out += ['    <plugin filename="gz-sim-multicopter-motor-model-system" name="gz::sim::systems::MulticopterMotorModel">',
                f"      <jointName>rotor_{n}_joint</jointName>", f"      <linkName>rotor_{n}</linkName>",
                f"      <turningDirection>{r.spin}</turningDirection>",
                f"      <timeConstantUp>{_g(rm.tau_m)}</timeConstantUp>", f"      <timeConstantDown>{_g(rm.tau_m)}</timeConstantDown>",
                f"      <maxRotVelocity>{_g(rm.omega_max)}</maxRotVelocity>", f"      <motorConstant>{_g(rm.k_eta)}</motorConstant>",
                f"      <momentConstant>{_g(rm.km_over_kt)}</momentConstant>",
                "      <commandSubTopic>command/motor_speed</commandSubTopic>", f"      <motorNumber>{n}</motorNumber>",
                f"      <rotorDragCoefficient>{_g(drag)}</rotorDragCoefficient>",
                f"      <rollingMomentCoefficient>{_g(rolling)}</rollingMomentCoefficient>",
                "      <rotorVelocitySlowdownSim>10</rotorVelocitySlowdownSim>", "      <motorType>velocity</motorType>", "    </plugin>"]
    out += ["  </model>", "</sdf>"]
    return "\n".join(out) + "\n"


def model_config(v: Vehicle) -> str:
    return "\n".join(['<?xml version="1.0"?>', "<model>", f"  <name>{escape(v.name)}</name>", "  <version>1.0</version>",
                      f'  <sdf version="{SDF_VERSION}">model.sdf</sdf>', "  <author>", "    <name>cogniframe</name>",
                      "    <email>none</email>", "  </author>",
                      f"  <description>{escape(v.name)}: a CogniFly-type exoskeleton quadcopter, {escape(v.motor)} motors, "
                      f"{escape(v.prop)} propellers; written by cogniframe for gz-sim (Harmonic).</description>", "</model>"]) + "\n"

"""gazebo/model.sdf and gazebo/model.config: a Gazebo (classic) model of the aircraft written as
PX4's own multicopter models are (PX4-SITL_gazebo-classic, models/iris/iris.sdf.jinja): a
base_link with the mass properties about the centre of gravity (the model's origin), one link per
propeller on a revolute joint about z, and per rotor the multicopter motor model plugin
(libgazebo_motor_model.so: turningDirection, timeConstantUp/Down, maxRotVelocity, motorConstant
= k_eta, momentConstant = k_m / k_eta, motorNumber, ...). Axes FLU (x front, y left, z up), SI.
Motor numbers as PX4's quad X (px4.py)."""

from __future__ import annotations

from xml.sax.saxutils import escape

import numpy as np

from .vehicle import PX4_ORDER, Vehicle, flu, inertia_in

SDF_VERSION = "1.6"


def _g(x: float) -> str:
    return f"{x + 0.0:.6g}"


def _inertial(mass: float, inertia: np.ndarray, indent: str) -> list[str]:
    i = inertia
    return [f"{indent}<inertial>", f"{indent}  <mass>{_g(mass)}</mass>", f"{indent}  <inertia>",
            f"{indent}    <ixx>{_g(i[0, 0])}</ixx>", f"{indent}    <ixy>{_g(i[0, 1])}</ixy>", f"{indent}    <ixz>{_g(i[0, 2])}</ixz>",
            f"{indent}    <iyy>{_g(i[1, 1])}</iyy>", f"{indent}    <iyz>{_g(i[1, 2])}</iyz>", f"{indent}    <izz>{_g(i[2, 2])}</izz>",
            f"{indent}  </inertia>", f"{indent}</inertial>"]


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
    span = 2 * max(max(abs(c) for c in flu(r.position_m)[:2]) for r in v.rotors)
    out = ['<?xml version="1.0"?>',
           f"<!-- {escape(v.name)}: written by cogniframe (`cogniframe fly`). Mass properties about the centre of gravity",
           "     (the model origin), FLU axes; rotors driven by the multicopter motor model as PX4's iris. -->",
           f'<sdf version="{SDF_VERSION}">', f'  <model name="{escape(v.name)}">', "    <pose>0 0 0.1 0 0 0</pose>",
           '    <link name="base_link">', "      <pose>0 0 0 0 0 0</pose>"]
    out += _inertial(body_kg, body_i, "      ")
    out += ['      <collision name="base_link_collision">', "        <geometry><box><size>"
            f"{_g(span)} {_g(span)} 0.06</size></box></geometry>", "      </collision>",
            '      <visual name="base_link_visual">', f"        <geometry><box><size>{_g(span)} {_g(span)} 0.06</size></box></geometry>",
            "      </visual>", "    </link>"]
    for n, r in enumerate(v.ordered(PX4_ORDER)):
        x, y, z = flu(r.position_m)
        radius = rm.prop_diameter_m / 2
        out += [f'    <link name="rotor_{n}">', f"      <pose>{_g(x)} {_g(y)} {_g(z)} 0 0 0</pose>"]
        out += _inertial(prop_kg, prop_i, "      ")
        out += [f'      <collision name="rotor_{n}_collision">',
                f"        <geometry><cylinder><length>0.005</length><radius>{_g(radius)}</radius></cylinder></geometry>",
                "      </collision>", f'      <visual name="rotor_{n}_visual">',
                f"        <geometry><cylinder><length>0.005</length><radius>{_g(radius)}</radius></cylinder></geometry>",
                "      </visual>", "    </link>",
                f'    <joint name="rotor_{n}_joint" type="revolute">', "      <child>rotor_" + str(n) + "</child>",
                "      <parent>base_link</parent>", "      <axis>", "        <xyz>0 0 1</xyz>",
                "        <limit><lower>-1e+16</lower><upper>1e+16</upper></limit>",
                "        <dynamics><spring_reference>0</spring_reference><spring_stiffness>0</spring_stiffness></dynamics>",
                "      </axis>", "    </joint>"]
    for n, r in enumerate(v.ordered(PX4_ORDER)):
        out += [f'    <plugin name="rotor_{n}_motor_model" filename="libgazebo_motor_model.so">',
                "      <robotNamespace></robotNamespace>", f"      <jointName>rotor_{n}_joint</jointName>",
                f"      <linkName>rotor_{n}</linkName>", f"      <turningDirection>{r.spin}</turningDirection>",
                f"      <timeConstantUp>{_g(rm.tau_m)}</timeConstantUp>", f"      <timeConstantDown>{_g(rm.tau_m)}</timeConstantDown>",
                f"      <maxRotVelocity>{_g(rm.omega_max)}</maxRotVelocity>", f"      <motorConstant>{_g(rm.k_eta)}</motorConstant>",
                f"      <momentConstant>{_g(rm.km_over_kt)}</momentConstant>",
                "      <commandSubTopic>/gazebo/command/motor_speed</commandSubTopic>", f"      <motorNumber>{n}</motorNumber>",
                "      <rotorDragCoefficient>0</rotorDragCoefficient>", "      <rollingMomentCoefficient>0</rollingMomentCoefficient>",
                f"      <motorSpeedPubTopic>/motor_speed/{n}</motorSpeedPubTopic>",
                "      <rotorVelocitySlowdownSim>10</rotorVelocitySlowdownSim>", "    </plugin>"]
    out += ["  </model>", "</sdf>"]
    return "\n".join(out) + "\n"


def model_config(v: Vehicle) -> str:
    return "\n".join(['<?xml version="1.0"?>', "<model>", f"  <name>{escape(v.name)}</name>", "  <version>1.0</version>",
                      f'  <sdf version="{SDF_VERSION}">model.sdf</sdf>', "  <author>", "    <name>cogniframe</name>",
                      "    <email>none</email>", "  </author>",
                      f"  <description>{escape(v.name)}: a CogniFly-type exoskeleton quadcopter, {escape(v.motor)} motors, "
                      f"{escape(v.prop)} propellers; written by cogniframe.</description>", "</model>"]) + "\n"

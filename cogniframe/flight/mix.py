"""The motor mix of a quad from its geometry, as INAV's and Betaflight's `mmix` lines write it:
throttle, roll, pitch and yaw factor of each motor.

Roll and pitch factors are each motor's arm about the roll and pitch axes (FRD body axes, from
the motors' common centre), over the longest of them, with the firmware's signs: a motor on the
right side gets a negative roll factor, one at the front a negative pitch factor, and a
clockwise propeller (seen from above) a yaw factor of -1 (INAV's and Betaflight's quad-X table,
mixerQuadX: rear right 1 -1 1 -1, front right 1 -1 -1 1, rear left 1 1 1 1, front left
1 1 -1 -1, props in). Factors proportional to the arms make the mix the least-squares
allocation of roll and pitch torque; a square frame gives exactly the quad-X table. The centre
of gravity's offset from the motors' centre is left to the controller's integral term, as the
firmware's own tables do.
"""

from __future__ import annotations

import numpy as np

from .vehicle import BF_ORDER, Vehicle, frd

QUAD_X = ((1.0, -1.0, 1.0, -1.0), (1.0, -1.0, -1.0, 1.0), (1.0, 1.0, 1.0, 1.0), (1.0, 1.0, -1.0, -1.0))


def mmix(v: Vehicle) -> tuple[tuple[float, float, float, float], ...]:
    """(throttle, roll, pitch, yaw) per motor in Betaflight/INAV order, rounded to 3 decimals."""
    rs = v.ordered(BF_ORDER)
    centre = v.rotor_centre_m
    pos = np.array([frd(np.asarray(r.position_m) - centre) for r in rs])  # x front, y right
    arm = float(np.abs(pos[:, :2]).max())
    out = []
    for r, p in zip(rs, pos):
        roll = -p[1] / arm
        pitch = -p[0] / arm
        yaw = -1.0 if r.spin == "cw" else 1.0
        out.append((1.0, round(roll, 3) + 0.0, round(pitch, 3) + 0.0, yaw))
    return tuple(out)


def mmix_lines(v: Vehicle) -> list[str]:
    names = {"rr": "rear right", "fr": "front right", "rl": "rear left", "fl": "front left"}
    lines = ["mmix reset"]
    for i, (row, corner) in enumerate(zip(mmix(v), BF_ORDER)):
        spin = v.rotor_at(corner).spin.upper()
        lines.append(f"mmix {i} {row[0]:.3f} {row[1]:.3f} {row[2]:.3f} {row[3]:.3f}  # motor {i + 1}: {names[corner]}, {spin}")
    return lines


def header(v: Vehicle, what: str) -> list[str]:
    c = -v.rotor_centre_m * 1000.0  # the centre of gravity from the motors' centre (hub plane), frame axes

    def mm(x: float) -> str:
        return f"{round(x, 1) + 0.0:+.1f}"

    return [f"# {what} for {v.name}, written by cogniframe (`cogniframe fly`). Paste into the Configurator's CLI tab.",
            f"# {v.motor} motors, {v.prop} propellers, props {'out' if v.props_out else 'in'}; "
            f"all-up mass {v.mass.mass_kg * 1000:.1f} g; ESC throttle at hover {v.rotor.hover_throttle:.0%} (flight tables), "
            f"hover thrust {v.hover_thrust_fraction:.0%} of full.",
            f"# Centre of gravity from the motors' centre: {mm(c[1])} mm front, {mm(c[0])} mm right, "
            f"{mm(-c[2])} mm below the propellers' plane."]

"""rotorpy.json: the vehicle parameters of rotorpy (PyPI `rotorpy`), with the keys its
`Multirotor` (rotorpy/vehicles/multirotor.py) and `SE3Control`
(rotorpy/controllers/quadrotor_control.py) read, laid out as its own rotorpy/vehicles/
crazyflie_params.py: mass (kg), Ixx .. Iyz (kg m^2), num_rotors, rotor_pos {r1: [x, y, z], ...}
(m, from the centre of gravity), rotor_directions (+1 for a clockwise propeller seen from above:
its drag torque turns the body counter-clockwise, +z), rI (the IMU), c_Dx/y/z, k_eta, k_m, k_d,
k_z, k_h, k_flap, tau_m, rotor_speed_min/max (rad/s), motor_noise_std. Axes FLU (x front, y
left, z up). Rotors r1..r4 in Betaflight's motor order (mix.py).

    from rotorpy.vehicles.multirotor import Multirotor
    from cogniframe.flight.rotorpy_params import load
    vehicle = Multirotor(load("out/carbon/flight/rotorpy.json"))
"""

from __future__ import annotations

import json

from .vehicle import BF_ORDER, Vehicle, flu, inertia_in

META = ("generator", "name", "axes", "sources", "usage")


def params(v: Vehicle) -> dict:
    i = inertia_in("flu", v.mass.inertia)
    rm = v.rotor

    def g(x):
        return float(f"{x + 0.0:.6g}")

    rs = v.ordered(BF_ORDER)
    return {"generator": "cogniframe", "name": v.name, "axes": "FLU (x front, y left, z up), SI units",
            "usage": "Multirotor(cogniframe.flight.rotorpy_params.load(path)): lists become numpy arrays",
            "mass": round(v.mass.mass_kg, 6),
            "Ixx": g(i[0, 0]), "Iyy": g(i[1, 1]), "Izz": g(i[2, 2]), "Ixy": g(i[0, 1]), "Iyz": g(i[1, 2]), "Ixz": g(i[0, 2]),
            "num_rotors": len(rs),
            "rotor_pos": {f"r{n}": [round(c, 6) + 0.0 for c in flu(r.position_m)] for n, r in enumerate(rs, start=1)},
            "rotor_directions": [1 if r.spin == "cw" else -1 for r in rs],
            "rI": [round(c, 6) + 0.0 for c in flu(v.imu_m)],
            "c_Dx": 0.0, "c_Dy": 0.0, "c_Dz": 0.0,
            "k_eta": g(rm.k_eta), "k_m": g(rm.k_m), "k_d": 0.0, "k_z": 0.0, "k_h": 0.0, "k_flap": 0.0,
            "tau_m": rm.tau_m, "rotor_speed_min": 0.0, "rotor_speed_max": round(rm.omega_max, 2), "motor_noise_std": 0.0,
            "sources": dict(rm.sources)}


def text(v: Vehicle) -> str:
    return json.dumps(params(v), indent=2) + "\n"


def load(path) -> dict:
    """rotorpy's quad_params from a rotorpy.json: numpy arrays where rotorpy does arithmetic on them."""
    import numpy as np

    with open(path, encoding="utf-8") as f:
        d = json.load(f)
    out = {k: val for k, val in d.items() if k not in META}
    out["rotor_pos"] = {k: np.asarray(p, float) for k, p in d["rotor_pos"].items()}
    out["rotor_directions"] = np.asarray(d["rotor_directions"], float)
    out["rI"] = np.asarray(d["rI"], float)
    return out

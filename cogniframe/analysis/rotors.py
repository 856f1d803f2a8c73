"""The rotors: where they are, which way they turn, and the constants a simulator needs.

Thrust T = k_eta w^2 and drag torque Q = k_m w^2 per rotor (w in rad/s), as rotorpy, Gazebo's
motor model and PX4's SIH write them. Where each number comes from (`RotorModel.sources`):

- k_eta from the propeller's static thrust coefficient C_T = T / (rho n^2 D^4) (load_cases.PROP_CT,
  the UIUC small-propeller tests), so the rotor speed at hover is the one `check` compares the
  frame's modes with (`stiffness.hover_rotor_hz`);
- the full-throttle thrust from the flight tables (analysis/flight.py: `max_thrust_g`);
- k_m from the same tables' battery current: shaft power = motor + ESC efficiency x V I at each
  table point, torque = power / w, fitted as Q = k_m w^2 over the points;
- the thrust curve's expo (thrust over full thrust = (1 - e) u + e u^2 at throttle u) fitted to
  the table: ArduPilot's MOT_THST_EXPO and PX4's THR_MDL_FAC use this very form;
- the motor time constant: the tables hold no step response; PX4 SIH's default thruster time
  constant (SIH_T_TAU = 0.05 s, src/modules/simulation/simulator_sih/sih_params.yaml) stands in.

Spin directions: `motors.props_out` false (the default) turns the propellers "in" as Betaflight's
and INAV's quad-X default does (rear right and front left clockwise seen from above), true
reverses every motor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constants import G, RHO_AIR

# Motor + ESC efficiency of small brushless motors (shaft power over battery power): the 0.6 of
# analysis/flight.py's FOM_ETA = figure of merit 0.5 x 0.6.
MOTOR_ESC_EFFICIENCY = 0.6
# Motor time constant, s: PX4 SIH's default SIH_T_TAU (sih_params.yaml: "the time taken for the
# thruster to step from 0 to 100% should be about 4 times tau"); no table here measures it.
TAU_M_S = 0.05
TAU_M_SOURCE = "PX4 SIH default thruster time constant SIH_T_TAU = 0.05 s (no step response in the flight tables)"

# Seen from above, propellers in (Betaflight / INAV quad-X default, "props in").
SPIN_PROPS_IN = {"rr": "cw", "fr": "ccw", "rl": "ccw", "fl": "cw"}


@dataclass(frozen=True)
class Rotor:
    corner: str  # fl | fr | rr | rl
    position_m: tuple[float, float, float]  # propeller hub, relative to the centre of gravity, frame axes
    spin: str  # "cw" | "ccw" seen from above


@dataclass(frozen=True)
class RotorModel:
    k_eta: float  # N / (rad/s)^2
    k_m: float  # N m / (rad/s)^2
    tau_m: float  # s
    omega_max: float  # rad/s at full throttle
    omega_hover: float  # rad/s
    thrust_max_n: float  # per rotor
    torque_max_nm: float  # per rotor at full throttle
    hover_throttle: float  # 0-1, the flight tables' (as `check`'s flight.hover_throttle)
    thrust_expo: float  # e in T/T_max = (1 - e) u + e u^2
    prop_diameter_m: float
    rotor_inertia_kg_m2: float  # the propeller about its shaft (a slender bar)
    sources: tuple[tuple[str, str], ...]

    @property
    def km_over_kt(self) -> float:
        """Drag torque per newton of thrust, m (PX4's CA_ROTORn_KM, Gazebo's momentConstant)."""
        return self.k_m / self.k_eta

    @property
    def hover_rotor_hz(self) -> float:
        return self.omega_hover / (2 * math.pi)

    @property
    def max_rotor_hz(self) -> float:
        return self.omega_max / (2 * math.pi)

    def to_dict(self) -> dict:
        return {"k_eta_n_per_rad_s2": float(f"{self.k_eta:.6g}"), "k_m_nm_per_rad_s2": float(f"{self.k_m:.6g}"),
                "km_over_kt_m": round(self.km_over_kt, 6), "tau_m_s": self.tau_m,
                "omega_hover_rad_s": round(self.omega_hover, 2), "omega_max_rad_s": round(self.omega_max, 2),
                "hover_rotor_hz": round(self.hover_rotor_hz, 2), "max_rotor_hz": round(self.max_rotor_hz, 2),
                "thrust_max_n": round(self.thrust_max_n, 4), "torque_max_nm": float(f"{self.torque_max_nm:.6g}"),
                "hover_throttle": round(self.hover_throttle, 4), "thrust_expo": round(self.thrust_expo, 4),
                "rotor_inertia_kg_m2": float(f"{self.rotor_inertia_kg_m2:.6g}"), "sources": dict(self.sources)}


def rotors(spec, frame, cg_m) -> tuple[Rotor, ...]:
    """The rotors in the frame's motor order, hubs relative to the centre of gravity (m). The hub
    is the propeller disc's centre as the assembly draws it (vitamins.motor_vitamins)."""
    from ..vitamins import motor_vitamins

    hubs = {v.name.removeprefix("propeller_"): v.disc[0] for v in motor_vitamins(spec, frame) if v.family == "propeller"}
    flip = {"cw": "ccw", "ccw": "cw"}
    out = []
    for m in frame.motors:
        spin = SPIN_PROPS_IN[m.corner]
        if spec.motors.props_out:
            spin = flip[spin]
        p = np.asarray(hubs[m.corner], float) / 1000.0 - np.asarray(cg_m, float)
        out.append(Rotor(m.corner, (float(p[0]), float(p[1]), float(p[2])), spin))
    return tuple(out)


def model(spec, mass_kg: float, n_rotors: int = 4) -> RotorModel:
    """The rotor constants for the design's motor, propeller and pack (see the module docstring).
    Raises UserError (naming motors.kv) when the flight tables have no entry for them."""
    from . import flight
    from .load_cases import PROP_CT
    p = flight.propulsion(spec)
    if p is None:
        tabled = "; ".join(f"{m} {k} KV with {pr}" for m, k, pr, _ in sorted(flight.TABLES))
        raise spec.error("motors.kv", f"the flight files need a thrust table for the motor, KV and propeller, and "
                                      f"analysis/flight.py has none for {spec.motor.name} {spec.motors.kv or flight.default_kv(spec.motor.name)} KV "
                                      f"with {flight.prop_name(spec)}", f"set motors.model, motors.kv and motors.prop to a tabled "
                                      f"set ({tabled})")
    d = spec.motors.prop_diameter / 1000.0
    k_eta = PROP_CT * RHO_AIR * d**4 / (4 * math.pi**2)
    t_max = flight.max_thrust_g(spec) / 1000.0 * G
    w_max = math.sqrt(t_max / k_eta)
    w_hover = math.sqrt(mass_kg * G / n_rotors / k_eta)
    v = spec.core.battery.cells * flight.CELL_V
    pts = [(u, tg * p.scale / 1000.0 * G, i * p.scale) for u, tg, i in p.table.points]
    w = np.array([math.sqrt(t / k_eta) for _, t, _ in pts])
    q = np.array([MOTOR_ESC_EFFICIENCY * v * i for _, _, i in pts]) / w
    k_m = float((q * w**2).sum() / (w**4).sum())
    u = np.array([0.0] + [x[0] for x in pts])
    rel = np.array([0.0] + [x[1] for x in pts]) / pts[-1][1]
    # least squares of rel - u = e (u^2 - u)
    a = u**2 - u
    expo = float((a * (rel - u)).sum() / (a * a).sum())
    fr = flight.evaluate(spec, mass_kg * 1000.0)
    prop_mass = spec.motors.prop_mass / 1000.0
    t = p.table
    sources = (
        ("k_eta", f"C_T = {PROP_CT} (UIUC small-propeller static tests, analysis/load_cases.PROP_CT), rho {RHO_AIR} kg/m^3, "
                  f"D {spec.motors.prop_diameter:g} mm: k_eta = C_T rho D^4 / (2 pi)^2"),
        ("thrust_max", f"flight table {t.motor} {t.kv}KV {t.prop} {t.cells}S"
                       + (f" scaled to {spec.core.battery.cells}S" if p.scale != 1.0 else "")
                       + (" (motors.max_thrust_g)" if spec.motors.max_thrust_g is not None else "") + f": {t.source}"),
        ("k_m", f"the same table's current: torque = {MOTOR_ESC_EFFICIENCY} (motor + ESC efficiency) x {v:.1f} V x I / w, "
                f"least squares of Q = k_m w^2 over its {len(pts)} points"),
        ("thrust_expo", "least squares of T/T_max = (1 - e) u + e u^2 over the table's throttle steps"),
        ("tau_m", TAU_M_SOURCE),
        ("hover_throttle", "analysis/flight.py: the table interpolated at a quarter of the all-up weight"),
    )
    return RotorModel(k_eta, k_m, TAU_M_S, w_max, w_hover, t_max, k_m * w_max**2, fr.hover_throttle if fr else 1.0,
                      expo, d, prop_mass * d * d / 12, sources)


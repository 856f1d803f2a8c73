"""Flight: thrust-to-weight, hover throttle, hover current and hover time from propulsion tables.

Method (see docs/flight.md):
1. A propulsion table per (motor class, KV, propeller, cell count): thrust (g) and battery current
   (A) per motor at throttle steps, at the pack's nominal voltage (3.7 V a cell).
2. Full-throttle thrust of the four motors over the all-up weight = thrust-to-weight.
3. Hover: each motor lifts weight / 4; the table is interpolated (piecewise linear in thrust) for
   throttle and current. Another cell count than the table's is scaled as a fixed propeller does:
   thrust and current ~ V^2 at the same throttle.
4. Avionics (FC, computer, camera, flow sensor) draw their power through a 5 V regulator.
5. Hover time = usable capacity (capacity x usable_fraction) / total hover current.

Momentum theory gives a cross-check: ideal hover power T^1.5 / sqrt(2 rho A) for a disc of the
propeller's area, divided by a figure of merit x motor/ESC efficiency (FOM_ETA).

The tables' sources: see TABLES (each names its basis). Pure Python, no heavy imports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..spec import Spec
from .constants import G, RHO_AIR

CELL_V = 3.7  # nominal LiPo cell voltage
FOM_ETA = 0.30  # figure of merit (~0.5) x motor + ESC efficiency (~0.6) for small props, momentum cross-check
BEC_EFFICIENCY = 0.85  # 5 V regulator feeding the avionics
AVIONICS_W = {"fc": 0.5, "pi_zero": 1.0, "pi_camera_v2": 1.25, "matek_3901_l0x": 0.2}  # W at 5 V (data sheets: Pi Zero W ~120-200 mA, camera v2 ~250 mA, 3901-L0X 40 mA)


@dataclass(frozen=True)
class PropulsionTable:
    motor: str
    kv: int
    prop: str
    prop_diameter_mm: float
    cells: int
    points: tuple[tuple[float, float, float], ...]  # (throttle 0-1, thrust g, current A) per motor
    source: str

    @property
    def voltage_v(self) -> float:
        return self.cells * CELL_V

    @property
    def max_thrust_g(self) -> float:
        return self.points[-1][1]


_REPRESENTATIVE = ("representative curve for this class, not a measured sheet: the full-throttle point ({}) is typical of "
                   "published vendor bench tables for this motor/prop/voltage class; the steps below it follow thrust ~ "
                   "throttle^1.8 and power ~ thrust^1.5 (momentum theory). Replace with your motor's bench table.")

TABLES: dict[tuple[str, int, str, int], PropulsionTable] = {(t.motor, t.kv, t.prop, t.cells): t for t in (
    PropulsionTable("1104", 6000, "3025", 76.2, 3,
                    ((0.3, 20, 0.23), (0.4, 34, 0.51), (0.5, 50, 0.92), (0.6, 70, 1.51), (0.7, 92, 2.29), (0.8, 117, 3.28),
                     (0.9, 145, 4.51), (1.0, 175, 6.0)),
                    _REPRESENTATIVE.format("175 g at 6.0 A on 3S") + " The paper's carbon build flies 1104 6000KV with 3025 on 3S."),
    PropulsionTable("1104", 7500, "3025", 76.2, 3,
                    ((0.3, 25, 0.33), (0.4, 41, 0.72), (0.5, 62, 1.32), (0.6, 86, 2.17), (0.7, 113, 3.28), (0.8, 144, 4.71),
                     (0.9, 178, 6.47), (1.0, 215, 8.6)),
                    _REPRESENTATIVE.format("215 g at 8.6 A on 3S")),
    PropulsionTable("1404", 3000, "4024", 101.6, 2,
                    ((0.3, 19, 0.24), (0.4, 32, 0.53), (0.5, 47, 0.97), (0.6, 66, 1.59), (0.7, 87, 2.4), (0.8, 110, 3.45),
                     (0.9, 136, 4.74), (1.0, 165, 6.3)),
                    _REPRESENTATIVE.format("165 g at 6.3 A on 2S") + " The bamboo build: 1404 3000KV, 4 in props, 2S 2000 mAh."),
)}

DEFAULT_KV = {"1104": 6000, "1404": 3000}


def default_kv(motor: str) -> int:
    return DEFAULT_KV.get(motor, 0)


def prop_name(spec: Spec) -> str:
    """motors.prop, or the table propeller nearest motors.prop_diameter."""
    from ..materials import PROPS

    if spec.motors.prop:
        return spec.motors.prop
    return min(PROPS.values(), key=lambda p: abs(p.diameter_mm - spec.motors.prop_diameter)).name


@dataclass(frozen=True)
class Propulsion:
    """The table used for a design and the factor that scales it to the design's pack."""

    table: PropulsionTable
    scale: float  # (V / V_table)^2 applied to thrust and current

    def thrust_g(self, throttle: float) -> float:
        return self.scale * _interp(throttle, [p[0] for p in self.table.points], [p[1] for p in self.table.points])

    def at_thrust(self, thrust_g: float) -> tuple[float, float]:
        """(throttle, current A) giving `thrust_g` from one motor (interpolated in thrust)."""
        pts = self.table.points
        t = [p[1] * self.scale for p in pts]
        if thrust_g > t[-1]:
            return float("inf"), float("inf")
        throttle = _interp(thrust_g, [0.0] + t, [0.0] + [p[0] for p in pts])
        current = _interp(thrust_g, [0.0] + t, [0.0] + [p[2] * self.scale for p in pts])
        return throttle, current


def _interp(x: float, xs: list[float], ys: list[float]) -> float:
    if x <= xs[0]:
        return ys[0]
    for i in range(1, len(xs)):
        if x <= xs[i]:
            return ys[i - 1] + (ys[i] - ys[i - 1]) * (x - xs[i - 1]) / (xs[i] - xs[i - 1])
    return ys[-1]


def propulsion(spec: Spec) -> Propulsion | None:
    """The design's propulsion table (scaled to its cell count), or None when no table matches."""
    kv = spec.motors.kv or default_kv(spec.motor.name)
    prop = prop_name(spec)
    cells = spec.core.battery.cells
    exact = TABLES.get((spec.motor.name, kv, prop, cells))
    if exact:
        return Propulsion(exact, 1.0)
    same = [t for (m, k, p, _), t in TABLES.items() if (m, k, p) == (spec.motor.name, kv, prop)]
    if not same:
        return None
    t = min(same, key=lambda t: abs(t.cells - cells))
    return Propulsion(t, (cells / t.cells) ** 2)




def max_thrust_g(spec: Spec) -> float:
    """Full-throttle thrust of one motor (g): `motors.max_thrust_g` when the params give it, else the
    thrust table for the motor, kv, prop and pack, else the motor class's typical value. The one
    value the flight model (thrust-to-weight) and the thrust load case use."""
    if spec.motors.max_thrust_g is not None:
        return float(spec.motors.max_thrust_g)
    p = propulsion(spec)
    if p is not None:
        return p.thrust_g(1.0)
    # the motor catalogue's typical full thrust of the class (materials.MOTOR_PRESETS)
    return spec.motor.thrust_g


def momentum_hover_power_w(thrust_n: float, prop_diameter_mm: float, fom_eta: float = FOM_ETA) -> float:
    """Electrical power (W) for one rotor to hover with `thrust_n`: ideal T^1.5 / sqrt(2 rho A) over fom_eta."""
    area = math.pi * (prop_diameter_mm / 2000.0) ** 2
    return thrust_n**1.5 / math.sqrt(2 * RHO_AIR * area) / fom_eta


def avionics_w(spec: Spec) -> float:
    keys = {c.vitamin for c in spec.components if c.vitamin}
    w = AVIONICS_W["fc"]
    for k in ("pi_zero", "pi_camera_v2", "matek_3901_l0x"):
        if k in keys:
            w += AVIONICS_W[k]
    return w


@dataclass(frozen=True)
class FlightResult:
    mass_g: float
    rotors: int
    max_thrust_g_per_motor: float
    thrust_to_weight: float
    hover_throttle: float
    hover_current_a: float  # total, battery side, motors + avionics
    hover_power_w: float
    hover_time_min: float
    voltage_v: float
    usable_mah: float
    avionics_w: float
    momentum_hover_power_w: float  # cross-check
    table: str
    source: str

    def summary(self) -> dict:
        def r(x: float, n: int) -> float:
            return round(float(x), n)

        return {"thrust_to_weight": r(self.thrust_to_weight, 2), "hover_throttle": r(self.hover_throttle, 3),
                "hover_current_a": r(self.hover_current_a, 2), "hover_time_min": r(self.hover_time_min, 1),
                "max_thrust_g_per_motor": r(self.max_thrust_g_per_motor, 1), "hover_power_w": r(self.hover_power_w, 1),
                "momentum_hover_power_w": r(self.momentum_hover_power_w, 1), "voltage_v": r(self.voltage_v, 2),
                "usable_mah": r(self.usable_mah, 1), "avionics_w": r(self.avionics_w, 2), "table": self.table}


def evaluate(spec: Spec, mass_g: float, rotors: int = 4) -> FlightResult | None:
    """Flight numbers for an all-up weight `mass_g`; None when no propulsion table matches."""
    p = propulsion(spec)
    if p is None:
        return None
    b = spec.core.battery
    v = b.cells * CELL_V
    t_max = max_thrust_g(spec)
    per_motor = mass_g / rotors
    throttle, i_motor = p.at_thrust(per_motor)
    if not math.isfinite(i_motor):  # cannot hover: report full throttle (thrust_to_weight < 1 fails the check)
        throttle, i_motor = 1.0, p.table.points[-1][2] * p.scale
    av = avionics_w(spec)
    i_total = rotors * i_motor + av / BEC_EFFICIENCY / v
    usable = b.capacity_mah * b.usable_fraction
    minutes = usable / 1000.0 / i_total * 60.0 if rotors * t_max >= mass_g else 0.0
    mom = rotors * momentum_hover_power_w(per_motor / 1000.0 * G, spec.motors.prop_diameter) + av / BEC_EFFICIENCY
    t = p.table
    name = f"{t.motor} {t.kv}KV, {t.prop}, {t.cells}S" + (f" scaled to {b.cells}S" if p.scale != 1.0 else "")
    return FlightResult(mass_g, rotors, t_max, rotors * t_max / mass_g, min(throttle, 1.0), i_total,
                        i_total * v, minutes, v, usable, av, mom, name, t.source)

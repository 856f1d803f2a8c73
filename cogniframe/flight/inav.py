"""inav.txt: INAV CLI lines: the custom motor mix for this geometry and spin directions (`mmix`,
mix.py) and the gyro filters the vibration analysis recommends (resonance.py). Setting names
from INAV's settings (docs/Settings.md): platform_type, gyro_main_lpf_hz, dterm_lpf_hz,
dynamic_gyro_notch_enabled, dynamic_gyro_notch_min_hz, dynamic_gyro_notch_mode."""

from __future__ import annotations

from . import mix
from .vehicle import Vehicle

# INAV's dynamic notch lower limit stays within the range Betaflight also allows (<= 250 Hz).
NOTCH_MIN_CAP_HZ = 250


def text(v: Vehicle) -> str:
    r = v.resonance
    lines = mix.header(v, "INAV CLI")
    lines += ["# Motor mix from the motors' places (roll, pitch factors = arm / longest arm; yaw -1 for a clockwise prop).",
              "set platform_type = MULTIROTOR", *mix.mmix_lines(v), "",
              "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(r.advice)["inav"]]
    lines += [f"set gyro_main_lpf_hz = {int(r.filter('gyro_lpf_hz'))}",
              f"set dterm_lpf_hz = {int(r.filter('dterm_lpf_hz'))}",
              "set dynamic_gyro_notch_enabled = ON",
              "set dynamic_gyro_notch_mode = 3D",
              f"set dynamic_gyro_notch_min_hz = {int(min(NOTCH_MIN_CAP_HZ, r.filter('rotor_notch_min_hz')))}",
              "save"]
    return "\n".join(lines) + "\n"

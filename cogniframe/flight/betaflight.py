"""betaflight.txt: Betaflight CLI lines: `mixer CUSTOM` with the mix of mix.py and the filters of
resonance.py. Setting names from Betaflight 4.3+ (cli settings): gyro_lpf1_static_hz,
dterm_lpf1_static_hz, dyn_notch_min_hz, dyn_notch_max_hz, dshot_bidir, rpm_filter_harmonics,
yaw_motors_reversed."""

from __future__ import annotations

from . import mix
from .vehicle import Vehicle

# Betaflight's limits: dyn_notch_min_hz 20-250, dyn_notch_max_hz 200-1000.
DYN_MIN_CAP_HZ, DYN_MAX_CAP_HZ = 250, 1000


def text(v: Vehicle) -> str:
    r = v.resonance
    lines = mix.header(v, "Betaflight CLI")
    lines += ["# Motor mix from the motors' places; the yaw signs already hold the spin directions.",
              "mixer CUSTOM", *mix.mmix_lines(v), "set yaw_motors_reversed = OFF", "",
              "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(r.advice)["betaflight"]]
    lines += [f"set gyro_lpf1_static_hz = {int(r.filter('gyro_lpf_hz'))}",
              f"set dterm_lpf1_static_hz = {int(r.filter('dterm_lpf_hz'))}",
              f"set dyn_notch_min_hz = {int(min(DYN_MIN_CAP_HZ, r.filter('rotor_notch_min_hz')))}",
              f"set dyn_notch_max_hz = {int(min(DYN_MAX_CAP_HZ, r.filter('rotor_notch_max_hz')))}",
              "set dshot_bidir = ON",
              "set rpm_filter_harmonics = 3",
              "save"]
    return "\n".join(lines) + "\n"

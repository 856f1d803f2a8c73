"""ardupilot/frame.json and ardupilot/params.parm.

frame.json is ArduPilot SITL's multicopter frame model, launched as

    sim_vehicle.py -v ArduCopter -f quad --model quad:frame.json --add-param-file=params.parm

(`-f quad` keeps ArduCopter's default parameters for a quad; the model string `quad:frame.json`
makes libraries/SITL/SIM_Frame.cpp `Frame::init` call `load_frame_params` on the part after the
colon, which must end in ".json"). Its keys are those `load_frame_params` reads: every one a JSON
number except `moment_inertia` and `motorN_position` / `motorN_vector` (arrays of three); SITL
blanks '#' comments before parsing. Body axes FRD, metres, kg, kg m^2. `motorN_yaw` is the yaw
factor, 1 for a counter-clockwise propeller and -1 for a clockwise one
(AP_MOTORS_MATRIX_YAW_FACTOR_CCW / _CW); motor N drives servo output N, so the file lists the
motors in the order of the FRAME_TYPE params.parm sets (`frame_type`).

What SITL makes of the thrust numbers (ArduPilot/ardupilot libraries/SITL/SIM_Frame.cpp
`Frame::init` and SIM_Motor.cpp `Motor::calc_thrust`, master at c1a9f75): hover_velocity_out =
2 refCurrent refVoltage / (mass g); velocity_max = hover_velocity_out / sqrt(hoverThrOut); thrust =
1/2 rho A_eff velocity_max^2 ((1 - propExpo) c + propExpo c^2) at command c, with A_eff sized so
that hover_velocity_out lifts the mass. Full thrust (c = 1) is therefore mass g / hoverThrOut:
hoverThrOut is the hover thrust as a fraction of full thrust (`Vehicle.hover_thrust_fraction`),
not the ESC throttle at hover, and propExpo is the thrust curve the flight table fits
(`RotorModel.thrust_expo`, the same (1 - e) u + e u^2 form).

params.parm: frame class and type, hover thrust and thrust curve, battery limits, gyro filter,
D-term filters and the throttle-referenced harmonic notch on the rotors (INS_HNTCH_*), with the
gyro rate that keeps its harmonics (INS_GYRO_RATE). Each value sits inside the range the
parameter's @Range documents (the table RANGES below, from the sources it names) or carries a
comment line saying why not.
"""

from __future__ import annotations

import json
import math

from .vehicle import AP_ORDER, BF_ORDER, Vehicle, frd, inertia_in

LIPO_FULL_V, LIPO_EMPTY_V = 4.2, 3.3  # per cell: charged, and where MOT_BAT_VOLT_MIN stops compensating

# ArduCopter FRAME_TYPE and the motor order it numbers (libraries/AP_Motors/AP_MotorsMatrix.cpp,
# master at 7c86187: MOTOR_FRAME_TYPE_X = 1 is motor 1 front right CCW, 2 rear left CCW, 3 front
# left CW, 4 rear right CW, i.e. props in; MOTOR_FRAME_TYPE_BF_X_REV = 18 is Betaflight's order,
# 1 rear right, 2 front right, 3 rear left, 4 front left, every spin reversed, i.e. props out).
FRAME_X, FRAME_BF_X_REV = 1, 18

# Documented ranges (@Range in the parameter's var_info), ArduPilot/ardupilot master:
RANGES = {
    # libraries/AP_Motors/AP_MotorsMulticopter.cpp (c1a9f75): THST_EXPO, THST_HOVER
    "MOT_THST_EXPO": (0.25, 0.8), "MOT_THST_HOVER": (0.125, 0.6875),
    # libraries/AC_AttitudeControl/AC_AttitudeControl_Multi.cpp (67c5752): RAT_RLL_FLTD, RAT_PIT_FLTD
    "ATC_RAT_RLL_FLTD": (5, 100), "ATC_RAT_PIT_FLTD": (5, 100),
    # libraries/AP_InertialSensor/AP_InertialSensor.cpp (5b049ea): _GYRO_FILTER
    "INS_GYRO_FILTER": (0, 256),
    # libraries/Filter/HarmonicNotchFilter.cpp (92775c3): FREQ, BW, ATT, REF
    "INS_HNTCH_FREQ": (10, 495), "INS_HNTCH_BW": (5, 250), "INS_HNTCH_ATT": (5, 50), "INS_HNTCH_REF": (0.0, 1.0),
    "INS_HNTC2_FREQ": (10, 495), "INS_HNTC2_BW": (5, 250),
}

# INS_GYRO_RATE n runs the IMU filters at 1 kHz x 2^n (AP_InertialSensor.cpp _GYRO_RATE:
# "0:1kHz,1:2kHz,2:4kHz,3:8kHz"; 0 and 1 kHz for IMUs without fast sampling), and the harmonic
# notch enables a harmonic only while its centre is below 0.48 x that rate
# (HarmonicNotchFilter.cpp `update`: `if (notch_center < nyquist_limit)`, nyquist_limit =
# 0.48 sample rate). The throttle notch follows the rotors up to full throttle (FREQ x
# sqrt(thrust / REF)), so a harmonic is kept when h x the full-throttle rotor frequency stays
# below the limit.
GYRO_RATES_HZ = (1000, 2000, 4000, 8000)
NYQUIST_FRACTION = 0.48
# The rotor's fundamental and its blade pass (2x for two blades); the third harmonic is left to
# the gyro low-pass, which sits at 0.6 x the hover rotor frequency (resonance.py).
NOTCH_HARMONICS = (1, 2)


def frame_type(v: Vehicle) -> int:
    return FRAME_BF_X_REV if v.props_out else FRAME_X


def motor_order(v: Vehicle) -> tuple[str, ...]:
    return BF_ORDER if v.props_out else AP_ORDER


def notch_harmonics(v: Vehicle) -> tuple[tuple[int, ...], int]:
    """(the harmonics written, INS_GYRO_RATE): the smallest gyro rate that keeps every harmonic
    of NOTCH_HARMONICS up to full throttle; where even 8 kHz does not, the harmonics it keeps."""
    full_hz = v.rotor.max_rotor_hz
    for n, rate in enumerate(GYRO_RATES_HZ):
        if max(NOTCH_HARMONICS) * full_hz < NYQUIST_FRACTION * rate:
            return NOTCH_HARMONICS, n
    kept = tuple(h for h in NOTCH_HARMONICS if h * full_hz < NYQUIST_FRACTION * GYRO_RATES_HZ[-1])
    return kept, len(GYRO_RATES_HZ) - 1


def frame_model(v: Vehicle) -> dict:
    inertia = inertia_in("frd", v.mass.inertia)
    rs = v.ordered(motor_order(v))
    diag = max(math.dist(a.position_m[:2], b.position_m[:2]) for a in v.rotors for b in v.rotors)
    out = {"mass": round(v.mass.mass_kg, 5), "diagonal_size": round(diag, 5),
           "refVoltage": round(v.voltage_v, 3), "refCurrent": round(v.hover_current_a, 3), "refAlt": 0.0, "refTempC": 15.0,
           "maxVoltage": round(LIPO_FULL_V * v.cells, 3), "battCapacityAh": round(v.capacity_mah / 1000.0, 4),
           "propExpo": round(v.rotor.thrust_expo, 4), "hoverThrOut": round(v.hover_thrust_fraction, 4),
           "pwmMin": 1000.0, "pwmMax": 2000.0,
           "disc_area": round(len(v.rotors) * math.pi * (v.rotor.prop_diameter_m / 2) ** 2, 6),
           "moment_inertia": [float(f"{inertia[i, i]:.6g}") for i in range(3)],
           "num_motors": float(len(v.rotors))}
    for i, r in enumerate(rs, start=1):
        out[f"motor{i}_position"] = [round(c, 5) + 0.0 for c in frd(r.position_m)]
        out[f"motor{i}_vector"] = [0.0, 0.0, -1.0]  # thrust up: -z in FRD
        out[f"motor{i}_yaw"] = 1.0 if r.spin == "ccw" else -1.0
    return out


def frame_json(v: Vehicle) -> str:
    head = ["# ArduPilot SITL frame model for " + v.name + ", written by cogniframe (`cogniframe fly`).",
            "# sim_vehicle.py -v ArduCopter -f quad --model quad:frame.json --add-param-file=params.parm",
            "# Body axes FRD (x front, y right, z down), metres, kg, kg m^2, about the centre of gravity.",
            f"# Motors in FRAME_TYPE {frame_type(v)}'s order (params.parm). hoverThrOut is the hover thrust over full thrust",
            "# (SITL's full thrust = mass g / hoverThrOut); the ESC throttle at hover is "
            f"{v.rotor.hover_throttle:.3f} (flight table).",
            "# refSpd / refAngle / refRotRate (drag) are not known for this frame: SITL's defaults stand."]
    return "\n".join(head) + "\n" + json.dumps(frame_model(v), indent=2) + "\n"


def in_range(name: str, value: float, why: str) -> tuple[float, list[str]]:
    """The value clamped into the documented range, and the comment lines a clamp needs."""
    lo, hi = RANGES[name]
    if lo <= value <= hi:
        return value, []
    got = min(max(value, lo), hi)
    return got, [f"# {name}: {why} gives {value:g}, outside the documented range {lo:g}-{hi:g}; written as {got:g}"]


def params_parm(v: Vehicle) -> str:
    r = v.resonance
    hover_hz = r.filter("hover_rotor_hz")
    harmonics, gyro_rate = notch_harmonics(v)
    expo = round(v.rotor.thrust_expo, 3)
    lines = [f"# ArduCopter parameters for {v.name}, written by cogniframe (`cogniframe fly`); load with",
             "# `param load params.parm` (MAVProxy) or Mission Planner's Full Parameter List > Load from file.",
             "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(r.advice)["ardupilot"]]
    expo_w, expo_note = in_range("MOT_THST_EXPO", expo, "the flight table's thrust curve")
    if expo_note:
        worst = abs(expo - expo_w) * 0.25  # (e1 - e2)(u^2 - u) is largest at u = 1/2
        expo_note.append(f"# (the two curves differ by at most {worst:.1%} of full thrust, at half throttle)")
    dterm = int(r.filter("dterm_lpf_hz"))
    freq_w, freq_note = in_range("INS_HNTCH_FREQ", round(hover_hz, 1), "the rotor frequency at hover")
    values = [("FRAME_CLASS", 1, ["# quad"]),
              ("FRAME_TYPE", frame_type(v), ["# X, props in (motor 1 front right CCW)" if not v.props_out else
                                             "# BetaFlightXReversed: props out, Betaflight's motor order (motor 1 rear right CCW)"]),
              ("MOT_THST_HOVER", round(v.hover_thrust_fraction, 4),
               ["# hover thrust / full thrust (AP_MotorsMulticopter: 'Motor thrust needed to hover expressed as a number",
                f"# from 0 to 1'); the ESC throttle at hover is {v.rotor.hover_throttle:.3f}"]),
              ("MOT_THST_EXPO", expo_w, ["# thrust curve fitted to the flight table", *expo_note]),
              ("MOT_BAT_VOLT_MAX", round(LIPO_FULL_V * v.cells, 2), [f"# {v.cells}S charged"]),
              ("MOT_BAT_VOLT_MIN", round(LIPO_EMPTY_V * v.cells, 2), [f"# {v.cells}S near empty"]),
              ("INS_GYRO_FILTER", int(r.filter("gyro_lpf_hz")), ["# gyro low-pass, Hz"]),
              ("INS_GYRO_RATE", gyro_rate,
               [f"# IMU filters at {GYRO_RATES_HZ[gyro_rate] // 1000} kHz: the notch keeps harmonic h only below "
                f"{NYQUIST_FRACTION} x the rate, and {max(harmonics)} x full throttle is {max(harmonics) * v.rotor.max_rotor_hz:.0f} Hz"])]
    for axis in ("RLL", "PIT"):
        w, note = in_range(f"ATC_RAT_{axis}_FLTD", dterm, "0.3 x the hover rotor frequency")
        values.append((f"ATC_RAT_{axis}_FLTD", int(w), [f"# {'roll' if axis == 'RLL' else 'pitch'} D-term low-pass, Hz", *note]))
    values += [("INS_HNTCH_ENABLE", 1, ["# harmonic notch on the rotors (reboot after setting)"]),
               ("INS_HNTCH_MODE", 1, ["# throttle-referenced: centre = FREQ x sqrt(thrust / REF)"]),
               ("INS_HNTCH_REF", round(v.hover_thrust_fraction, 4), ["# hover thrust / full thrust, where the rotors turn at FREQ"]),
               ("INS_HNTCH_FREQ", freq_w, ["# rotor frequency at hover, Hz", *freq_note]),
               ("INS_HNTCH_BW", round(freq_w / 2, 1), ["# half the centre frequency"]),
               ("INS_HNTCH_HMNCS", sum(1 << (h - 1) for h in harmonics),
                ["# harmonics " + ", ".join(map(str, harmonics)) + " (bitmask; blade pass of two blades is the 2nd)"]),
               ("INS_HNTCH_ATT", 40, ["# dB"])]
    flags = [f for f in r.flags if f.band.startswith("rotor")]
    if flags:
        values += [("INS_HNTC2_ENABLE", 1, ["# fixed notch on the frame mode the rotors meet"]), ("INS_HNTC2_MODE", 0, ["# fixed"]),
                   ("INS_HNTC2_FREQ", round(flags[0].hz, 1), [f"# frame mode {flags[0].mode}"]),
                   ("INS_HNTC2_BW", round(flags[0].hz * 0.3, 1), ["# +-15 %"]), ("INS_HNTC2_HMNCS", 1, ["# fundamental only"])]
    for k, val, why in values:
        lines += [*why, f"{k} {val}"]
    return "\n".join(lines) + "\n"

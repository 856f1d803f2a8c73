"""ardupilot/frame.json and ardupilot/params.parm.

frame.json is ArduPilot SITL's multicopter frame model (`sim_vehicle.py -v ArduCopter -f
quad:frame.json`): the keys `Frame::load_frame_params` reads in libraries/SITL/SIM_Frame.cpp,
every one a JSON number except `moment_inertia` and `motorN_position` / `motorN_vector` (arrays
of three numbers); SITL strips '#' comments before parsing. Body axes FRD, metres, kg, kg m^2;
`motorN_yaw` is the yaw factor, 1 for a counter-clockwise propeller and -1 for a clockwise one
(AP_MOTORS_MATRIX_YAW_FACTOR_CCW / _CW). Motor numbers follow ArduCopter's quad X
(FRAME_CLASS 1, FRAME_TYPE 1): 1 front right, 2 rear left, 3 front left, 4 rear right.

params.parm: frame class and type, hover throttle and thrust curve, battery limits, gyro filter
and the throttle-referenced harmonic notch on the rotors (INS_HNTCH_*), as the ArduPilot wiki's
"Harmonic Notch" and "Tuning Process" pages name them.
"""

from __future__ import annotations

import json
import math

from .vehicle import AP_ORDER, Vehicle, frd, inertia_in

LIPO_FULL_V, LIPO_EMPTY_V = 4.2, 3.3  # per cell: charged, and where MOT_BAT_VOLT_MIN stops compensating


def frame_model(v: Vehicle) -> dict:
    inertia = inertia_in("frd", v.mass.inertia)
    rs = v.ordered(AP_ORDER)
    diag = max(math.dist(a.position_m[:2], b.position_m[:2]) for a in v.rotors for b in v.rotors)
    out = {"mass": round(v.mass.mass_kg, 5), "diagonal_size": round(diag, 5),
           "refVoltage": round(v.voltage_v, 3), "refCurrent": round(v.hover_current_a, 3), "refAlt": 0.0, "refTempC": 15.0,
           "maxVoltage": round(LIPO_FULL_V * v.cells, 3), "battCapacityAh": round(v.capacity_mah / 1000.0, 4),
           "propExpo": round(v.rotor.thrust_expo, 4), "hoverThrOut": round(v.rotor.hover_throttle, 4),
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
            "# sim_vehicle.py -v ArduCopter -f quad:frame.json --add-param-file=params.parm",
            "# Body axes FRD (x front, y right, z down), metres, kg, kg m^2, about the centre of gravity.",
            "# refSpd / refAngle / refRotRate (drag) are not known for this frame: SITL's defaults stand."]
    return "\n".join(head) + "\n" + json.dumps(frame_model(v), indent=2) + "\n"


def params_parm(v: Vehicle) -> str:
    r = v.resonance
    hover_hz = r.filter("hover_rotor_hz")
    lines = [f"# ArduCopter parameters for {v.name}, written by cogniframe (`cogniframe fly`); load with",
             "# `param load params.parm` (MAVProxy) or Mission Planner's Full Parameter List > Load from file.",
             "# Filters (resonance.json):"]
    lines += [f"#   {a}" for a in dict(r.advice)["ardupilot"]]
    values = [("FRAME_CLASS", 1, "quad"), ("FRAME_TYPE", 1, "X"),
              ("MOT_THST_HOVER", round(v.rotor.hover_throttle, 4), "hover throttle, flight tables"),
              ("MOT_THST_EXPO", round(v.rotor.thrust_expo, 3), "thrust curve fitted to the flight table"),
              ("MOT_BAT_VOLT_MAX", round(LIPO_FULL_V * v.cells, 2), f"{v.cells}S charged"),
              ("MOT_BAT_VOLT_MIN", round(LIPO_EMPTY_V * v.cells, 2), f"{v.cells}S near empty"),
              ("INS_GYRO_FILTER", int(r.filter("gyro_lpf_hz")), "gyro low-pass, Hz"),
              ("ATC_RAT_RLL_FLTD", int(r.filter("dterm_lpf_hz")), "roll D-term low-pass, Hz"),
              ("ATC_RAT_PIT_FLTD", int(r.filter("dterm_lpf_hz")), "pitch D-term low-pass, Hz"),
              ("INS_HNTCH_ENABLE", 1, "harmonic notch on the rotors (reboot after setting)"),
              ("INS_HNTCH_MODE", 1, "throttle-referenced"),
              ("INS_HNTCH_REF", round(v.rotor.hover_throttle, 4), "throttle at which the rotors turn at FREQ: hover"),
              ("INS_HNTCH_FREQ", round(min(hover_hz, 495.0), 1), "rotor frequency at hover, Hz"),
              ("INS_HNTCH_BW", round(min(hover_hz, 495.0) / 2, 1), "half the centre frequency"),
              ("INS_HNTCH_HMNCS", 7, "harmonics 1, 2 and 3 (blade pass of two blades is the 2nd)"),
              ("INS_HNTCH_ATT", 40, "dB")]
    flags = [f for f in r.flags if f.band.startswith("rotor")]
    if flags:
        values += [("INS_HNTC2_ENABLE", 1, "fixed notch on the frame mode the rotors meet"), ("INS_HNTC2_MODE", 0, "fixed"),
                   ("INS_HNTC2_FREQ", round(flags[0].hz, 1), f"frame mode {flags[0].mode}"),
                   ("INS_HNTC2_BW", round(flags[0].hz * 0.3, 1), "+-15 %"), ("INS_HNTC2_HMNCS", 1, "fundamental only")]
    for k, val, why in values:
        lines += [f"# {why}", f"{k} {val}"]
    return "\n".join(lines) + "\n"

"""`cogniframe fly` and the build's flight/ folder: mass properties, rotor constants, the
flight-controller mix, the simulator models (each checked by what reads it: rotorpy flies it,
SDFormat parses it, the ArduPilot and PX4 names are the ones their sources define) and the
resonance check."""

from __future__ import annotations

import copy
import json
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tiers

from cogniframe import api
from cogniframe.analysis.constants import G
from cogniframe.analysis import massprops
from cogniframe.flight.mix import QUAD_X

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("carbon", "bamboo")


def _params(name: str) -> Path:
    return ROOT / ("examples" if name.startswith("rect") else "params") / f"{name}.yaml"


@pytest.fixture(scope="module")
@tiers.needs('fe')
def flown(tmp_path_factory):
    """{name: (flight folder, check result)} for both presets and the 240 x 180 example."""
    out = {}
    for name in (*PRESETS, "rect-240x180"):
        d = api.load(_params(name))
        folder = d.fly(tmp_path_factory.mktemp("fly") / name)
        out[name] = (folder, d.check().result)
    return out


def _strip_hash_comments(text: str) -> str:
    """What ArduPilot's SIM_Frame.cpp does before parsing: blank every '#' to the end of its line."""
    return re.sub(r"#[^\n]*", "", text)


# -- mass properties ---------------------------------------------------------------------------

def test_inertia_of_a_box_and_two_rods_matches_the_closed_form():
    """A 100 g box 40 x 20 x 10 mm at the origin and two 10 g rods 200 mm long along x at
    y = +-50 mm: I = m (b^2 + c^2) / 12 per box axis, m L^2 / 12 + m d^2 per rod (thin rods
    plus the parallel-axis term), the centre of gravity at the origin."""
    bodies = [massprops.box("box", 100.0, (0, 0, 0), (40, 20, 10)),
              massprops.rod("r1", 10.0, (-100, 50, 0), (100, 50, 0), 0.0),
              massprops.rod("r2", 10.0, (-100, -50, 0), (100, -50, 0), 0.0)]
    mp = massprops.combine(bodies, "test")
    ixx = 100 * (20**2 + 10**2) / 12 + 2 * 10 * 50**2
    iyy = 100 * (40**2 + 10**2) / 12 + 2 * 10 * 200**2 / 12
    izz = 100 * (40**2 + 20**2) / 12 + 2 * (10 * 200**2 / 12 + 10 * 50**2)
    assert mp.mass_kg == pytest.approx(0.120)
    assert mp.cg_m == pytest.approx((0, 0, 0), abs=1e-12)
    assert np.diag(mp.inertia) == pytest.approx(np.array([ixx, iyy, izz]) * 1e-9, rel=1e-12)
    # moved off the origin: the centre of gravity follows, the inertia about it does not change
    shifted = massprops.combine([massprops.box("box", 100.0, (5, 5, 5), (40, 20, 10)),
                                 massprops.rod("r1", 10.0, (-95, 55, 5), (105, 55, 5), 0.0),
                                 massprops.rod("r2", 10.0, (-95, -45, 5), (105, -45, 5), 0.0)], "test")
    assert shifted.cg_mm == pytest.approx((5, 5, 5))
    assert shifted.inertia == pytest.approx(mp.inertia, rel=1e-9, abs=1e-15)


def test_mesh_solid_props_match_the_box_closed_form():
    """The build's STL path: a 40 x 20 x 10 mm box as 12 triangles, turned and moved, carrying
    8 g: the box's m (b^2 + c^2) / 12 about each of its own axes."""
    import trimesh

    m = trimesh.creation.box(extents=(40, 20, 10))
    props = massprops.solid_props(m.triangles)
    assert props.volume == pytest.approx(8000) and props.centroid == pytest.approx((0, 0, 0), abs=1e-12)
    tf = trimesh.transformations.rotation_matrix(0.7, (1, 2, 3))
    tf[:3, 3] = (5, -3, 40)
    body = massprops.placed_body("box", 8.0, props, tf)
    r = tf[:3, :3]
    assert body.centroid == pytest.approx((5, -3, 40))
    assert r.T @ np.asarray(body.inertia) @ r == pytest.approx(np.diag([8 * (400 + 100), 8 * (1600 + 100), 8 * (1600 + 400)]) / 12,
                                                               abs=1e-9)


def test_cylinder_and_propeller_closed_forms():
    c = massprops.cylinder("c", 6.0, (0, 0, 0), (0, 0, 1), 7.0, 13.0)
    assert np.diag(c.inertia) == pytest.approx([6 * (3 * 49 + 169) / 12] * 2 + [6 * 49 / 2])
    p = massprops.propeller("p", 1.5, (0, 0, 0), 76.2)  # slender bar m D^2 / 12 about the shaft
    assert p.inertia[2][2] == pytest.approx(1.5 * 76.2**2 / 12) and p.inertia[0][0] == pytest.approx(p.inertia[2][2] / 2)


@pytest.mark.parametrize("name", PRESETS)
def test_mass_in_every_file_is_checks_all_up_mass(flown, name):
    folder, result = flown[name]
    m = result.mass.total_g / 1000.0
    rp = json.loads((folder / "rotorpy.json").read_text())
    ap = json.loads(_strip_hash_comments((folder / "ardupilot" / "frame.json").read_text()))
    sih = {line.split("\t")[2]: float(line.split("\t")[3]) for line in (folder / "px4" / "sih.params").read_text().splitlines()
           if not line.startswith("#")}
    sdf = (folder / "gazebo" / "model.sdf").read_text()
    sdf_mass = sum(float(x) for x in re.findall(r"<mass>([^<]+)</mass>", sdf))
    res = json.loads((folder / "resonance.json").read_text())
    for got in (rp["mass"], ap["mass"], sih["SIH_MASS"], sdf_mass, res["mass"]["mass_kg"]):
        assert got == pytest.approx(m, abs=2e-5)


# -- rotors ------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", PRESETS)
def test_rotor_constants_reproduce_the_flight_numbers(flown, name):
    """k_eta puts hover at the rotor speed `check` compares the modes with; full throttle gives
    the flight tables' full thrust; k_m / k_eta is a small propeller's 0.5-1 % of a metre."""
    folder, result = flown[name]
    rp = json.loads((folder / "rotorpy.json").read_text())
    w_hover = math.sqrt(rp["mass"] * G / 4 / rp["k_eta"])
    assert w_hover / (2 * math.pi) == pytest.approx(result.stiffness["hover_rotor_hz"], rel=1e-3)
    assert rp["k_eta"] * rp["rotor_speed_max"] ** 2 == pytest.approx(result.flight.max_thrust_g_per_motor / 1000 * G, rel=1e-3)
    assert 0.004 < rp["k_m"] / rp["k_eta"] < 0.012
    res = json.loads((folder / "resonance.json").read_text())
    assert res["rotor"]["hover_throttle"] == pytest.approx(result.flight.hover_throttle, abs=1e-3)
    assert set(res["rotor"]["sources"]) >= {"k_eta", "k_m", "thrust_max", "tau_m"}


# -- rotorpy flies it ----------------------------------------------------------------------------

def _fly_step(plant: dict, controller: dict, seconds: float = 4.0, dt: float = 0.005):
    """rotorpy's Multirotor (the plant) under rotorpy's SE3Control (its model: `controller`),
    hovering at 1 m and commanded 1 m forward at t = 0. Times and positions."""
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.vehicles.multirotor import Multirotor

    w_hover = math.sqrt(plant["mass"] * 9.81 / plant["num_rotors"] / plant["k_eta"])
    state = {"x": np.array([0.0, 0.0, 1.0]), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]), "w": np.zeros(3),
             "wind": np.zeros(3), "rotor_speeds": np.full(plant["num_rotors"], w_hover)}
    vehicle = Multirotor(plant, initial_state=copy.deepcopy(state), control_abstraction="cmd_motor_speeds", aero=False)
    control = SE3Control(controller)
    goal = {"x": np.array([1.0, 0.0, 1.0]), "x_dot": np.zeros(3), "x_ddot": np.zeros(3), "x_dddot": np.zeros(3),
            "x_ddddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0}
    ts, xs = [], []
    for k in range(int(round(seconds / dt))):
        state = vehicle.step(state, control.update(k * dt, state, goal), dt)
        ts.append((k + 1) * dt)
        xs.append(state["x"].copy())
    return np.array(ts), np.array(xs), goal["x"]


def _settling(ts, xs, goal, band: float = 0.05) -> tuple[float, float]:
    err = np.linalg.norm(xs - goal, axis=1)
    if not np.isfinite(err).all():
        return math.inf, math.inf
    out = np.nonzero(err > band)[0]
    return (ts[out[-1]] if out.size else 0.0), float(err[-1])


@pytest.mark.parametrize("name", PRESETS)
def test_rotorpy_model_hovers_and_follows_a_1_m_step_with_se3control(flown, name):
    """The plant is rotorpy.json as written, checked against `check` (mass and hover rotor
    speed above); rotorpy's own SE3Control, fed the same file, settles the 1 m step within 5 cm
    in under 2.5 s and holds it to 1 cm."""
    from cogniframe.flight.rotorpy_params import load

    p = load(flown[name][0] / "rotorpy.json")
    ts, xs, goal = _fly_step(p, p)
    t_settle, final = _settling(ts, xs, goal)
    assert t_settle < 2.5 and final < 0.01
    assert np.abs(xs[:, 2] - 1.0).max() < 0.05  # altitude held through the step


@pytest.mark.parametrize("wrong", [{"Ixx": 10.0, "Iyy": 10.0, "Izz": 10.0}, {"k_eta": 0.5}])
def test_rotorpy_step_fails_with_a_wrong_inertia_or_thrust_coefficient(flown, wrong):
    """The same flight with the controller given a 10x inertia or half the thrust coefficient
    misses the goal: the test above can fail."""
    from cogniframe.flight.rotorpy_params import load

    p = load(flown["carbon"][0] / "rotorpy.json")
    q = dict(p)
    for k, f in wrong.items():
        q[k] = p[k] * f
    ts, xs, goal = _fly_step(p, q)
    t_settle, final = _settling(ts, xs, goal)
    assert t_settle >= 2.5 or final >= 0.01
    assert final > 0.1


# -- what the simulators read ---------------------------------------------------------------------

@pytest.mark.parametrize("name", PRESETS)
def test_sdf_passes_sdformats_own_check(flown, name):
    """`ign sdf -k` (Debian's libsdformat + ignition-tools; .ci/run installs them)."""
    ign = shutil.which("ign")
    if ign is None:
        pytest.skip("ign (ignition-tools with libsdformat) is not installed")
    folder, result = flown[name]
    r = subprocess.run([ign, "sdf", "-k", str(folder / "gazebo" / "model.sdf")], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "Valid" in r.stdout, r.stdout + r.stderr
    sdf = (folder / "gazebo" / "model.sdf").read_text()
    # gz-sim (Harmonic) as PX4's x500: the motor model system per rotor, IMU and barometer, drag
    assert sdf.count('filename="gz-sim-multicopter-motor-model-system"') == 4 and "libgazebo" not in sdf
    assert sorted(re.findall(r"<turningDirection>(\w+)</turningDirection>", sdf)) == ["ccw", "ccw", "cw", "cw"]
    assert 'type="imu"' in sdf and 'type="air_pressure"' in sdf
    assert all(float(x) > 0 for x in re.findall(r"<(?:rotorDragCoefficient|rollingMomentCoefficient)>([^<]+)<", sdf))
    # the collision is the cage: its joints' centres' box
    size = [float(x) for x in re.search(r'<collision name="base_link_collision">.*?<size>([^<]+)</size>', sdf, re.S).group(1).split()]
    lo, hi = result.design.frame.bbox()
    assert sorted(size) == pytest.approx(sorted((hi - lo) / 1000), abs=1e-5)


# The frame model's keys, as libraries/SITL/SIM_Frame.cpp (Frame::load_frame_params) reads them:
# FRAME_VAR floats, moment_inertia a vector of three, motorN_position / _vector vectors, motorN_yaw float.
ARDUPILOT_FLOATS = {"mass", "diagonal_size", "refSpd", "refAngle", "refVoltage", "refCurrent", "refAlt", "refTempC",
                    "maxVoltage", "battCapacityAh", "refBatRes", "propExpo", "refRotRate", "hoverThrOut", "pwmMin",
                    "pwmMax", "spin_min", "spin_max", "slew_max", "disc_area", "mdrag_coef", "num_motors"}
ARDUPILOT_VECTORS = {"moment_inertia"}


@pytest.mark.parametrize("name", PRESETS)
def test_ardupilot_frame_file_has_the_keys_sitl_reads_with_its_types(flown, name):
    folder, result = flown[name]
    model = json.loads(_strip_hash_comments((folder / "ardupilot" / "frame.json").read_text()))
    for k, v in model.items():
        m = re.fullmatch(r"motor(\d+)_(position|vector|yaw)", k)
        if m:
            assert 1 <= int(m.group(1)) <= 4
            kind = "float" if m.group(2) == "yaw" else "vector"
        else:
            assert k in ARDUPILOT_FLOATS | ARDUPILOT_VECTORS, k
            kind = "vector" if k in ARDUPILOT_VECTORS else "float"
        if kind == "float":
            assert isinstance(v, float), k
        else:
            assert isinstance(v, list) and len(v) == 3 and all(isinstance(x, float) for x in v), k
    assert model["num_motors"] == 4.0 and {f"motor{i}_position" for i in range(1, 5)} <= set(model)
    # ArduCopter quad X: motor 1 front right and 2 rear left counter-clockwise (yaw +1), FRD positions
    assert model["motor1_position"][0] > 0 < model["motor1_position"][1] and model["motor1_yaw"] == 1.0
    assert model["motor2_position"][0] < 0 > model["motor2_position"][1] and model["motor2_yaw"] == 1.0
    assert model["hoverThrOut"] == pytest.approx(_hover_thrust_fraction(result), abs=1e-4)
    values = _parm(folder)
    assert values["FRAME_CLASS"] == "1" and values["FRAME_TYPE"] == "1" and values["INS_HNTCH_ENABLE"] == "1"
    assert float(values["INS_HNTCH_FREQ"]) == pytest.approx(result.stiffness["hover_rotor_hz"], abs=0.1)
    assert _ardupilot_defects(folder, result) == []


def _hover_thrust_fraction(result) -> float:
    """check's hover thrust over full thrust: a quarter of the all-up weight over one rotor's
    full-throttle thrust (the flight table's)."""
    return result.mass.total_g / 4 / result.flight.max_thrust_g_per_motor


def _parm(folder) -> dict[str, str]:
    text = (folder / "ardupilot" / "params.parm").read_text()
    return dict(line.split() for line in text.splitlines() if line and not line.startswith("#"))


def _sitl_thrust(model: dict) -> tuple[float, float]:
    """ArduPilot SITL's full thrust per rotor (N) and hover thrust fraction from a frame model,
    written out from its source (ArduPilot/ardupilot libraries/SITL/SIM_Frame.cpp Frame::init:
    hover_velocity_out = 2 refCurrent refVoltage / (mass g), effective_disc_area = mass g /
    (1/2 rho hover_velocity_out^2), velocity_max = hover_velocity_out / sqrt(hoverThrOut);
    SIM_Motor.cpp Motor::calc_thrust at command 1, full pack, no inflow: 1/2 rho
    effective_prop_area velocity_max^2, effective_prop_area = effective_disc_area / motors)."""
    g, rho = 9.80665, 1.225
    weight = model["mass"] * g
    v_hover = 2 * model["refCurrent"] * model["refVoltage"] / weight
    area = weight / (0.5 * rho * v_hover**2) / model["num_motors"]
    full = 0.5 * rho * area * (v_hover / math.sqrt(model["hoverThrOut"])) ** 2
    return full, weight / model["num_motors"] / full


@pytest.mark.parametrize("name", PRESETS)
def test_ardupilot_sitl_full_thrust_and_hover_fraction_are_checks(flown, name):
    """SITL flies our frame.json with check's full thrust per rotor and hover thrust fraction
    (within 2 %): hoverThrOut is a thrust fraction, not the ESC throttle (0.55 would give
    SITL 1.07 N a rotor instead of 1.72 N for carbon)."""
    folder, result = flown[name]
    model = json.loads(_strip_hash_comments((folder / "ardupilot" / "frame.json").read_text()))
    full, fraction = _sitl_thrust(model)
    assert full == pytest.approx(result.flight.max_thrust_g_per_motor / 1000 * G, rel=0.02)
    assert fraction == pytest.approx(_hover_thrust_fraction(result), rel=0.02)
    raw = dict(model, hoverThrOut=result.flight.hover_throttle)
    assert _sitl_thrust(raw)[0] < 0.8 * result.flight.max_thrust_g_per_motor / 1000 * G


# ArduCopter's quad motor tables (ArduPilot/ardupilot libraries/AP_Motors/AP_MotorsMatrix.cpp,
# master at 7c86187): FRAME_TYPE -> (arm angle from the nose, clockwise positive, yaw factor) per
# motor number. 1 X; 12 BF_X; 18 BF_X_REV.
AP_QUAD = {1: ((45, 1), (-135, 1), (-45, -1), (135, -1)), 12: ((135, -1), (45, 1), (-135, 1), (-45, -1)),
           18: ((135, 1), (45, -1), (-135, -1), (-45, 1))}


def _ardupilot_defects(folder, result, parm: dict | None = None, model: dict | None = None, text: str | None = None) -> list[str]:
    """What ArduCopter would read otherwise than we mean in params.parm and frame.json."""
    from cogniframe.flight.ardupilot import RANGES

    parm = parm if parm is not None else _parm(folder)
    model = model if model is not None else json.loads(_strip_hash_comments((folder / "ardupilot" / "frame.json").read_text()))
    text = text if text is not None else (folder / "ardupilot" / "params.parm").read_text()
    out = []
    fraction = _hover_thrust_fraction(result)
    for key, got in (("MOT_THST_HOVER", parm["MOT_THST_HOVER"]), ("INS_HNTCH_REF", parm["INS_HNTCH_REF"]),
                     ("hoverThrOut", model["hoverThrOut"])):
        if float(got) != pytest.approx(fraction, rel=0.02):
            out.append(f"{key} {got} is not the hover thrust fraction {fraction:.3f}")
    # the notch keeps harmonic h only below 0.48 x the gyro rate (HarmonicNotchFilter.cpp update);
    # the throttle notch reaches h x the full-throttle rotor frequency
    res = json.loads((folder / "resonance.json").read_text())
    full_hz = next(b for b in res["bands"] if b["name"] == "rotor 1x")["hi_hz"]
    rate = 1000 * 2 ** int(parm.get("INS_GYRO_RATE", 0))
    for h in range(1, 9):
        if int(parm["INS_HNTCH_HMNCS"]) & (1 << (h - 1)) and h * full_hz >= 0.48 * rate:
            out.append(f"harmonic {h} ({h * full_hz:.0f} Hz at full throttle) dropped at {rate} Hz")
    for i, (angle, yaw) in enumerate(AP_QUAD[int(parm["FRAME_TYPE"])], start=1):
        x, y, _ = model[f"motor{i}_position"]
        if abs((math.degrees(math.atan2(y, x)) - angle + 180) % 360 - 180) > 20 or model[f"motor{i}_yaw"] != yaw:
            out.append(f"motor {i} of FRAME_TYPE {parm['FRAME_TYPE']} is at {angle} deg with yaw {yaw}")
    lines = text.splitlines()
    for n, line in enumerate(lines):
        key, _, val = line.partition(" ")
        if key in RANGES and not RANGES[key][0] <= float(val) <= RANGES[key][1]:
            if not any(key in c and "documented range" in c for c in lines[max(0, n - 3):n]):
                out.append(f"{key} {val} outside {RANGES[key]} without a comment")
    return out


def test_ardupilot_defect_check_fails_on_each_defect_of_issue_46(flown):
    """Raw throttle where thrust is meant, a dropped harmonic, props-out yaw under FRAME_TYPE 1, an
    out-of-range value without its comment: each is caught."""
    folder, result = flown["carbon"]
    parm, text = _parm(folder), (folder / "ardupilot" / "params.parm").read_text()
    model = json.loads(_strip_hash_comments((folder / "ardupilot" / "frame.json").read_text()))
    raw = f"{result.flight.hover_throttle:.3f}"
    assert any("MOT_THST_HOVER" in d for d in _ardupilot_defects(folder, result, parm=dict(parm, MOT_THST_HOVER=raw)))
    assert any("hoverThrOut" in d for d in _ardupilot_defects(folder, result, model=dict(model, hoverThrOut=float(raw))))
    dropped = _ardupilot_defects(folder, result, parm=dict(parm, INS_HNTCH_HMNCS="7", INS_GYRO_RATE="0"))
    assert any("harmonic 2" in d for d in dropped) and any("harmonic 3" in d for d in dropped)
    flipped = dict(model, **{f"motor{i}_yaw": -model[f"motor{i}_yaw"] for i in range(1, 5)})
    assert any("FRAME_TYPE 1" in d for d in _ardupilot_defects(folder, result, model=flipped))
    bare = re.sub(r"^# MOT_THST_EXPO.*\n(# \(.*\n)?", "", text.replace("MOT_THST_EXPO 0.8", "MOT_THST_EXPO 0.848"), flags=re.M)
    assert any("MOT_THST_EXPO 0.848" in d for d in _ardupilot_defects(folder, result, text=bare))


# PX4's parameter names, from its sources: src/modules/simulation/simulator_sih/sih_params.yaml
# (SIH_*), src/modules/control_allocator/module.yaml (CA_AIRFRAME, CA_ROTOR_COUNT,
# CA_ROTOR${i}_PX/_PY/_PZ/_KM), the position controller (MPC_THR_HOVER), the mixer (THR_MDL_FAC)
# and the gyro filters (src/modules/sensors/vehicle_angular_velocity: IMU_GYRO_CUTOFF,
# IMU_DGYRO_CUTOFF, IMU_GYRO_NF0_FRQ, IMU_GYRO_NF0_BW).
PX4_NAMES = {"SIH_MASS", "SIH_IXX", "SIH_IYY", "SIH_IZZ", "SIH_IXY", "SIH_IXZ", "SIH_IYZ", "SIH_T_MAX", "SIH_Q_MAX",
             "SIH_L_ROLL", "SIH_L_PITCH", "SIH_KDV", "SIH_KDW", "SIH_T_TAU", "SIH_VEHICLE_TYPE",
             "CA_AIRFRAME", "CA_ROTOR_COUNT", "MPC_THR_HOVER", "THR_MDL_FAC", "IMU_GYRO_CUTOFF", "IMU_DGYRO_CUTOFF",
             "IMU_GYRO_NF0_FRQ", "IMU_GYRO_NF0_BW", "SENS_EN_GPSSIM", "SENS_EN_BAROSIM", "SENS_EN_MAGSIM"} \
    | {f"CA_ROTOR{i}_{a}" for i in range(12) for a in ("PX", "PY", "PZ", "KM", "CT")} \
    | {f"{p}{i}" for p in ("PWM_MAIN_FUNC", "SIM_GZ_EC_FUNC") for i in range(1, 9)}


@pytest.mark.parametrize("name", PRESETS)
def test_px4_parameters_are_names_px4_defines(flown, name):
    folder, result = flown[name]
    sih = [line.split("\t") for line in (folder / "px4" / "sih.params").read_text().splitlines() if not line.startswith("#")]
    assert all(len(f) == 5 and f[:2] == ["1", "1"] and f[4] in ("6", "9") for f in sih)
    names = [f[2] for f in sih]
    airframes = list((folder / "px4").glob("[0-9]*_*"))
    assert len(airframes) == 1 and re.fullmatch(r"\d+_sihsim_\w+", airframes[0].name)  # PX4 lists numbered airframes
    script = airframes[0].read_text()
    assert "PX4_SIMULATOR=${PX4_SIMULATOR:=sihsim}" in script and ". ${R}etc/init.d/rc.mc_defaults" in script
    air = re.findall(r"^param set-default (\S+) (\S+)$", script, re.M)
    assert set(names) | {n for n, _ in air} <= PX4_NAMES
    assert {"SIH_MASS", "SIH_IXX", "SIH_T_MAX", "SIH_Q_MAX", "SIH_L_ROLL", "SIH_L_PITCH", "SIH_KDV", "SIH_KDW"} <= set(names)
    a = dict(air)
    assert a["CA_ROTOR_COUNT"] == "4" and float(a["MPC_THR_HOVER"]) == pytest.approx(_hover_thrust_fraction(result), abs=1e-3)
    # SIH's thrust is linear in the command: no thrust curve under SIH, and hover at m g / (4 T_max)
    s = {f[2]: float(f[3]) for f in sih}
    assert a["THR_MDL_FAC"] == "0.0" and s["THR_MDL_FAC"] == 0.0
    assert s["MPC_THR_HOVER"] == pytest.approx(s["SIH_MASS"] * G / 4 / s["SIH_T_MAX"], abs=1e-3)
    assert [a[f"PWM_MAIN_FUNC{i}"] for i in range(1, 5)] == ["101", "102", "103", "104"]  # Motor 1 .. 4
    # drag sized for this aircraft: SIH's freefall speed 10 MASS / KDV (sih_params.yaml) is the cage's
    # quadratic-drag terminal speed, far above the 1 kg default's 2.4 m/s
    lo, hi = (np.asarray(c) for c in result.design.frame.bbox())
    area = (hi[0] - lo[0]) * (hi[1] - lo[1]) / 1e6
    v_t = math.sqrt(2 * s["SIH_MASS"] * G / (1.225 * 1.0 * area))
    assert s["SIH_MASS"] * G / s["SIH_KDV"] == pytest.approx(v_t, rel=1e-3) and v_t > 5
    assert float(a["SIH_KDV"]) == s["SIH_KDV"]
    # PX4 quad X: rotor 0 front right CCW (KM > 0), rotor 2 front left CW (KM < 0)
    assert float(a["CA_ROTOR0_PX"]) > 0 < float(a["CA_ROTOR0_PY"]) and float(a["CA_ROTOR0_KM"]) > 0
    assert float(a["CA_ROTOR2_PX"]) > 0 > float(a["CA_ROTOR2_PY"]) and float(a["CA_ROTOR2_KM"]) < 0


# -- the motor mix ----------------------------------------------------------------------------------

def _mmix(text: str) -> list[tuple[float, ...]]:
    return [tuple(float(x) for x in m) for m in re.findall(r"^mmix \d (\S+) (\S+) (\S+) (\S+)", text, re.M)]


@pytest.mark.parametrize("name", PRESETS)
def test_square_presets_mix_is_the_firmware_quad_x_table(flown, name):
    folder = flown[name][0]
    assert _mmix((folder / "inav.txt").read_text()) == [tuple(r) for r in QUAD_X]
    assert _mmix((folder / "betaflight.txt").read_text()) == [tuple(r) for r in QUAD_X]


def test_quad_x_table_is_inavs():
    """INAV's mixerQuadX (its custom-mix documentation lists the same four rows): rear right,
    front right, rear left, front left."""
    assert QUAD_X == ((1.0, -1.0, 1.0, -1.0), (1.0, -1.0, -1.0, 1.0), (1.0, 1.0, 1.0, 1.0), (1.0, 1.0, -1.0, -1.0))


def test_rectangular_frames_mix_follows_its_geometry(flown):
    """240 x 180: the roll factors are the motors' distances across over the longest arm, the
    pitch factors their distances fore and aft, from the frame's motor axes."""
    folder, result = flown["rect-240x180"]
    rows = _mmix((folder / "inav.txt").read_text())
    motors = {m.corner: np.asarray(m.axis) for m in result.design.frame.motors}
    centre = np.mean(list(motors.values()), axis=0)
    across = max(abs(p[0] - centre[0]) for p in motors.values())  # x: right
    along = max(abs(p[1] - centre[1]) for p in motors.values())  # y: front
    arm = max(across, along)
    assert across != pytest.approx(along, rel=0.05)  # the example is not square
    for row, corner in zip(rows, ("rr", "fr", "rl", "fl")):
        p = motors[corner] - centre
        assert row[1] == pytest.approx(-p[0] / arm, abs=1e-3)  # roll: right side negative
        assert row[2] == pytest.approx(-p[1] / arm, abs=1e-3)  # pitch: front negative
    assert {abs(r[1]) for r in rows} != {abs(r[2]) for r in rows}


@pytest.mark.fe
def test_props_out_reverses_every_spin(flown, tmp_path):
    text = _params("carbon").read_text().replace("  prop: \"3025\"", "  prop: \"3025\"\n  props_out: true")
    assert "props_out: true" in text
    d = api.from_text(text, "carbon-out.yaml")
    folder = d.fly(tmp_path / "out")
    rows = _mmix((folder / "inav.txt").read_text())
    assert [r[3] for r in rows] == [-r[3] for r in QUAD_X] and [r[:3] for r in rows] == [r[:3] for r in QUAD_X]
    rp = json.loads((folder / "rotorpy.json").read_text())
    base = json.loads((flown["carbon"][0] / "rotorpy.json").read_text())
    assert rp["rotor_directions"] == [-x for x in base["rotor_directions"]]
    # ArduCopter: props out is FRAME_TYPE 18 (BetaFlightXReversed), frame.json in its motor order;
    # FRAME_TYPE 1 with the reversed yaw signs would turn ArduCopter's yaw control around
    assert _parm(folder)["FRAME_TYPE"] == "18"
    assert _ardupilot_defects(folder, d.check().result) == []
    sdf = (folder / "gazebo" / "model.sdf").read_text()
    base_sdf = (flown["carbon"][0] / "gazebo" / "model.sdf").read_text()
    flip = {"cw": "ccw", "ccw": "cw"}
    spins = re.findall(r"<turningDirection>(\w+)</turningDirection>", sdf)
    assert spins == [flip[x] for x in re.findall(r"<turningDirection>(\w+)</turningDirection>", base_sdf)]
    km = dict(re.findall(r"^param set-default (CA_ROTOR\d_KM) (\S+)$", next((folder / "px4").glob("1*")).read_text(), re.M))
    base_km = dict(re.findall(r"^param set-default (CA_ROTOR\d_KM) (\S+)$", next((flown["carbon"][0] / "px4").glob("1*")).read_text(), re.M))
    assert {k: float(x) for k, x in km.items()} == {k: -float(x) for k, x in base_km.items()}


# -- resonance -------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", PRESETS)
def test_resonance_modes_are_checks_and_flags_follow_the_15_percent_rule(flown, name):
    folder, result = flown[name]
    res = json.loads((folder / "resonance.json").read_text())
    assert [m["hz"] for m in res["modes"]] == pytest.approx(result.stiffness["modes_hz"], abs=0.011)
    assert all(0.0 <= m["fc_participation"] <= 1.0 for m in res["modes"])
    flagged = set()
    for m in res["modes"]:
        for b in res["bands"]:
            if 0.85 * b["lo_hz"] <= m["hz"] <= 1.15 * b["hi_hz"]:
                flagged.add((m["mode"], b["name"]))
    assert {(f["mode"], f["band"]) for f in res["flags"]} == flagged
    rotor = next(b for b in res["bands"] if b["name"] == "rotor 1x")
    assert rotor["lo_hz"] == pytest.approx(result.stiffness["hover_rotor_hz"], abs=0.01)
    assert (folder / "resonance.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_check_warns_on_a_flagged_mode_and_does_not_fail(flown):
    folder, result = flown["carbon"]
    warns = [w for w in result.warnings if w.startswith("resonance:")]
    assert warns and result.verdict == "PASS" and not result.problems
    from cogniframe.analysis.verdict import check_dict

    f = check_dict(result)["flight"]
    assert len(f["cg_mm"]) == 3 and np.asarray(f["inertia_kg_m2"]).shape == (3, 3)
    assert {(x["mode"], x["band"]) for x in f["resonance_flags"]} == {
        (x["mode"], x["band"]) for x in json.loads((folder / "resonance.json").read_text())["flags"]}


@pytest.mark.fe
def test_flight_files_are_byte_identical_between_runs(flown, tmp_path):
    again = api.load(_params("carbon")).fly(tmp_path / "again")
    first = flown["carbon"][0]
    files = sorted(p.relative_to(first) for p in first.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(again) for p in again.rglob("*") if p.is_file())
    for rel in files:
        assert (first / rel).read_bytes() == (again / rel).read_bytes(), rel


@pytest.mark.fe
def test_fly_never_overwrites_a_folder_it_did_not_make(tmp_path, run_cli):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    code, _, err = run_cli("fly", str(_params("carbon")), "-o", str(out))
    assert code == 2 and (out / "notes.txt").read_text() == "keep me"


# -- the build's flight/ folder: the CAD solids ----------------------------------------------------

@pytest.fixture
def built_carbon(preset_build):
    return preset_build("carbon")


def test_build_writes_the_flight_folder_with_cad_inertia_within_3_percent_of_the_estimate(built_carbon, flown):
    """The build's mass properties come from the CAD solids (each part's STL carrying its budget
    mass); the part list's estimate (fly, check) agrees within 3 % on every principal moment, and
    the mass is the build's check.json all-up mass."""
    cad = json.loads((built_carbon / "flight" / "resonance.json").read_text())["mass"]
    est = json.loads((flown["carbon"][0] / "resonance.json").read_text())["mass"]
    assert cad["source"] == "cad" and est["source"] == "estimate"
    check = json.loads((built_carbon / "check.json").read_text())
    assert cad["mass_kg"] == pytest.approx(check["mass"]["total_g"] / 1000, abs=1e-5)  # check.json: 0.01 g
    assert np.diag(cad["inertia_kg_m2"]) == pytest.approx(np.diag(est["inertia_kg_m2"]), rel=0.03)
    assert cad["cg_mm"] == pytest.approx(est["cg_mm"], abs=1.0)
    for rel in ("inav.txt", "px4/sih.params", "gazebo/model.sdf", "rotorpy.json", "resonance.png"):
        assert (built_carbon / "flight" / rel).is_file(), rel
    html = (built_carbon / "report.html").read_text()
    assert 'href="flight/inav.txt"' in html and "Campbell diagram" in html


def test_rotor_positions_are_the_motors_places_in_assembly_glb(built_carbon):
    """Each rotor (rotorpy.json, FLU from the centre of gravity) sits on its motor's axis and its
    propeller's disc as assembly.glb draws them (glTF y up: world (x, y, z) is (x, z, -y))."""
    import trimesh

    rp = json.loads((built_carbon / "flight" / "rotorpy.json").read_text())
    cg = np.asarray(json.loads((built_carbon / "flight" / "resonance.json").read_text())["mass"]["cg_mm"]) / 1000
    scene = trimesh.load(built_carbon / "assembly.glb", force="scene")

    def world_bounds(node: str) -> np.ndarray:
        tf, geom = scene.graph[node]
        m = scene.geometry[geom].copy()
        m.apply_transform(tf)
        lo, hi = m.bounds  # glTF axes
        return np.array([[lo[0], -hi[2], lo[1]], [hi[0], -lo[2], hi[1]]]) / 1000.0  # world, m

    for key, corner in zip(("r1", "r2", "r3", "r4"), ("rr", "fr", "rl", "fl")):
        x_f, y_l, z = rp["rotor_pos"][key]
        hub = np.array([-y_l, x_f, z]) + cg  # FLU -> frame axes, from the origin
        motor = world_bounds(f"motor_{corner}").mean(axis=0)
        disc = world_bounds(f"propeller_{corner}").mean(axis=0)
        assert hub[:2] == pytest.approx(motor[:2], abs=1e-5)
        assert hub == pytest.approx(disc, abs=1e-5)


@pytest.mark.fe
def test_fly_without_a_thrust_table_is_exit_2_naming_motors_kv_and_writes_nothing(run_cli, tmp_path):
    p = tmp_path / "odd.yaml"
    p.write_text(_params("carbon").read_text().replace("  kv: 6000 ", "  kv: 5000 "))
    assert "kv: 5000" in p.read_text()
    out = tmp_path / "out"
    code, _, err = run_cli("fly", str(p), "-o", str(out))
    assert code == 2 and not out.exists()
    assert "odd.yaml: motors.kv (line" in err and "Fix:" in err and "Traceback" not in err


def test_docs_preset_tables_are_the_flight_files(flown):
    """docs/flight-files.md's mass, rotor and mode tables are what tools/flight_tables.py makes of
    the presets' flight files now (`python tools/flight_tables.py --write` renews them)."""
    import sys

    sys.path.insert(0, str(ROOT / "tools"))
    import flight_tables

    doc = (ROOT / "docs" / "flight-files.md").read_text()
    made = flight_tables.tables({n: flown[n][0] for n in PRESETS})
    for key, (begin, end) in flight_tables.MARKS.items():
        assert doc.split(begin, 1)[1].split(end, 1)[0].strip() == made[key], key
    assert f"{flown['carbon'][1].mass.total_g:.2f}" in made["mass"]  # check's all-up mass, to the hundredth of a gram

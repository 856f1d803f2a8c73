"""Rectangular boxes (width != depth) are first-class: examples/rect-240x180.yaml and a near-square 212 x 210.

Before: any box that was not square exited 3 ("stiffness model: no rod of corner_bottom_fr matches a
socket of its part"): partlist turned the fl joint to every corner, which only fits sockets
symmetric about the corner's 45 deg diagonal. Now a corner that is not the fl corner turned gets a
`<kind>_mirrored` part (fr, rl), each knee sits in the vertical plane through its corner and its
core link, the arm pair is offset across the arm's own plan direction, and the motor mount turns to
each arm's direction.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.families.base import CORNER_ROTATION

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "rect-240x180.yaml"
JOINT_KINDS = ("corner_top", "corner_bottom", "knee", "core_link")


def _variant(base: str, **frame) -> spec_mod.Spec:
    data = yaml.safe_load((ROOT / "params" / f"{base}.yaml").read_text(encoding="utf-8"))
    data["frame"].update(frame)
    data["name"] = f"{base}-variant"
    return spec_mod.from_dict(data)


@pytest.fixture(scope="module")
def rect():
    return design_mod.design(spec_mod.load(EXAMPLE))


@pytest.fixture(scope="module", params=["rect-240x180", "212x210", "180x240", "carbon", "bamboo"])
def any_box(request):
    """The example, near-square and portrait rectangles, and the square presets."""
    if request.param == "rect-240x180":
        return design_mod.design(spec_mod.load(EXAMPLE))
    if request.param == "212x210":
        return design_mod.design(_variant("carbon", width=212))
    if request.param == "180x240":
        return design_mod.design(_variant("carbon", width=180, depth=240))
    return design_mod.design(spec_mod.load(ROOT / "params" / f"{request.param}.yaml"))


def _rz(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])


# -- the example -----------------------------------------------------------------------------

def test_example_is_a_full_commented_params_file_like_the_presets():
    text = EXAMPLE.read_text(encoding="utf-8")
    data = yaml.safe_load(text)
    carbon = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text(encoding="utf-8"))
    assert data["name"] == "rect-240x180"
    assert (data["frame"]["width"], data["frame"]["depth"], data["frame"]["height"]) == (240, 180, 120)
    assert set(data) == set(carbon) and all(set(data[k]) == set(carbon[k]) for k in carbon if isinstance(carbon[k], dict))
    assert text.startswith("# yaml-language-server: $schema=../cogniframe/data/params.schema.json")


@pytest.mark.fe
def test_check_of_the_example_exits_0_or_1_with_finite_mass_and_stiffness(run_cli):
    """The solid FE of every joint (the mirrored ones by reflection), then the frame model: this is
    where the rectangle used to exit 3."""
    code, out, err = run_cli("check", EXAMPLE, "--json")
    assert code in (0, 1), err
    d = json.loads(out)
    assert d["name"] == "rect-240x180"
    assert math.isfinite(d["mass"]["total_g"]) and 150 < d["mass"]["total_g"] < 300
    k = d["stiffness"]["k_n_per_m"]
    assert math.isfinite(k) and k > 1000
    assert all(math.isfinite(f) and f > 0 for f in d["stiffness"]["modes_hz"])
    assert all(j["method"] == "fe" for j in d["stiffness"]["joints"].values()), d["stiffness"]["joints"]
    assert {p["name"]: p["qty"] for p in d["parts"]} == {
        "corner_top": 2, "corner_top_mirrored": 2, "corner_bottom": 2, "corner_bottom_mirrored": 2, "knee": 2,
        "knee_mirrored": 2, "core_link": 2, "core_link_mirrored": 2, "motor_mount": 4, "core_plate": 1,
        "battery_holder": 1, "sensor_mount": 1, "front_camera_mount": 1, "computer_mount": 1}
    items = {i["name"]: i for i in d["mass"]["items"]}
    assert items["knee_mirrored"]["qty"] == 2 and items["knee_mirrored"]["mass_g"] == items["knee"]["mass_g"]


def test_near_square_box_checks_and_matches_the_square(run_cli, tmp_path):
    """The reported case: carbon with frame.width 212 (depth 210) exited 3. Its numbers now lie next to
    the square's (closed-form joints: milliseconds; the FE is the example's test above)."""
    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text(encoding="utf-8"))
    data["model"]["stiffness_model"] = "analytic"
    data["core"]["link"] = "tab"  # the closed forms' link
    ks = {}
    for width in (210, 212):
        data["frame"]["width"] = width
        data["name"] = f"w{width}"
        path = tmp_path / f"w{width}.yaml"
        path.write_text(yaml.safe_dump(data), encoding="utf-8")
        code, out, err = run_cli("check", path, "--json")
        assert code in (0, 1), err
        ks[width] = json.loads(out)["stiffness"]
    assert ks[212]["k_n_per_m"] == pytest.approx(ks[210]["k_n_per_m"], rel=0.03)
    assert ks[212]["k_lateral_n_per_m"] == pytest.approx(ks[210]["k_lateral_n_per_m"], rel=0.05)
    assert ks[212]["strain"]["hinge"] == pytest.approx(ks[210]["strain"]["hinge"], rel=0.05)  # the mirrored knees are hinged too


# -- cut list --------------------------------------------------------------------------------

def test_cut_list_has_the_rectangles_rod_lengths(rect):
    spec, frame = rect.spec, rect.frame
    length = {n: r.cut_length for n, r in frame.rods.items()}
    cut = {n: row.length_mm for row in rect.cut.rows for n in row.rods}
    assert cut == length
    for level in ("top", "bottom"):
        front, rear = cut[f"rod_cage_{level}_front"], cut[f"rod_cage_{level}_rear"]
        left, right = cut[f"rod_cage_{level}_left"], cut[f"rod_cage_{level}_right"]
        assert front == rear and left == right
        # the same joints and seats at both ends: the difference is the box's
        assert front - left == spec.frame.width - spec.frame.depth == 60
    # every corner is the same shape (mirrored or turned): its legs, arms and struts are equal
    for role in ("arm", "strut"):
        assert len({cut[r.name] for r in frame.rods_of(role)}) == 1, role
    for leg in ("upper", "lower"):
        assert len({cut[f"rod_leg_{leg}_{k}"] for k in ("fl", "fr", "rr", "rl")}) == 1
    rows = [(r.role, r.length_mm, r.qty) for r in rect.cut.rows]
    assert ("cage", 229.0, 2) in rows and ("cage", 169.0, 2) in rows and sum(q for _, _, q in rows) == 28


# -- every socket where its rod is -----------------------------------------------------------

def test_every_joint_socket_placed_coincides_with_its_rod_end(any_box):
    """Each part's sockets, turned and moved by each of its placements, land on the frame graph's rod
    ends at that node (port and direction, seat and depth): all four corners, every kind."""
    frame = any_box.frame
    seen = set()
    for p in any_box.parts:
        if p.family != "joint":
            continue
        for pl in p.placements:
            node = frame.nodes[pl.instance]
            R = _rz(pl.rotation_deg)
            assert np.allclose(pl.origin, node.pos, atol=1e-6)
            placed = {}
            for s in p.sockets:
                port = R @ np.asarray(s.port) + np.asarray(pl.origin)
                direction = R @ np.asarray(s.direction)
                match = [rn for rn in node.rods
                         if np.linalg.norm(port - np.asarray(frame.rods[rn].end_at(node.name).port)) < 1e-5
                         and np.linalg.norm(direction - frame.rods[rn].socket_direction(node.name)) < 1e-5]
                assert len(match) == 1, (p.name, pl.instance, s.rod)
                end = frame.rods[match[0]].end_at(node.name)
                assert (s.seat, s.depth) == (end.seat, end.depth)
                placed[match[0]] = s
            assert set(placed) == set(node.rods), (p.name, pl.instance)
            seen.add(pl.instance)
    assert seen == {f"{k}_{c}" for k in JOINT_KINDS for c in ("fl", "fr", "rr", "rl")}


def test_every_motor_mount_clips_its_own_arm_rods(any_box):
    from cogniframe.families.motor_mount import mount_rods

    frame = any_box.frame
    mount = next(p for p in any_box.parts if p.family == "motor_mount")
    motors = {m.name: m for m in frame.motors}
    assert sorted(pl.instance for pl in mount.placements) == sorted(motors)
    local = [(np.asarray(p), np.asarray(d)) for p, d in mount.param("arm_rods")]
    for pl in mount.placements:
        m = motors[pl.instance]
        assert np.allclose(pl.origin, m.axis, atol=1e-6)
        R = _rz(pl.rotation_deg)
        placed = [(R @ p, R @ d) for p, d in local]
        for p, d in mount_rods(frame, m):
            assert min(np.linalg.norm(q - p) + np.linalg.norm(e - d) for q, e in placed) < 1e-5, pl.instance
        assert math.hypot(*m.axis[:2]) == pytest.approx(any_box.spec.motors.radius, abs=1e-6)


def test_square_boxes_keep_one_part_per_kind_turned_to_each_corner(preset):
    parts = {p.name: p for p in design_mod.design(preset).parts}
    assert not any(n.endswith("_mirrored") and n != "core_link_mirrored" for n in parts)
    for kind in ("corner_top", "corner_bottom", "knee"):
        assert [pl.rotation_deg for pl in parts[kind].placements] == [CORNER_ROTATION[k] for k in ("fl", "fr", "rr", "rl")]
    assert [pl.rotation_deg for pl in parts["motor_mount"].placements] == [0.0, -90.0, -180.0, 90.0]


def test_rectangle_mirrored_parts_are_exact_mirror_images(rect):
    """The fr/rl parts are the fl/rr ones reflected (x -> -x): the joint FE reflects their
    super-element instead of meshing them again, and the CAD prints their mirror image."""
    from cogniframe.analysis.joints import mirror_original

    parts = {p.name: p for p in rect.parts}
    for kind in JOINT_KINDS:
        mirror = parts[f"{kind}_mirrored"]
        assert dict(mirror.params)["kind"] == kind and dict(mirror.params)["mirror"] is True
        assert [pl.instance for pl in mirror.placements] == [f"{kind}_fr", f"{kind}_rl"]
        assert [pl.instance for pl in parts[kind].placements] == [f"{kind}_fl", f"{kind}_rr"]
        original, P, _ = mirror_original(mirror, rect.parts)
        assert original.name == kind
        assert np.array_equal(P, np.diag([-1.0, 1.0, 1.0]))


def test_rectangle_corner_folds_stay_in_one_vertical_plane(rect):
    """Corner, knee, core link and strut of each corner in one vertical plane, the arm pair offset
    horizontally across it: every knee and core link prints flat like a square box's."""
    frame = rect.frame
    for k in ("fl", "fr", "rr", "rl"):
        c = np.asarray(frame.nodes[f"corner_bottom_{k}"].pos)[:2]
        link = np.asarray(frame.nodes[f"core_link_{k}"].pos)[:2]
        knee = np.asarray(frame.nodes[f"knee_{k}"].pos)[:2]
        u = (link - c) / np.linalg.norm(link - c)
        assert abs(u[0] * (knee - c)[1] - u[1] * (knee - c)[0]) < 1e-9
        assert np.linalg.norm(knee - c) == pytest.approx(rect.spec.frame.knee_inset * math.sqrt(2))
        a1, a2 = frame.rods[f"rod_arm_{k}_1"], frame.rods[f"rod_arm_{k}_2"]
        off = np.asarray(a1.a.port) - np.asarray(a2.a.port)
        assert off[2] == 0 and np.linalg.norm(off) == pytest.approx(rect.spec.frame.arm_spacing)
        assert abs(off @ a1.axis) < 1e-9  # across the arm


def test_assembly_steps_name_the_mirrored_parts(rect):
    from cogniframe.report.assembly_steps import assembly_steps

    steps = assembly_steps(rect)
    used = [label for s in steps for label in s.parts]
    assert len(used) == len(set(used))
    for kind in ("corner_top", "corner_bottom", "knee"):
        step = next(s for s in steps if f"{kind}_fl" in s.parts)
        assert f"{kind}_mirrored_fr" in step.parts and f"{kind}_mirrored_rl" in step.parts
        assert f"{kind}_mirrored at front-right and rear-left" in step.text
    assert "rectangular ring" in steps[0].text


# -- one real build ----------------------------------------------------------------------------

@pytest.mark.cad
@pytest.mark.slicer
@pytest.mark.fe
def test_build_of_the_example_is_watertight_and_clash_checked(tmp_path):
    import trimesh

    from cogniframe.pipeline import run_build

    out = tmp_path / "rect"
    result = run_build(spec_mod.load(EXAMPLE), EXAMPLE, out, jobs=2)
    stls = sorted(out.glob("stl/*/*.stl"))
    names = {p.stem for p in stls}
    assert {"knee", "knee_mirrored", "corner_top_mirrored", "corner_bottom_mirrored", "core_link_mirrored"} <= names
    for p in stls:
        mesh = trimesh.load(p, force="mesh")
        assert mesh.is_watertight and mesh.volume > 0, p.name
    clash = json.loads((out / "clash.json").read_text())
    assert clash is not None and (out / "clash.json").stat().st_size > 0
    check = json.loads((out / "check.json").read_text())
    assert result.check.verdict == check["verdict"] and not [c for c in check["problems"] if "clash" in c]
    bom = (out / "bom.md").read_text()
    assert "knee_mirrored" in bom and "corner_bottom_mirrored" in bom


def test_the_wall_case_is_the_worst_of_the_four_side_faces():
    """A rectangle's long and short sides meet a wall differently: every face is tried and the
    one allowing the lowest speed is reported, with its name."""
    from cogniframe import design as design_mod
    from cogniframe import spec as spec_mod
    from cogniframe.analysis import load_cases as lc
    from cogniframe.analysis import stiffness as st

    spec = spec_mod.load(Path(__file__).resolve().parents[1] / "examples" / "rect-240x180.yaml")
    data = spec.model_dump(mode="json")
    data["model"]["stiffness_model"] = "analytic"
    data["core"]["link"] = "tab"  # the closed forms' link
    spec = spec_mod.from_dict(data)
    d = design_mod.design(spec)
    joints = st.joint_models(spec, d.parts, "analytic")
    masses = st.masses_g(spec, d.frame, d.parts, 245.0)
    mdl = st.build_model(spec, d.frame, d.parts, joints, masses=masses)
    K = mdl.fe.stiffness(sparse=True)
    faces = [lc._wall_face(spec, d.frame, mdl, K, masses, 0.558, a, s) for a, s in lc.WALL_FACES]
    worst = lc._wall_case(spec, d.frame, mdl, K, masses, 0.558)
    assert worst["max_wall_speed_m_s"] == min(f["max_wall_speed_m_s"] for f in faces)
    assert {f["face"] for f in faces} == {"+x (right)", "-x (left)", "+y (front)", "-y (rear)"}
    long_side = next(f for f in faces if f["face"] == "+x (right)")
    short_side = next(f for f in faces if f["face"] == "+y (front)")
    assert long_side["k_lateral_n_per_m"] != pytest.approx(short_side["k_lateral_n_per_m"], rel=0.01)

"""The joint surrogate (`model.stiffness_model: surrogate`) against the solid FE it was fitted to:
on held-out joints (tests/data/joint_surrogate_holdout.json, made by tools/train_joint_surrogate.py
from designs the fit never saw) and on live FE solves; its training box, fallback and notes."""

from __future__ import annotations

import json
import statistics
from pathlib import Path

import numpy as np
import pytest
import yaml

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from cogniframe.analysis import stiffness
from cogniframe.analysis.joints import fe_joint, is_mirror, mirror_original, reflect_unit, surrogate_models
from cogniframe.analysis.joints import surrogate as sg
from cogniframe.analysis.joints.model import TPU_PRINTED_MODULUS_FACTOR, JointStiffness
from cogniframe.sweep.evaluate import apply_overrides

ROOT = Path(__file__).resolve().parents[1]
HOLDOUT = json.loads((ROOT / "tests" / "data" / "joint_surrogate_holdout.json").read_text())


def design(overrides: dict, **extra):
    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    s = spec_mod.from_dict(apply_overrides(data, {**overrides, **extra}))
    f = frame_mod.frame_of(s)
    return s, f, partlist.part_list(s, f)


def joints_of(parts):
    return [p for p in parts if p.family == "joint"]


def unpack(c: dict) -> np.ndarray:
    n = len(c["labels"]) * 6
    K = np.zeros((n, n))
    K[np.triu_indices(n)] = c["triu"]
    return K + np.triu(K, 1).T


def rel_error(k_pred: np.ndarray, k_fe: np.ndarray) -> float:
    """Relative Frobenius error of a super-element, rotations scaled by surrogate.LENGTH_MM (so that
    forces and moments weigh alike), as docs/stiffness-model.md states the accuracy."""
    s = np.tile([1.0, 1.0, 1.0, sg.LENGTH_MM, sg.LENGTH_MM, sg.LENGTH_MM], k_fe.shape[0] // 6)
    a, b = k_pred / np.outer(s, s), k_fe / np.outer(s, s)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def frame_k(s, f, parts, units: dict) -> float:
    """Secant k with the factor-1 `units` of the original joints (mirrors reflected from them)."""
    joints = {}
    for p in joints_of(parts):
        if is_mirror(p):
            o, P, order = mirror_original(p, parts)
            u = reflect_unit(units[o.name], p, P, order, [x.rod for x in o.sockets])
        else:
            u = units[p.name]
        joints[p.name] = JointStiffness(u.name, u.method, u.labels, u.refs,
                                        tuple(map(tuple, (TPU_PRINTED_MODULUS_FACTOR * u.matrix).tolist())))
    return stiffness.secant_solution(s, f, parts, joints).k_n_per_m


@pytest.fixture(scope="module")
def held_out():
    """Per held-out design: its parts, the FE units and the surrogate's (both at factor 1)."""
    out = []
    # the core link they were trained on (the tab before the held-out file recorded it), whatever the preset's is now
    link = HOLDOUT["meta"].get("core_link", "tab")
    for d in HOLDOUT["designs"]:
        s, f, parts = design(d["overrides"], **{"core.link": link})
        fe = {}
        sur = {}
        for p in joints_of(parts):
            if is_mirror(p):
                continue
            c = d["joints"][p.name]
            fe[p.name] = JointStiffness(p.name, "fe", tuple(c["labels"]), tuple(map(tuple, c["refs"])),
                                        tuple(map(tuple, unpack(c).tolist())))
            sur[p.name], _ = sg.predict(s, p, 1.0)
        out.append((d, s, f, parts, fe, sur))
    return out


def test_holdout_set_is_of_designs_the_fit_never_saw():
    meta = HOLDOUT["meta"]
    assert meta["data_sha256"] == sg.DATA_SHA256  # made with the shipped fit
    assert len(HOLDOUT["designs"]) >= 12
    trained = json.loads(sg.DATA_FILE.read_text())["meta"]
    assert trained["train_designs"] >= 96
    # frame k is the held-out figure the calibration moves: its stored values are at today's factor
    # (after a new calibration: tools/train_joint_surrogate.py --refresh-k)
    assert meta["tpu_factor"] == TPU_PRINTED_MODULUS_FACTOR


# The corners are fitted to the joint level. The knee's living hinge and the flat link's bands make
# their super-elements far from a smooth function of the geometry (held out: knee median 10 %, worst
# 39 %; core link 3 %, 34 %, docs/stiffness-model.md), so they are judged where the sweep reads them:
# the frame's k and the bare arm's hinge below.
JOINT_LEVEL = ("corner_top", "corner_bottom")


def test_per_joint_stiffness_within_3_percent_median_5_worst_of_the_fe_on_held_out_joints(held_out):
    errors = {}
    outside = 0
    for d, s, f, parts, fe, sur in held_out:
        for name, unit in fe.items():
            if name not in JOINT_LEVEL:
                continue
            if sur[name] is None:  # outside the training box: `check` solves it by FE
                outside += 1
                continue
            errors[(d["design"], name)] = rel_error(sur[name].matrix, unit.matrix)
    assert outside <= 0.1 * (outside + len(errors))  # the held-out designs come from the training's box
    v = list(errors.values())
    worst = max(errors, key=errors.get)
    assert statistics.median(v) <= 0.03, statistics.median(v)
    assert max(v) <= 0.05, (worst, errors[worst])


def test_bare_arm_hinge_in_the_core_link_within_3_percent_median_6_worst_of_the_fe(held_out):
    """What the bare arms hang on under thrust (`arms_only_core_link_hinge_n_mm_per_rad`) is the core
    link's super-element condensed: the sweep's figure that depends on the link alone."""
    from cogniframe.analysis.load_cases import arm_pair_hinge

    errs = []
    for d, s, f, parts, fe, sur in held_out:
        if sur["core_link"] is None:  # outside the training box: solved by FE
            continue
        errs.append(arm_pair_hinge({"core_link": sur["core_link"]}, parts) / arm_pair_hinge(fe, parts) - 1)
    assert len(errs) >= 12
    assert statistics.median(np.abs(errs)) <= 0.03, errs
    assert max(np.abs(errs)) <= 0.06, errs


def test_frame_k_within_3_percent_median_5_worst_of_the_fe_on_held_out_designs(held_out):
    errs = []
    for d, s, f, parts, fe, sur in held_out:
        k_fe = frame_k(s, f, parts, fe)
        assert k_fe == pytest.approx(d["k_fe"], rel=1e-4)  # the stored FE matrices give the stored k
        # a joint outside the training box is solved by FE, as `check` does
        errs.append(frame_k(s, f, parts, {n: sur[n] or fe[n] for n in fe}) / k_fe - 1)
    assert statistics.median(np.abs(errs)) <= 0.03, errs
    assert max(np.abs(errs)) <= 0.05, errs


# A family trained on its own (`tools/train_joint_surrogate.py --family`, e.g. the pegged core link
# on the pegged carbon preset) has its own held-out section: its joints' FE on designs the fit never
# saw, and the frame k with the family's joints from the FE against the fit's, the other joints
# from the surrogate in both (they are not solved by such a run). It is held to the same bounds.
SECTIONS = HOLDOUT.get("families", {})


def section_joints(family: str) -> list:
    """Per held-out joint of a family trained alone: its record, design, part, FE unit and the
    surrogate's (None outside the box), all at factor 1."""
    sec = SECTIONS[family]
    out = []
    for j in sec["joints"]:
        s, f, parts = design(j["overrides"], **{"core.link": sec["meta"]["core_link"]})
        p = next(p for p in joints_of(parts) if p.name == j["part"])
        c = j["fe"]
        fe = JointStiffness(p.name, "fe", tuple(c["labels"]), tuple(map(tuple, c["refs"])),
                            tuple(map(tuple, unpack(c).tolist())))
        out.append((j, s, f, parts, p, fe, sg.predict(s, p, 1.0)[0]))
    return out


@pytest.mark.parametrize("family", sorted(SECTIONS))
def test_a_family_trained_alone_is_within_the_same_bounds_on_its_own_held_out_designs(family):
    sec = SECTIONS[family]
    trained = json.loads(sg.DATA_FILE.read_text())["meta"]["families"][family]
    keys = ("base", "box", "core_link", "seed", "train_designs")
    assert {k: sec["meta"][k] for k in keys} == {k: trained[k] for k in keys}  # the shipped fit's held-out set
    assert trained["train_designs"] >= 96 and sec["meta"]["holdout_designs"] >= 12
    rows = section_joints(family)
    assert rows and all(sg.family_of(r[4]) == family for r in rows)
    inside = [r for r in rows if r[6] is not None]
    assert len(rows) - len(inside) <= 0.1 * len(rows)
    for j, s, f, parts, p, fe, sur in inside:  # the stored errors are the shipped fit's
        assert rel_error(sur.matrix, fe.matrix) == pytest.approx(j["frobenius"], rel=1e-3, abs=1e-6)
    if family in JOINT_LEVEL:
        v = [rel_error(r[6].matrix, r[5].matrix) for r in inside]
        assert statistics.median(v) <= 0.03 and max(v) <= 0.05, v
    if sg.family_of(rows[0][4]).startswith("core_link"):
        from cogniframe.analysis.load_cases import arm_pair_hinge

        errs = [arm_pair_hinge({p.name: sur}, parts) / arm_pair_hinge({p.name: fe}, parts) - 1
                for j, s, f, parts, p, fe, sur in inside]
        assert len(errs) >= 12
        assert statistics.median(np.abs(errs)) <= 0.03, errs
        assert max(np.abs(errs)) <= 0.06, errs
    errs = []
    for fr in sec["designs"]:
        mine = [r for r in rows if r[0]["design"] == fr["design"]]
        s, f, parts = mine[0][1:4]
        sur = {p.name: sg.predict(s, p, 1.0)[0] for p in joints_of(parts) if not is_mirror(p)}
        k_fe = frame_k(s, f, parts, {**sur, **{r[4].name: r[5] for r in mine}})
        assert k_fe == pytest.approx(fr["k_family_fe"], rel=1e-4)
        errs.append(frame_k(s, f, parts, {n: u or next(r[5] for r in mine if r[4].name == n) for n, u in sur.items()}) / k_fe - 1)
    assert len(errs) >= 0.9 * sec["meta"]["holdout_designs"]  # left out only where another joint needs the FE
    assert statistics.median(np.abs(errs)) <= 0.03, errs
    assert max(np.abs(errs)) <= 0.05, errs


def test_surrogate_joint_has_exactly_the_six_rigid_modes_and_is_positive_semidefinite():
    s, f, parts = design({"joints.wall": 1.7, "rods.diameter": 3.3})
    units = surrogate_models(s, joints_of(parts))
    assert {n for n, u in units.items() if u.method == "surrogate"} == {"corner_top", "corner_bottom", "knee", "core_link",
                                                                         "core_link_mirrored"}
    for unit in units.values():
        K = unit.matrix
        w = np.linalg.eigvalsh(K)
        assert (w[:6] / w[-1] < 1e-12).all() and w[6] / w[-1] > 1e-9 and w.min() > -1e-9 * w[-1]
        from cogniframe.analysis.framefe import rigid_transfer

        R = np.vstack([rigid_transfer(np.zeros(3), np.asarray(r)) for r in unit.refs])
        assert np.linalg.norm(K @ R) <= 1e-9 * np.linalg.norm(K)


def test_surrogate_scales_with_the_tpu_factor_and_repeats_to_the_bit():
    s, f, parts = design({"joints.wall": 1.7})
    p = next(p for p in joints_of(parts) if p.name == "corner_top")
    a, _ = sg.predict(s, p, 1.0)
    b, _ = sg.predict(s, p, 0.5)
    np.testing.assert_allclose(b.matrix, 0.5 * a.matrix, rtol=1e-12)
    assert sg.predict(s, p, 1.0)[0].K == a.K


@pytest.mark.cad
def test_live_fe_of_an_unseen_corner_agrees_with_the_surrogate():
    # rods, wall, depth and clearance between the presets': a geometry in no training or held-out design
    s, f, parts = design({"rods.diameter": 3.25, "joints.wall": 1.55, "joints.socket_depth": 10.5,
                          "joints.fit_clearance.tpu_95a": 0.07, "frame.height": 126.0})
    p = next(p for p in joints_of(parts) if p.name == "corner_top")
    fe = fe_joint(s, p, 1.0)
    sur, why = sg.predict(s, p, 1.0)
    assert why is None
    assert rel_error(sur.matrix, fe.matrix) <= 0.05


@pytest.mark.fe
def test_carbon_preset_k_from_the_surrogate_within_5_percent_of_the_fe(carbon):
    s = carbon
    f = frame_mod.frame_of(s)
    parts = partlist.part_list(s, f)
    k_fe = stiffness.secant_solution(s, f, parts, stiffness.joint_models(s, parts, "fe")).k_n_per_m
    k_sur = stiffness.secant_solution(s, f, parts, stiffness.joint_models(s, parts, "surrogate")).k_n_per_m
    # the surrogate's documented worst on held-out frames (the preset's -0.30 fit is the box's lower wall)
    assert k_sur == pytest.approx(k_fe, rel=0.05)


@pytest.mark.fe
def test_a_joint_outside_the_box_is_named_solved_by_fe_and_only_noted():
    # a 2.5 mm wall: thicker than any trained joint, so every joint that reads joints.wall leaves the
    # box (the pegged core link's columns have the connector's own wall: it stays in, its mirror with it)
    over = {"joints.wall": 2.5}
    s, f, parts = design(over)
    notes = sg.outside_reasons(s, joints_of(parts))
    assert set(notes) == {"corner_top", "corner_bottom", "knee"} and "wall" in notes["corner_top"]
    models = surrogate_models(s, joints_of(parts))
    links = {"core_link", "core_link_mirrored"}
    assert {n: m.method for n, m in models.items()} == {p.name: "surrogate" if p.name in links else "fe"
                                                        for p in joints_of(parts)}
    from cogniframe.analysis import verdict

    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    sp = spec_mod.from_dict(apply_overrides(data, {**over, "model.stiffness_model": "surrogate"}))
    d = verdict.check_dict(verdict.check(sp))
    said = {n: f"joint {n}: outside the surrogate's training box (" + notes[n] + "); its stiffness is from the solid FE"
            for n in notes}
    assert [n for n in d["notes"] if n.startswith("joint ")] == [said[p.name] for p in joints_of(parts) if p.name in said]
    assert not any("surrogate" in p for p in d["problems"])
    assert d["stiffness"]["joints"]["corner_top"]["method"] == "fe"


def test_a_changed_data_file_is_refused(tmp_path, monkeypatch):
    bad = tmp_path / "joint_surrogate.json"
    bad.write_bytes(sg.DATA_FILE.read_bytes() + b" ")
    monkeypatch.setattr(sg, "DATA_FILE", bad)
    with pytest.raises(RuntimeError, match="not the joint surrogate"):
        sg.families()


def test_fit_is_deterministic_and_recovers_a_log_linear_family():
    rng = np.random.default_rng(3)
    X = rng.uniform(0, 1, (40, 3))
    Y = np.column_stack([1 + 2 * X[:, 0] - X[:, 2], 0.5 * X[:, 1], np.full(40, 0.3)])
    a, _ = sg.fit_family("k", ("r0", "body"), ("a", "b", "c"), X, Y)
    b, _ = sg.fit_family("k", ("r0", "body"), ("a", "b", "c"), X, Y)
    assert json.dumps(a.to_json()) == json.dumps(b.to_json())
    x = np.array([[0.3, 0.6, 0.2]])
    np.testing.assert_allclose(a.basis(x) @ np.asarray(a.coef), [[1 + 0.6 - 0.2, 0.3, 0.3]], atol=1e-3)


def test_fit_with_fewer_than_two_samples_a_term_is_refused():
    rng = np.random.default_rng(3)
    X = rng.uniform(0, 1, (5, 3))  # 3 components: the intercept and the linear terms need 8 samples
    Y = X @ [[1.0], [2.0], [3.0]]
    with pytest.raises(ValueError, match="k: 5 samples are too few to fit its 3 principal components"):
        sg.fit_family("k", ("r0", "body"), ("a", "b", "c"), X, Y)
    fam, _ = sg.fit_family("k", ("r0", "body"), ("a", "b", "c"), np.vstack([X, rng.uniform(0, 1, (3, 3))]),
                           np.vstack([Y, np.zeros((3, 1))]))
    assert fam.n_train == 8 and fam.quadratic == 0


@pytest.mark.fe
def test_sweep_row_k_equals_checks_fe_k_within_5_percent():
    """A sweep's row (surrogate joints, the sweeps' default) against `check` of the same params
    with `model.stiffness_model: fe`: bamboo rods, geometry no training design has."""
    from cogniframe.analysis import verdict
    from cogniframe.sweep import evaluate as ev

    base = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    over = {"rods.material": "bamboo", "rods.diameter": 3.4, "joints.wall": 1.8, "joints.socket_depth": 11.0,
            "frame.height": 131.0}
    row = ev.evaluate_one(base, {**over, "model.stiffness_model": "surrogate"}, 120)
    assert row["joints_outside_box"] == "" and row["stiffness.joints.corner_top.method"] == "surrogate"
    fe = verdict.check_dict(verdict.check(spec_mod.from_dict(apply_overrides(base, over))))
    assert fe["stiffness"]["joint_model"] == "fe"
    assert row["k_n_per_m"] == pytest.approx(fe["drop"]["k_n_per_m"], rel=0.05)
    assert row["max_safe_drop_cm"] == pytest.approx(fe["drop"]["max_safe_height_cm"], rel=0.05)
    assert row["verdict"] == fe["verdict"]


@pytest.mark.process
def test_a_joint_outside_the_box_is_solved_on_worker_processes_and_announced(tmp_path):
    """With the surrogate, `Design.needs_fe` says a check will solve a joint's FE (the studio then
    shows the fast figures first) exactly when a joint is outside the box and not cached; `check`
    solves it on worker processes, so the checking process never imports the CAD kernel."""
    import os
    import subprocess
    import sys

    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    inside = apply_overrides(data, {"model.stiffness_model": "surrogate"})
    outside = apply_overrides(data, {"joints.wall": 2.5, "model.stiffness_model": "surrogate"})
    for name, doc in (("inside", inside), ("outside", outside)):
        doc["name"] = name
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    code = ("import sys; from cogniframe import api; d = api.load(sys.argv[1]); before = d.needs_fe(); "
            "r = d.check(); print(before, d.needs_fe(), r.to_dict()['stiffness']['joints']['corner_top']['method'], "
            "'cadquery' in sys.modules)")
    env = {**os.environ, "COGNIFRAME_CACHE": str(tmp_path / "cache")}

    def run(name):
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path / f"{name}.yaml")], capture_output=True,
                             text=True, cwd=ROOT, env=env, check=True)
        return out.stdout.split()

    assert run("inside") == ["False", "False", "surrogate", "False"]
    assert run("outside") == ["True", "False", "fe", "False"]  # solved once, on the workers; cached after

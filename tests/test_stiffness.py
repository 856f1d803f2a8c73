"""Stiffness FE model: PyNite against closed forms, the paper's k, physical trends, symmetry."""

from __future__ import annotations

import copy
import math
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from cogniframe import frame as frame_mod
from cogniframe import spec as spec_mod
from cogniframe.analysis import stiffness as st

ROOT = Path(__file__).resolve().parents[1]
CARBON = ROOT / "params" / "carbon.yaml"


def _carbon_data() -> dict:
    """The carbon preset as a mapping (the default spec until params/carbon.yaml exists)."""
    return yaml.safe_load(CARBON.read_text(encoding="utf-8")) if CARBON.is_file() else {}


def _carbon() -> spec_mod.Spec:
    return spec_mod.load(CARBON) if CARBON.is_file() else spec_mod.from_dict({})


def _variant(**sections) -> spec_mod.Spec:
    """The carbon preset with some sections' keys replaced (a shallow merge per section)."""
    data = copy.deepcopy(_carbon_data())
    for section, values in sections.items():
        if isinstance(values, dict):
            data.setdefault(section, {})
            data[section] = {**(data[section] or {}), **values}
        else:
            data[section] = values
    return spec_mod.from_dict(data)


def _k(spec, **kw) -> float:
    return st.predict_stiffness(spec, frame_mod.build(spec), **kw).k_n_per_m


@pytest.fixture(scope="module")
def carbon_result():
    s = _carbon()
    return st.predict_stiffness(s, frame_mod.build(s))


# -- PyNite against closed forms -----------------------------------------------------------

@pytest.mark.parametrize("length, d, e, g", [
    (100.0, 3.0, 125_000.0, 5_000.0),  # a carbon arm
    (50.0, 3.0, 15_000.0, 1_000.0),  # a bamboo leg
    (10.0, 6.3, 26.0, 8.8),  # a TPU stub
])
def test_cantilever_matches_3EI_over_L3(length, d, e, g):
    closed = 3 * e * (math.pi * d**4 / 64) / length**3
    fe = st.cantilever_stiffness(length, d, e, g)
    assert fe == pytest.approx(closed, rel=0.01)


def _l_frame(h, a, d, e, g, *, planar: bool) -> float:
    """Tip deflection (mm) of an L-shaped two-bar frame under a unit tip load, from PyNite.

    planar: a column of height h clamped at its foot, an arm of length a from its top, load down
    at the arm's tip (arm bending + column bending + column compression).
    not planar: both bars horizontal at right angles, clamped at one end, load down at the other
    (arm bending + clamped bar bending + clamped bar torsion).
    """
    from Pynite import FEModel3D

    m = FEModel3D()
    m.add_material("m", e, g, 0.3, 1e-9)
    m.add_section("s", *st.circle_section(d))
    if planar:
        pts = {"A": (0, 0, 0), "B": (0, 0, h), "C": (a, 0, h)}
    else:
        pts = {"A": (0, 0, 0), "B": (h, 0, 0), "C": (h, a, 0)}
    for name, p in pts.items():
        m.add_node(name, *map(float, p))
    m.add_member("AB", "A", "B", "m", "s")
    m.add_member("BC", "B", "C", "m", "s")
    m.def_support("A", True, True, True, True, True, True)
    m.add_node_load("C", "FZ", -1.0)
    m.analyze_linear(check_stability=False)
    return -m.nodes["C"].DZ["Combo 1"]


@pytest.mark.parametrize("h, a", [(60.0, 85.0), (120.0, 30.0)])
def test_two_bar_frame_matches_virtual_work(h, a):
    d, e, g = 3.0, 125_000.0, 5_000.0
    area, i, _, _ = st.circle_section(d)
    closed = a**3 / (3 * e * i) + a**2 * h / (e * i) + h / (e * area)
    assert _l_frame(h, a, d, e, g, planar=True) == pytest.approx(closed, rel=0.01)


@pytest.mark.parametrize("b, a", [(60.0, 85.0), (100.0, 40.0)])
def test_plan_two_bar_frame_bending_and_torsion_matches_closed_form(b, a):
    d, e, g = 3.0, 15_000.0, 1_000.0
    _, i, _, j = st.circle_section(d)
    closed = a**3 / (3 * e * i) + b**3 / (3 * e * i) + a**2 * b / (g * j)
    assert _l_frame(b, a, d, e, g, planar=False) == pytest.approx(closed, rel=0.01)


def test_sections_are_the_textbook_ones():
    a, iy, iz, j = st.tube_section(6.3, 3.1)
    assert a == pytest.approx(math.pi / 4 * (6.3**2 - 3.1**2))
    assert iy == iz == pytest.approx(math.pi / 64 * (6.3**4 - 3.1**4))
    assert j == pytest.approx(2 * iy)
    a, strong, weak, j = st.strip_section(6.3, 1.2)
    assert (a, strong, weak) == pytest.approx((6.3 * 1.2, 1.2 * 6.3**3 / 12, 6.3 * 1.2**3 / 12))
    assert 0 < j < 6.3 * 1.2**3 / 3


# -- the frame against the paper -------------------------------------------------------------

def test_carbon_preset_within_15pct_of_7040(carbon_result):
    assert carbon_result.k_n_per_m == pytest.approx(7040.0, rel=0.15)
    assert carbon_result.calibration == st.JOINT_CALIBRATION
    assert carbon_result.deflection_mm == pytest.approx(1000 * carbon_result.load_n / carbon_result.k_n_per_m)


def test_calibration_constant_is_the_carbon_calibration():
    # The single global factor is what `calibrate` gives for the carbon preset (guards a stale
    # constant after a geometry change), and it is of order one: a correction, not the model.
    s = _carbon()
    c = st.calibrate(s, frame_mod.build(s))
    assert st.JOINT_CALIBRATION == pytest.approx(c, rel=0.02)
    assert 0.25 < st.JOINT_CALIBRATION < 4


def test_calibration_scales_only_the_joints():
    s = _carbon()
    f = frame_mod.build(s)
    soft = st.predict_stiffness(s, f, calibration=0.5 * st.JOINT_CALIBRATION)
    assert soft.calibration == 0.5 * st.JOINT_CALIBRATION
    # Halving the joint modulus is the same model as a joint material of half the modulus.
    tpu = s.material(s.joints.material)
    half = _variant(materials={"half_tpu": {"density_g_cm3": tpu.density_g_cm3, "e_mpa": tpu.e_mpa / 2,
                                            "g_mpa": tpu.g_mpa / 2, "printed": True}},
                    joints={"material": "half_tpu", "fit_clearance": {"half_tpu": s.fit_clearance}})
    assert _k(half) == pytest.approx(soft.k_n_per_m, rel=1e-6)


# -- trends from physics -----------------------------------------------------------------------

def test_k_rises_with_rod_diameter_3_to_4_mm():
    # same 1.6 mm joint wall for both: a 4 mm rod needs at least 1.6 mm (40 % of the rod)
    assert _k(_variant(rods={"diameter": 4.0}, joints={"wall": 1.6})) > _k(_variant(rods={"diameter": 3.0}, joints={"wall": 1.6}))


def test_k_rises_with_rod_modulus_bamboo_to_carbon():
    assert _k(_variant(rods={"material": "carbon_rod"})) > _k(_variant(rods={"material": "bamboo"}))


def test_k_falls_with_softer_joint_material():
    tpu = spec_mod.from_dict({}).material("tpu_95a")
    soft = _variant(materials={"soft_tpu": {"density_g_cm3": 1.22, "e_mpa": tpu.e_mpa / 2, "g_mpa": tpu.g_mpa / 2,
                                            "printed": True}},
                    joints={"material": "soft_tpu", "fit_clearance": {"soft_tpu": 0.1}})
    k_soft, k = _k(soft), _k(_variant())
    assert k_soft < k
    assert k_soft < 0.75 * k  # the TPU joints, not the rods, carry most of the compliance


def test_k_rises_with_joint_wall():
    assert _k(_variant(joints={"wall": 2.4})) > _k(_variant(joints={"wall": 1.6}))


def test_struts_carry_the_payload():
    assert _k(_variant(frame={"struts": False})) < 0.2 * _k(_variant(frame={"struts": True}))


def test_friction_at_the_feet_stiffens():
    s = _carbon()
    assert _k(s, feet="pinned") > _k(s, feet="sliding")


# -- the model itself ----------------------------------------------------------------------

def test_symmetry_four_feet_and_links_deflect_equally():
    s = _carbon()
    mdl = st.build_model(s, frame_mod.build(s))
    mdl.fe.analyze_linear(check_stability=False, sparse=False)
    nodes = mdl.fe.nodes

    def equal(values):
        lo, hi = min(values), max(values)
        return (hi - lo) <= 1e-6 * max(abs(lo), abs(hi))

    def radial(n):
        return (n.DX["payload"] * n.X + n.DY["payload"] * n.Y) / math.hypot(n.X, n.Y)

    def tangential(n):
        return (n.DY["payload"] * n.X - n.DX["payload"] * n.Y) / math.hypot(n.X, n.Y)

    assert len(mdl.feet) == len(mdl.links) == len(mdl.knees) == 4
    assert equal([nodes[n].DZ["payload"] for n in mdl.links])
    assert equal([nodes[n].DZ["payload"] for n in mdl.knees])
    assert equal([radial(nodes[n]) for n in mdl.feet])
    assert equal([radial(nodes[n]) for n in mdl.knees])
    assert all(nodes[n].DZ["payload"] == 0 for n in mdl.feet)  # standing on the floor
    # The tangential floor springs only pin the rigid-body modes: they carry no force.
    feet_move = max(abs(radial(nodes[n])) for n in mdl.feet)
    assert max(abs(tangential(nodes[n])) for n in mdl.feet) < 1e-6 * feet_move
    pay = nodes[mdl.payload]
    assert abs(pay.DX["payload"]) < 1e-6 * abs(pay.DZ["payload"])
    assert abs(pay.DY["payload"]) < 1e-6 * abs(pay.DZ["payload"])


def test_fe_solve_is_deterministic():
    s = _carbon()
    f = frame_mod.build(s)
    a, b = st.predict_stiffness(s, f), st.predict_stiffness(s, frame_mod.build(s))
    fields = ("k_n_per_m", "deflection_mm", "max_joint_rotation_deg", "k_top_n_per_m", "knee_spread_mm", "n_nodes", "n_members")
    assert [getattr(a, x) for x in fields] == [getattr(b, x) for x in fields]


def test_linear_in_load_and_exact_without_rod_subdivision():
    s = _carbon()
    f = frame_mod.build(s)
    base = st.predict_stiffness(s, f)
    assert st.predict_stiffness(s, f, load_n=2.364).k_n_per_m == pytest.approx(base.k_n_per_m, rel=1e-9)
    assert st.predict_stiffness(s, f, load_n=115.0).deflection_mm == pytest.approx(11.5 * base.deflection_mm, rel=1e-9)
    assert st.predict_stiffness(s, f, rod_segments=3).k_n_per_m == pytest.approx(base.k_n_per_m, rel=1e-5)


def test_rigid_members_are_rigid_enough(monkeypatch):
    s = _carbon()
    f = frame_mod.build(s)
    k = st.predict_stiffness(s, f).k_n_per_m
    monkeypatch.setattr(st, "_RIGID_E_MPA", 10 * st._RIGID_E_MPA)
    monkeypatch.setattr(st, "_RIGID_G_MPA", 10 * st._RIGID_G_MPA)
    assert st.predict_stiffness(s, f).k_n_per_m == pytest.approx(k, rel=1e-4)


def test_result_fields(carbon_result):
    r = carbon_result
    assert r.load_n == st.DEFAULT_LOAD_N
    assert r.n_nodes > 16 and r.n_members > 28
    assert 0 < r.max_joint_rotation_deg < 10
    assert r.k_top_n_per_m > r.k_n_per_m  # pressing the top moves the payload less than loading it
    assert r.knee_spread_mm is not None


def test_bad_arguments_raise():
    s = _carbon()
    f = frame_mod.build(s)
    with pytest.raises(ValueError):
        st.predict_stiffness(s, f, calibration=0.0)
    with pytest.raises(ValueError):
        st.predict_stiffness(s, f, feet="glued")
    with pytest.raises(ValueError):
        st.predict_stiffness(s, f, load_n=-1.0)


def test_module_does_not_import_cad():
    code = "import sys, cogniframe.analysis.stiffness as s; assert 'cadquery' not in sys.modules and 'OCP' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_cached_k_follows_a_change_in_the_materials_library(tmp_path, monkeypatch):
    """The check path caches k on disk; the key must cover materials.py (library moduli), not
    only the params file, or an edited TPU modulus would serve a stale k."""
    from cogniframe.analysis import drop

    s = _carbon()
    key = drop._stiffness_key(s)
    lib = Path(drop.__file__).resolve().parents[1] / "materials.py"
    real = Path.read_bytes

    def edited(self):
        data = real(self)
        return data + b"\n# edited modulus\n" if self.resolve() == lib else data

    monkeypatch.setattr(Path, "read_bytes", edited)
    assert drop._stiffness_key(s) != key

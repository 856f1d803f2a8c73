"""The motor catalogue, the screws in the assembly and the fit check (analysis/fit_check.py).

Benchmarks: the authors' motor base (CogniFly-STL v8 Flex_MotorBase_Shorter) has its four 2.0 mm
holes 4.5 mm from the centre: the FPV "9x9" read across the shaft. ISO 4762 / 4032 give the screw
and nut sizes. Each fit-check rule has a failing case built from a preset's own plan with one
thing changed (a hole moved onto a rod, a longer screw, the pattern read as a square)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cogniframe import fasteners as fasteners_mod
from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from cogniframe.analysis import fit_check
from cogniframe.errors import UserError
from cogniframe.materials import MIN_THREAD_TURNS, MOTOR_PRESETS, SCREWS
from presets import preset_spec

ROOT = Path(__file__).resolve().parents[1]
CLASSES = ("1103", "1104", "1105", "1106", "1202", "1203", "1204", "1404", "1406", "1407", "1408", "1505")


def _design(spec):
    fr = frame_mod.frame_of(spec)
    return fr, partlist.part_list(spec, fr)


def _mount(parts):
    return next(p for p in parts if p.family == "motor_mount")


def _with(part, **params):
    d = dict(part.params)
    d.update(params)
    return replace(part, params=tuple(d.items()))


def _fit(spec, fr, parts):
    return fit_check.check(spec, parts, fasteners_mod.fasteners(spec, fr, parts))


# -- the catalogue ---------------------------------------------------------------------------

def test_catalogue_has_the_classes_with_sources_and_thread_depths():
    assert set(CLASSES) <= set(MOTOR_PRESETS)
    for m in MOTOR_PRESETS.values():
        assert m.source and m.screw in SCREWS and len(m.holes) == 2
        # a screw can engage 4 turns and still stop inside the thread
        assert MIN_THREAD_TURNS * SCREWS[m.screw].pitch <= m.thread_depth
        assert m.bell_d > max(m.holes) and m.mass_g > 0 and m.thrust_g > 0


def test_9x9_is_four_holes_on_a_9mm_circle_not_a_square():
    pts = np.asarray(MOTOR_PRESETS["1104"].hole_points(0.0))
    assert np.allclose(np.hypot(pts[:, 0], pts[:, 1]), 4.5)  # the authors' motor base: 4.5 mm from the centre
    assert np.linalg.norm(pts[0] - pts[1]) == pytest.approx(9.0)  # an opposite pair, 9 mm apart across the shaft


def test_two_pair_pattern_reads_each_pair_across_the_shaft():
    m = replace(MOTOR_PRESETS["1505"], holes=(16.0, 19.0))
    pts = np.asarray(m.hole_points(0.0))
    assert np.linalg.norm(pts[0] - pts[1]) == pytest.approx(16.0)
    assert np.linalg.norm(pts[2] - pts[3]) == pytest.approx(19.0)
    assert m.pattern == "16x19"


def test_iso_screw_table():
    m2 = SCREWS["M2"]
    assert (m2.d, m2.pitch, m2.head_d, m2.head_h, m2.nut_af, m2.nut_m, m2.clearance_d) == (2.0, 0.4, 3.8, 2.0, 4.0, 1.6, 2.4)


def test_motor_models_in_the_schema():
    import json

    schema = json.loads((ROOT / "cogniframe" / "data" / "params.schema.json").read_text())
    desc = schema["$defs"]["MotorsSection"]["properties"]["model"]["description"]
    assert all(c in desc for c in CLASSES)


# -- the presets pass -------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_presets_pass_the_fit_check(name):
    spec = preset_spec(name)
    fr, parts = _design(spec)
    r = _fit(spec, fr, parts)
    assert r.ok, r.messages()
    mount = _mount(parts)
    fs = fasteners_mod.fasteners(spec, fr, parts)
    assert sum(f.name.startswith("screw_motor_") for f in fs) == 4 * len(mount.param("holes")) >= 8
    assert r.screws == sum(f.kind == "screw" for f in fs)
    # the 1104 and 1404 patterns: 4.5 mm from the shaft axis
    assert np.allclose([math.hypot(*h) for h in mount.param("holes")], 4.5)
    e = mount.param("engagement")
    assert MIN_THREAD_TURNS * 0.4 <= e <= spec.motor.thread_depth


def test_rectangle_example_passes_the_fit_check():
    spec = spec_mod.load(ROOT / "examples" / "rect-240x180.yaml")
    fr, parts = _design(spec)
    assert _fit(spec, fr, parts).ok


@pytest.mark.parametrize("spacing, holes", [(12.0, 2), (25.0, 4)])
def test_mount_keeps_the_pairs_that_clear_the_rods(spacing, holes):
    """The authors' rods 25 mm apart leave room for all four holes; 12 mm apart, the pair across the
    arm would cut the rods, so the mount carries the pair on the arm axis."""
    spec = preset_spec("carbon", frame__arm_spacing=spacing, core__link="tab")  # the pegs need 14 mm
    fr, parts = _design(spec)
    mount = _mount(parts)
    assert len(mount.param("holes")) == holes
    assert _fit(spec, fr, parts).ok
    for x, y in mount.param("holes"):
        for p, d in mount.param("arm_rods"):
            assert fit_check.plan_distance((x, y), p, d) >= spec.bore / 2 + 1.2 + 0.8


@pytest.mark.parametrize("model", CLASSES)
@pytest.mark.parametrize("spacing", [12.0, 25.0])
def test_every_motor_class_fits_or_is_refused_on_arm_spacing(model, spacing):
    spec = preset_spec("carbon", motors__model=model, frame__arm_spacing=spacing, core__link="tab")  # the pegs need 14 mm
    try:
        fr, parts = _design(spec)
    except UserError as e:
        assert e.key == "frame.arm_spacing", str(e)
        return
    r = _fit(spec, fr, parts)
    assert r.ok, r.messages()


def test_too_narrow_arm_spacing_is_refused_with_the_key():
    spec = preset_spec("carbon", frame__arm_spacing=8.0, core__link="tab")  # the mount's own refusal, not the pegs'
    with pytest.raises(UserError) as err:
        _design(spec)
    assert err.value.key == "frame.arm_spacing" and "frame.arm_spacing to at least" in str(err.value)


# -- each rule fails where it should ----------------------------------------------------------

def test_fails_a_hole_through_a_rod():
    """The carbon preset with its rods 12 mm apart, and the pair across the arm added back: those
    holes sit 1.5 mm from a rod's axis, inside its 3.2 mm bore."""
    spec = preset_spec("carbon", frame__arm_spacing=12, core__link="tab")  # the pegs need 14 mm
    fr, parts = _design(spec)
    mount = _mount(parts)
    d0 = np.asarray(mount.param("arm_rods")[0][1], float)
    turn = math.degrees(math.atan2(d0[1], d0[0]))
    bad = _with(mount, holes=spec.motor.hole_points(turn))
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    rods = [p for p in r.problems if p.rule == "rod_wall"]
    assert len(rods) == 2 and all("arm rod" in p.b and "motor_mount hole" in p.a for p in rods)
    assert "cuts its 3.2 mm bore" in rods[0].message  # the through-sleeve: 3 mm + joints.sleeve_clearance
    assert {p.rule for p in r.problems} == {"rod_wall"}


def test_fails_a_screw_too_long():
    """An M2 x 8 through the 2.7 mm seat enters the 1104 5.3 mm: past its 2.5 mm thread, into the windings."""
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    mount = _mount(parts)
    bad = _with(mount, screw_length=8.0)
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    assert r.problems and {p.rule for p in r.problems} == {"thread"}
    p = r.problems[0]
    assert p.a == "screw_motor_fl_1" and p.b == "motor_fl" and "5.30 mm" in p.message and "windings" in p.message


def test_fails_a_screw_too_short():
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    mount = _mount(parts)
    bad = _with(mount, screw_length=3.0)
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    assert {p.rule for p in r.problems} == {"thread"} and "would strip" in r.problems[0].message


def test_fails_a_screw_wider_than_its_hole():
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    mount = _mount(parts)
    bad = _with(mount, screw_clearance=2.0)
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    assert "screw_hole" in {p.rule for p in r.problems}
    p = next(p for p in r.problems if p.rule == "screw_hole")
    assert p.a == "motor_mount_fl" and p.b.startswith("screw_motor_fl")


def test_fails_the_pattern_read_as_a_square():
    """The old reading of "9x9": holes on a 9 mm square, 6.36 mm from the axis; the rods 25 mm
    apart so the holes clear them and only the pattern rule can catch it."""
    spec = preset_spec("carbon", frame__arm_spacing=25.0)
    fr, parts = _design(spec)
    mount = _mount(parts)
    d0 = np.asarray(mount.param("arm_rods")[0][1], float)
    u = d0[:2] / np.linalg.norm(d0[:2])
    v = np.array([-u[1], u[0]])
    square = tuple(tuple(float(c) for c in (a * u + b * v) * 4.5) for a in (-1, 1) for b in (-1, 1))
    bad = _with(mount, holes=square)
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    pat = [p for p in r.problems if p.rule == "pattern"]
    assert len(pat) == 4 and "6.36 mm from the shaft axis" in pat[0].message and pat[0].b == "motor 1104"


def test_fails_the_diagonal_pattern_read_on_the_arm_axis():
    """Rods 25 mm apart: the mount carries the four holes at 45 deg to the arm (pattern_turn 45).
    The same holes on a mount that says its pattern lies on the arm axis are 3.44 mm from every
    catalogue hole: the pattern rule reads the turn, it does not accept any hole on the circle."""
    spec = preset_spec("carbon", frame__arm_spacing=25.0)
    fr, parts = _design(spec)
    mount = _mount(parts)
    assert mount.param("pattern_turn") == 45.0
    bad = _with(mount, pattern_turn=0.0)
    parts = tuple(bad if p is mount else p for p in parts)
    pat = [p for p in _fit(spec, fr, parts).problems if p.rule == "pattern"]
    assert len(pat) == 4 and "nearest 3.44 mm away" in pat[0].message


def test_fails_a_mount_without_an_opposite_pair():
    spec = preset_spec("carbon", frame__arm_spacing=25.0)
    fr, parts = _design(spec)
    mount = _mount(parts)
    holes = mount.param("holes")
    bad = _with(mount, holes=(holes[0], holes[2]))  # one hole of each pair
    parts = tuple(bad if p is mount else p for p in parts)
    r = _fit(spec, fr, parts)
    assert [p.rule for p in r.problems] == ["pattern"] and "opposite pair" in r.problems[0].message


def test_fit_failure_fails_the_verdict(monkeypatch):
    """The fit check's problems are the verdict's: a failing plan makes `check` FAIL, naming both parts."""
    from cogniframe.analysis import verdict

    spec = preset_spec("carbon", model__stiffness_model="analytic", core__link="tab")  # closed forms: the tab's
    from cogniframe.design import design

    d = design(spec)
    mount = _mount(d.parts)
    bad = _with(mount, screw_length=8.0)
    d = replace(d, parts=tuple(bad if p is mount else p for p in d.parts))
    r = verdict.check(spec, design_=d, peaks=False, modes=False, survival_margins=False)
    assert r.verdict == "FAIL"
    assert any("screw_motor_fl_1" in p and "motor_fl" in p for p in r.problems)
    out = verdict.check_dict(r)
    assert out["fit"]["ok"] is False and out["fit"]["problems"][0]["rule"] == "thread"


# -- the assembly ------------------------------------------------------------------------------

def test_screws_are_vitamins_at_their_holes():
    from cogniframe.vitamins import thread_pairs, vitamins

    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    mount = _mount(parts)
    vits = {v.name: v for v in vitamins(spec, fr, parts)}
    screws = [v for v in vits.values() if v.name.startswith("screw_motor_")]
    assert len(screws) == 4 * len(mount.param("holes"))
    for mo in fr.motors:
        mine = [v for v in screws if v.name.startswith(f"screw_motor_{mo.corner}_")]
        for v in mine:
            head, shank = v.prims
            # the shank's axis 4.5 mm from the motor's axis, its tip inside the motor's thread
            assert math.hypot(shank.centre[0] - mo.axis[0], shank.centre[1] - mo.axis[1]) == pytest.approx(4.5, abs=1e-6)
            tip = shank.centre[2] + shank.length
            assert mo.seat_z < tip <= mo.seat_z + spec.motor.thread_depth + 1e-9
            assert head.radius == pytest.approx(1.9) and head.centre[2] + head.length == pytest.approx(shank.centre[2])
        assert all(frozenset((v.name, f"motor_{mo.corner}")) in thread_pairs(spec, fr, parts) for v in mine)


def test_bom_lists_the_motor_screws_with_their_length():
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    mount = _mount(parts)
    (hw,) = mount.hardware
    assert hw.item == f"M2 x {mount.param('screw_length'):g} socket-head screw (motor to mount)"
    assert hw.qty == len(mount.param("holes"))


# -- the built solid -----------------------------------------------------------------------------

def _cylinder(face):
    from OCP.BRepAdaptor import BRepAdaptor_Surface

    return BRepAdaptor_Surface(face.wrapped).Cylinder()


def _hole_faces(shape, radius: float):
    """(axis point x, y, z range) of every vertical cylindrical face of `radius` in the solid."""
    out = []
    for f in shape.Faces():
        if f.geomType() != "CYLINDER":
            continue
        cyl = _cylinder(f)
        if abs(cyl.Radius() - radius) > 1e-6:
            continue
        ax = cyl.Axis().Direction()
        if abs(abs(ax.Z()) - 1.0) > 1e-9:
            continue
        loc = cyl.Axis().Location()
        bb = f.BoundingBox()
        out.append((loc.X(), loc.Y(), bb.zmin, bb.zmax, f))
    return out


@pytest.mark.parametrize("spacing, wall, n", [(12.0, 1.2, 2), (25.0, 1.2, 4), (12.0, 3.5, 2)])
@pytest.mark.cad
def test_built_1104_mount_holes_are_4p5mm_from_the_axis_and_clear_the_rods(spacing, wall, n):
    """On the CAD solid: the screw holes' cylinder axes lie 4.5 mm from the shaft hole's axis, each
    hole's wall stays within the seat plate (it never runs through a clip sleeve), and the hole and
    the head's seat keep at least two extrusion lines of TPU to every rod bore."""
    from cogniframe.families import motor_mount

    spec = preset_spec("carbon", frame__arm_spacing=spacing, joints__wall=wall, core__link="tab")  # the pegs need 14 mm
    fr, parts = _design(spec)
    mount = _mount(parts)
    built = motor_mount.solid(mount)
    shape = built.shape
    (shaft,) = {(round(x, 3), round(y, 3)): (x, y) for x, y, *_ in _hole_faces(shape, mount.param("shaft_hole") / 2)}.values()
    holes = _hole_faces(shape, mount.param("screw_clearance") / 2)
    axes = {(round(x, 3), round(y, 3)) for x, y, *_ in holes}
    assert len(axes) == n
    for x, y, *_ in holes:
        assert math.hypot(x - shaft[0], y - shaft[1]) == pytest.approx(4.5, abs=1e-5)
    grip = float(mount.param("grip"))
    bores = [f for f in shape.Faces() if f.geomType() == "CYLINDER"
             and abs(_cylinder(f).Radius() - spec.sleeve_bore / 2) < 1e-6]  # the mount's through-sleeves
    assert len(bores) >= 2
    seats = _hole_faces(shape, mount.param("counterbore_d") / 2)
    # a seat has faces where it cut a sleeve: 3.5 mm walls fill the plate's underside between the rods
    assert {(round(x, 3), round(y, 3)) for x, y, *_ in seats} == (axes if wall > 3 else set())
    for *_, z0, z1, face in holes:
        assert z0 >= -1e-6 and z1 <= grip + 1e-6  # the hole runs through the seat plate only
    for *_, face in holes + seats:  # neither the hole nor the head's seat cuts into a bore
        for b in bores:
            assert face.distance(b) >= 2 * spec.printer.nozzle - 1e-6


# -- the core's screws and nuts -----------------------------------------------------------------

def test_camera_and_computer_screws_pass_through_board_and_mount_into_a_nut():
    """Carbon: the Pi camera v2 (M2 on 21 x 12.5 mm) through its 1.0 mm board and the 1.6 mm upright,
    and the Pi Zero (M2.5 on 58 x 23 mm) through its 1.4 mm board, a 3 mm nylon spacer (the board
    stands over the stack screws' heads) and the 2.0 mm mount frame, each into an ISO 4032 nut it
    fills: M2.5 x 10, 3.6 mm past the 6.4 mm grip (the 2.0 mm nut and 1.6 mm beyond)."""
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    fs = {f.name: f for f in fasteners_mod.fasteners(spec, fr, parts)}
    cam = [f for n, f in fs.items() if n.startswith("screw_camera_")]
    pi = [f for n, f in fs.items() if n.startswith("screw_computer_")]
    assert len(cam) == len(pi) == 4
    for f in cam:
        assert f.grip == pytest.approx(2.6) and f.length == 6.0 and f.engagement == pytest.approx(3.4)
        assert fs[f.thread].kind == "nut" and np.allclose(fs[f.thread].base, f.tip() - np.asarray(f.axis) * 3.4)
    xs = sorted({round(f.base[0], 6) for f in cam})
    assert xs == [-10.5, 10.5]  # 21 mm apart
    c = fr.core.computer
    assert sorted({(round(f.base[0] - c.centre[0], 6), round(f.base[1] - c.centre[1], 6)) for f in pi}) == \
        [(-29.0, -11.5), (-29.0, 11.5), (29.0, -11.5), (29.0, 11.5)]
    for f in pi:
        assert f.size == "M2.5" and f.grip == pytest.approx(6.4) and f.length == 10.0 and f.engagement == pytest.approx(3.6)


def test_fails_a_screw_that_does_not_fill_its_nut():
    spec = preset_spec("carbon")
    fr, parts = _design(spec)
    fs = list(fasteners_mod.fasteners(spec, fr, parts))
    i = next(k for k, f in enumerate(fs) if f.name == "screw_computer_1")
    fs[i] = replace(fs[i], length=8.0, engagement=round(8.0 - fs[i].grip, 4))  # 1.6 mm into a 2.0 mm nut
    r = fit_check.check(spec, parts, fs)
    (p,) = r.problems
    assert (p.rule, p.a, p.b) == ("thread", "screw_computer_1", "nut_computer_1") and "does not fill the nut" in p.message

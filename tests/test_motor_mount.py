"""The lean motor mount (families/motor_mount.py): a round seat bridged to two rod sleeves.

Benchmarks: the authors' motor base (CogniFly-STL v8 Flex_MotorBase_Shorter, measured: 0.91 cm^3,
1.11 g of TPU at 1.22 g/cm^3, a 15 mm seat on rods 25.3 mm apart, four holes at 45 deg to the arm);
the issue's targets (at most 1.6 g at the authors' 25 mm spacing for the 1104, no heavier than the
square-plate mount's 1.66 g at 12 mm); the fixed-guided beam P L^3 / (12 E I) for the bridges.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe.errors import UserError
from presets import link_for, preset_spec

TPU_DENSITY = 1.22  # g/cm^3, materials.py tpu_95a


def _mount(spec):
    fr = frame_mod.frame_of(spec)
    return next(p for p in partlist.part_list(spec, fr) if p.family == "motor_mount")


def _built(mount):
    from cogniframe.export.mesh import tessellate
    from cogniframe.families import motor_mount

    built = motor_mount.solid(mount)
    return built, tessellate(built.shape)


def _arm_angle(mount) -> float:
    d = mount.param("arm_rods")[0][1]
    return math.degrees(math.atan2(d[1], d[0]))


# -- mass: the issue's targets --------------------------------------------------------------------

@pytest.mark.parametrize("spacing, most_g", [(25.0, 1.6), (12.0, 1.66)])
@pytest.mark.cad
def test_1104_mount_weighs_no_more_than_the_issue_allows(spacing, most_g):
    """At the authors' 25 mm: at most 1.6 g (their part 1.11 g); at 12 mm: no heavier than the
    square-plate mount (1.66 g). The CAD's volume and the closed form both."""
    mount = _mount(preset_spec(frame__arm_spacing=spacing, **link_for(spacing)))
    built, mesh = _built(mount)
    cad_g = built.shape.Volume() * TPU_DENSITY / 1000
    assert cad_g <= most_g
    assert mount.estimate.volume * TPU_DENSITY / 1000 <= most_g
    # near the authors' 0.91 cm^3 at their spacing: the same parts (seat, bridges, sleeves), not a plate
    if spacing == 25.0:
        assert built.shape.Volume() == pytest.approx(906.0, rel=0.25)


# -- the closed form and the print, across the spacing range ----------------------------------------

@pytest.mark.parametrize("base, changes", [
    ("carbon", {"frame__arm_spacing": 12.0, "core__link": "tab"}),  # the pegs need 14 mm
    ("carbon", {"frame__arm_spacing": 16.0}),
    ("carbon", {"frame__arm_spacing": 25.0}),
    ("carbon", {"frame__arm_spacing": 30.0}),
    ("carbon", {"frame__arm_spacing": 25.0, "frame__knee_height": 0.3, "frame__level_arms": False, "core__link": "tab"}),  # arms rising toward the core (the tab: pegs need level arms)
    ("bamboo", {"frame__arm_spacing": 25.0, "frame__knee_height": 0.38}),  # level arms
    ("carbon", {"frame__arm_spacing": 25.0, "motors__model": "1103"}),
    ("carbon", {"frame__arm_spacing": 25.0, "motors__model": "1505"}),
    ("carbon", {"frame__arm_spacing": 25.0, "joints__wall": 3.0}),
    ("carbon", {"motors__model": "1106", "motors__seat_raise": 5.0}),  # the authors' taller motor base
    ("carbon", {"motors__model": "1106", "motors__seat_raise": 10.0}),  # and their tallest
])
@pytest.mark.cad
def test_closed_form_tracks_the_cad_and_the_mount_prints_flat(base, changes):
    """The estimate is the CAD volume within the part suite's 15 %; one closed solid on the bed,
    no unsupported overhang (printed seat down, no supports)."""
    from cogniframe.export.mesh import flat_contact_ratio, overhangs

    mount = _mount(preset_spec(base, **changes))
    built, mesh = _built(mount)
    cad = built.shape.Volume()
    assert abs(mount.estimate.volume / cad - 1) < 0.15, (mount.estimate.volume, cad)
    assert mesh.is_watertight and mesh.body_count == 1
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    oh = overhangs(mesh)
    assert oh["fraction"] < 0.01 and oh["area"] < 1.0, oh
    assert flat_contact_ratio(mesh) >= 0.20


# -- the holes ------------------------------------------------------------------------------------

def test_four_holes_at_45_deg_to_the_arm_at_the_authors_spacing():
    """Rods 25 mm apart: the 1104's four holes 4.5 mm from the shaft at 45 deg to the arm, as the
    authors' motor base; 12 mm apart: the pair on the arm axis only."""
    wide = _mount(preset_spec(frame__arm_spacing=25.0))
    assert wide.param("pattern_turn") == 45.0 and len(wide.param("holes")) == 4
    arm = _arm_angle(wide)
    for x, y in wide.param("holes"):
        assert math.hypot(x, y) == pytest.approx(4.5, abs=1e-5)
        assert (math.degrees(math.atan2(y, x)) - arm - 45.0) % 90.0 == pytest.approx(0.0, abs=1e-4) or \
            (math.degrees(math.atan2(y, x)) - arm - 45.0) % 90.0 == pytest.approx(90.0, abs=1e-4)
    narrow = _mount(preset_spec(frame__arm_spacing=12.0, core__link="tab"))
    assert narrow.param("pattern_turn") == 0.0 and len(narrow.param("holes")) == 2
    for x, y in narrow.param("holes"):
        assert (math.degrees(math.atan2(y, x)) - _arm_angle(narrow)) % 180.0 == pytest.approx(0.0, abs=1e-4) or \
            (math.degrees(math.atan2(y, x)) - _arm_angle(narrow)) % 180.0 == pytest.approx(180.0, abs=1e-4)


def test_centre_hole_that_opens_into_a_rod_is_refused_with_the_key():
    """The 1408's 6 mm shaft boss needs a 7 mm hole; rods 9.5 mm apart would pass through it (the
    screw holes on the arm axis clear them). Refused on frame.arm_spacing; the spacing it names builds."""
    with pytest.raises(UserError) as err:
        _mount(preset_spec(motors__model="1408", frame__arm_spacing=9.5, core__link="tab"))
    assert err.value.key == "frame.arm_spacing"
    msg = str(err.value)
    assert "shaft boss" in msg and "7 mm hole" in msg
    least = float(msg.split("frame.arm_spacing to at least ")[1].split()[0])
    assert least == pytest.approx(7.0 + 3.2 + 4 * 0.4, abs=0.05)  # hole + the through-sleeve's bore + two lines each side
    from cogniframe.analysis.fit_check import plan_distance

    mount = _mount(preset_spec(motors__model="1408", frame__arm_spacing=least, **link_for(least)))
    for p, d in mount.param("arm_rods"):
        assert plan_distance((0.0, 0.0), p, d) >= mount.param("shaft_hole") / 2 + 0.8 + 3.1 / 2 - 1e-6


def test_whoop_centre_hole_keeps_clear_of_the_screw_holes_and_passes_the_boss():
    """The whoop classes' M1.4 holes on a 6.6 mm circle end 2.5 mm from the axis, where a 4 mm
    boss's 5 mm hole would end: the centre hole stays clear of them and still passes the boss."""
    from cogniframe.families.motor_mount import HOLE_CLEAR
    from cogniframe.materials import SCREWS

    spec = preset_spec(motors__model="1103", frame__arm_spacing=25.0)
    mount = _mount(spec)
    r = mount.param("shaft_hole") / 2
    assert r >= spec.motor.shaft_boss_d / 2 + 0.1
    for x, y in mount.param("holes"):
        for hr in (SCREWS["M1.4"].clearance_d / 2, mount.param("counterbore_d") / 2):
            for edge in (math.hypot(x, y) - hr, math.hypot(x, y) + hr):
                assert abs(r - edge) >= HOLE_CLEAR - 1e-9


# -- stiffness: the bridges carry the thrust and the torque ---------------------------------------

@pytest.mark.parametrize("spacing", [25.0, 30.0])
def test_bridge_sag_and_twist_under_full_thrust_are_below_a_layer_PL3_over_12EI(spacing):
    """Each bridge as a fixed-guided beam from its sleeve's web to the seat's rim (the seat and the
    web-backed sleeve are many times deeper): half the motor's full thrust bends it out of plane,
    the motor's full-throttle drag torque (flight/rotors.py) shared by the two bridges bends it in
    plane. Both deflections stay below one printed layer (the smallest step the printer makes)."""
    from cogniframe.families.motor_mount import _span
    from cogniframe.analysis import rotors

    spec = preset_spec(frame__arm_spacing=spacing, **link_for(spacing))
    mount = _mount(spec)
    rm = rotors.model(spec, 0.24)
    e_mpa = spec.material(mount.material).e_mpa
    rods = [(np.asarray(p, float), np.asarray(d, float)) for p, d in mount.param("arm_rods")]
    e0, e1 = _span(rods, float(mount.param("clip_start")), float(mount.param("clip_len")))
    b = e1 - e0  # the bridge's width along the arm
    t = min(mount.wall + 1.5, float(mount.param("seat_z")))
    r = float(mount.param("bore")) / 2 + mount.wall
    w = min(mount.param("skirt")) * r
    seat_r = float(mount.param("seat_d")) / 2
    half = spacing / 2
    rim = math.sqrt(max(seat_r**2 - max(abs(e0), abs(e1)) ** 2, 0.0))  # the rim at the bridge's edges
    free = half - w - rim
    assert 0 < free < half
    sag = (rm.thrust_max_n / 2) * free**3 / (12 * e_mpa * b * t**3 / 12)
    shear = rm.torque_max_nm * 1000 / (2 * half)  # N on each bridge, along the arm
    twist = shear * free**3 / (12 * e_mpa * t * b**3 / 12)
    assert sag < spec.printer.layer_height, sag
    assert twist < spec.printer.layer_height, twist


@pytest.mark.parametrize("spacing", [12.0, 25.0])
@pytest.mark.cad
def test_level_arms_build_d_sleeves_that_print_flat(spacing):
    """Level arm rods (the authors' build; no preset height makes them exactly level yet): the
    carbon mount's rods laid level, planned again by the module's own layout, build D-section
    sleeves (webs as wide as the sleeve) as one closed solid with no overhang; the closed form
    tracks the CAD within the part suite's 15 %."""
    import dataclasses

    from cogniframe.export.mesh import overhangs
    from cogniframe.families import motor_mount as mm

    spec = preset_spec(frame__arm_spacing=spacing, **link_for(spacing))
    m = _mount(spec)
    rods = tuple((p, tuple(np.round(np.array([d[0], d[1], 0.0]) / math.hypot(d[0], d[1]), 6)))
                 for p, d in m.param("arm_rods"))
    seat_z, holes = m.param("seat_z"), m.param("holes")
    lay = mm.layout(spec, rods, holes, seat_z, m.param("counterbore_d"), m.param("shaft_hole"), spec.rods.diameter)
    est = mm._estimate(spec, rods, lay, seat_z, min(m.wall + 1.5, seat_z), holes, m.param("grip"),
                       m.param("counterbore_d"), m.param("shaft_hole"))
    params = dict(m.params)
    params.update(arm_rods=rods, arm_slope_deg=0.0, seat_d=lay.seat_d, clip_start=lay.clip_start,
                  clip_len=lay.clip_len, skirt=lay.skirts)
    part = dataclasses.replace(m, params=tuple(params.items()), estimate=est)
    assert lay.skirts == (1.0, 1.0) and lay.clip_start == -lay.clip_len / 2
    built, mesh = _built(part)
    assert mesh.is_watertight and mesh.body_count == 1
    oh = overhangs(mesh)
    assert oh["fraction"] < 0.01 and oh["area"] < 1.0, oh
    assert abs(est.volume / built.shape.Volume() - 1) < 0.15


# -- the taller motor base (motors.seat_raise) -------------------------------------------------------

def test_a_raised_seat_lifts_motor_and_propeller_and_weighs_its_webs():
    """motors.seat_raise: the seat, the motor and the propeller plane go up by it; the mount's
    closed form grows by the two webs under the sleeves, each `raise` taller along its clip, and
    the all-up weight by the motor-mount line alone, four webs of TPU (printed solid at most)."""
    from cogniframe import design as design_mod
    from cogniframe.analysis.mass import budget
    from cogniframe.materials import MATERIALS

    def made(raise_mm):
        spec = preset_spec(motors__model="1106", motors__seat_raise=raise_mm)
        d = design_mod.design(spec)
        return d, next(p for p in d.parts if p.family == "motor_mount"), budget(spec, d.frame, d.cut, d.parts)

    d0, m0, mass0 = made(0.0)
    d5, m5, mass5 = made(5.0)
    assert m5.param("seat_z") == pytest.approx(m0.param("seat_z") + 5.0)
    assert d5.frame.motors[0].prop_z == pytest.approx(d0.frame.motors[0].prop_z + 5.0)
    # two webs (level arms), each the sleeve's width (a skirt of its outer radius each side) by the clip's length, 5 mm taller
    r = m5.param("bore") / 2 + m5.wall
    web = sum(2 * f * r for f in m5.param("skirt")) * m5.param("clip_len") * 5.0
    assert m5.estimate.volume - m0.estimate.volume == pytest.approx(web, rel=0.02)
    line = {i.name: i.mass_g for i in mass5.items}["motor_mount"] - {i.name: i.mass_g for i in mass0.items}["motor_mount"]
    assert mass5.total_g - mass0.total_g == pytest.approx(line, abs=1e-9)  # nothing else changes
    solid = 4 * web * MATERIALS[m5.material].density_g_mm3
    assert 0.3 * solid < line <= solid * 1.001


def test_seat_raise_is_bounded_by_the_schema():
    with pytest.raises(UserError, match="motors.seat_raise"):
        preset_spec(motors__seat_raise=20.0)

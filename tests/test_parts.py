"""One suite over every registered part family: each part the presets plan, whatever its family,
is closed, printable without supports, on the bed and estimated right; each family module offers
what the registry promises. A new family is tested here by being registered.

The builds are shared (one per preset per test session) through `built_preset`, which the other
CAD test files import too.
"""

from __future__ import annotations

import functools
import math
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from cogniframe.errors import UserError
from cogniframe.families import registry

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("carbon", "bamboo")
FAMILIES = registry.families()
# the families only an option plans (off in the presets), with the key that turns each on
OPTION_FAMILIES = {"net": {"frame__rear_net": True}}
OVERHANG_MAX = 0.01  # unsupported fraction of the downward-facing area


@functools.lru_cache(maxsize=None)
def planned(name: str):
    """A preset's spec, frame and part list (no CAD)."""
    spec = spec_mod.load(ROOT / "params" / f"{name}.yaml")
    frame = frame_mod.frame_of(spec)
    return spec, frame, partlist.part_list(spec, frame)


# Every part of every preset, named by the registry's plans: the suite's cases.
PART_NAMES = {p: tuple(part.name for part in planned(p)[2]) for p in PRESETS}
CASES = [(p, n) for p in PRESETS for n in PART_NAMES[p]]


@functools.lru_cache(maxsize=None)
def built_preset(name: str):
    """Build a preset's parts once a process into a temp dir, through the run's cache (the other
    worker's parts are read from it, not built again); meshes re-read from the STL files."""
    from cogniframe.cache import cache_dir
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl

    spec, frame, parts = planned(name)
    out = Path(tempfile.mkdtemp(prefix=f"cogniframe-test-{name}-"))
    built = build_parts(spec, frame, parts, out, cache_dir=cache_dir())
    meshes = {b.name: load_stl(out / b.stl) for b in built}
    return SimpleNamespace(spec=spec, frame=frame, parts={p.name: p for p in parts}, built={b.name: b for b in built},
                           out=out, meshes=meshes)


def test_presets_have_the_expected_parts():
    """The plans, in the registry's order: the carbon preset carries every family."""
    assert PART_NAMES == {
        "carbon": ("corner_top", "corner_bottom", "knee", "core_link", "core_link_mirrored", "motor_mount", "core_plate",
                   "battery_holder", "sensor_mount", "front_camera_mount", "computer_mount"),
        "bamboo": ("corner_top", "corner_bottom", "knee", "core_link", "core_link_mirrored", "motor_mount", "core_plate",
                   "battery_holder", "core_spacer"),
    }


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.cad
def test_family_module_keeps_the_registry_contract(family):
    """Each family's module names itself, sizes from a real params key, plans its own parts (every
    family but an option's is planned by the carbon preset, so it runs through the CAD cases below;
    an option's family, `OPTION_FAMILIES`, is planned with its key on) and gives, without CAD, the
    same print orientation its solid is built in."""
    mod = registry.get(family)
    assert mod.NAME == family and mod.DOC
    spec, frame, _ = planned("carbon")
    if family in OPTION_FAMILIES:
        from presets import preset_spec

        spec = preset_spec("carbon", **OPTION_FAMILIES[family])
        frame = frame_mod.frame_of(spec)
    value = spec
    for key in mod.SIZE_KEY.split("."):
        value = getattr(value, key)
    assert value is not None
    parts = mod.plan(spec, frame)
    assert parts and all(p.family == family for p in parts)
    for p in parts:
        built = registry.solid(p) if family in OPTION_FAMILIES else built_preset("carbon").built[p.name]
        assert np.allclose(mod.print_from_local(p), built.print_from_local, atol=1e-9)


@pytest.mark.parametrize("preset,name", CASES)
@pytest.mark.cad
def test_stl_is_a_closed_single_volume(preset, name):
    d = built_preset(preset)
    m, b = d.meshes[name], d.built[name]
    assert m.is_watertight and m.is_volume
    assert m.volume > 0
    assert m.body_count == 1 == b.shells
    assert b.watertight
    assert b.volume_mm3 == pytest.approx(m.volume, rel=1e-6)
    assert b.area_h_mm2 + b.area_v_mm2 == pytest.approx(m.area, rel=1e-6)


@pytest.mark.parametrize("preset,name", CASES)
@pytest.mark.cad
def test_part_sits_flat_inside_the_bed(preset, name):
    from cogniframe.export.mesh import flat_contact_ratio

    d = built_preset(preset)
    m = d.meshes[name]
    assert m.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    assert np.all(m.extents <= np.asarray(d.spec.printer.bed) + 1e-6), f"{name} {m.extents} > bed"
    assert flat_contact_ratio(m) >= 0.20


# The pegged core link prints standing on its pegs with two overhangs the authors' connector has
# too: the arch's first layer beside the columns and the bridge under its crown, 8 mm across, past
# this check's 6 mm bridges. tests/test_pegged_core_link.py slices it layer by layer and allows
# exactly those two.
PEGGED_LINKS = {"core_link", "core_link_mirrored"}


@pytest.mark.parametrize("preset,name", [(p, n) for p, n in CASES if n not in PEGGED_LINKS])
@pytest.mark.cad
def test_no_unsupported_overhang(preset, name):
    from cogniframe.export.mesh import overhangs

    oh = overhangs(built_preset(preset).meshes[name])
    assert oh["fraction"] < OVERHANG_MAX, oh
    assert oh["area"] < 1.0, oh


@pytest.mark.parametrize("preset,name", CASES)
@pytest.mark.cad
def test_analytic_estimate_tracks_the_cad_volume(preset, name):
    d = built_preset(preset)
    est, cad = d.parts[name].estimate.volume, d.built[name].volume_mm3
    assert abs(est / cad - 1) < 0.15, f"{name}: estimate {est:.0f} vs CAD {cad:.0f} mm^3"


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_core_plate_volume_is_its_closed_form(preset):
    """The pegged presets' plate: its X, ribs and tubes (families/core_plate.py `_with_tubes`, by
    hand in tests/test_core_plate_pegs.py) within 0.5 % of the CAD; a square plate: the box less its
    holes."""
    d = built_preset(preset)
    p = d.parts["core_plate"]
    if dict(p.params).get("tubes"):
        closed = p.estimate.volume
    else:
        size, t, hole_d = p.param("size"), p.param("thickness"), p.param("hole_d")
        closed = size * size * t - len(p.param("holes")) * math.pi / 4 * hole_d**2 * t
    assert d.built["core_plate"].volume_mm3 == pytest.approx(closed, rel=0.005)


@pytest.mark.cad
def test_battery_holder_volume_is_box_minus_cavity_and_openings():
    """Closed form: outer box - cavity - stack holes - two side windows and two strap slots through
    the walls - the floor window - the lead notch in the top wall over the mouth (pointed windows:
    L w - w^2/2)."""
    d = built_preset("carbon")
    p = d.parts["battery_holder"]
    (w, length, h), (iw, il, ih) = p.param("outer"), p.param("inner")
    t = p.param("wall")
    skin = (h - ih) / 2
    ya, ye, hz = p.param("side_window")
    fa, fe, fw = p.param("floor_window")
    _, _, s_len, s_w = p.param("strap_slot")
    lw, y0 = p.param("lead_exit")
    closed = (w * length * h - iw * il * ih - 4 * math.pi / 4 * p.param("hole_d") ** 2 * skin
              - 2 * ((ye - ya) * hz - hz**2 / 2) * t - ((fe - fa) * fw - fw**2 / 2) * skin
              - 2 * s_len * s_w * t - lw * (length / 2 - y0) * skin)
    assert d.built["battery_holder"].volume_mm3 == pytest.approx(closed, rel=0.005)
    # printed standing on its back stop: as tall as the holder is long
    assert d.built["battery_holder"].bbox_mm[2] == pytest.approx(length)
    # the lead notch passes the connector (XT30: 10.2 mm wide)
    assert lw > 10.2


# -- the open camera and computer mounts ---------------------------------------------------------

def _ring(centre, r, n=24):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)]


def _computer_mount_closed_form(p):
    (a, b), t = p.param("size"), p.param("thickness")
    holes = 4 * math.pi / 4 * (p.param("computer_hole_d") ** 2 + p.param("stack_hole_d") ** 2)
    windows = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in p.param("windows"))
    return (a * b - windows - holes) * t


def _assert_computer_mount_frame_carries_its_screws(spec, p, mesh, print_from_local):
    """Each hole's nut (M2.5 ISO 4032: 5.0 across flats, 5.77 across corners) or screw head bears
    on solid frame all round (points on the across-corners circle, mid-thickness, lie in the
    mesh); the bars between windows and every rail are at least two lines of the nozzle wide."""
    from cogniframe.export.mesh import contains
    from cogniframe.materials import SCREWS

    for key, screw in (("computer_holes", spec.core.computer.screw), ("stack_holes", spec.core.stack_screw)):
        s = SCREWS[screw]
        r = max(s.head_d / 2, s.nut_af / math.sqrt(3))
        for h in p.param(key):
            pts = np.c_[_ring(h, r), np.zeros(24), np.ones(24)]  # on the plate's local mid-plane
            inside = contains(mesh, (pts @ np.asarray(print_from_local).T)[:, :3])
            assert inside.all(), f"{key} {h}: the {screw} nut/head overhangs a window"
    (a, b) = p.param("size")
    wins = sorted(p.param("windows"))
    assert wins, "the computer mount is open between its bars"
    min_member = 2 * spec.printer.nozzle
    for x0, y0, x1, y1 in wins:
        assert b / 2 - y1 >= min_member and y0 + b / 2 >= min_member and x0 + a / 2 >= min_member and a / 2 - x1 >= min_member
    for (_, _, x1, _), (x0, _, _, _) in zip(wins, wins[1:]):
        assert x0 - x1 >= min_member


@pytest.mark.cad
def test_computer_mount_is_an_open_frame_of_plate_less_windows_and_holes():
    """Carbon: the mount is the authors' kind of part (RPI_Support_new, a 2.0 mm frame of bars,
    1.65 cm^3): its CAD volume is the closed form plate - windows - holes, it is under half the
    65 x 30 mm plate it replaces (4.76 cm^3), and it still carries the Pi Zero's 58 x 23 mm holes
    (Raspberry Pi Zero mechanical drawing) and the 20 x 20 stack's."""
    d = built_preset("carbon")
    p = d.parts["computer_mount"]
    cad = d.built["computer_mount"].volume_mm3
    assert cad == pytest.approx(_computer_mount_closed_form(p), rel=1e-3)
    assert cad < 0.5 * (65 * 30 * 2.5)
    assert p.param("thickness") == 2.0
    assert sorted(p.param("computer_holes")) == sorted((x, y) for x in (-29.0, 29.0) for y in (-11.5, 11.5))
    assert sorted(p.param("stack_holes")) == sorted((x, y) for x in (-10.0, 10.0) for y in (-10.0, 10.0))
    _assert_computer_mount_frame_carries_its_screws(d.spec, p, d.meshes["computer_mount"],
                                                    d.built["computer_mount"].print_from_local)


def _camera_mount_closed_form(p, stack_d):
    """Untilted: base (box - two front corner triangles - window - stack holes) x base_t + upright
    (board-wide, `height` tall above the base, less the slot and the camera holes) x wall."""
    from cogniframe.families.camera_mount import CAMERA_SPINE

    w, yf, yb, bt, wall, h = (p.param(k) for k in ("width", "y_front", "y_back", "base_t", "wall", "height"))
    k = p.param("corner_cut") - (yf - wall)
    x0 = max(k, CAMERA_SPINE)
    corner = (max(0.0, w / 2 - k) ** 2 - max(0.0, min(x0, w / 2) - k) ** 2) / 2
    wx0, wy0, wx1, wy1 = p.param("base_window")
    base = w * (yf - yb) - 2 * corner - (wx1 - wx0) * (wy1 - wy0) - 4 * math.pi / 4 * stack_d**2
    up = w * h - 2 * p.param("slot") * h - 4 * math.pi / 4 * p.param("camera_hole_d") ** 2
    return base * bt + up * wall


@pytest.mark.cad
def test_camera_mount_is_two_stiles_on_an_open_base():
    """Carbon: the camera bracket is the authors' kind of support (CameraConnectorLeft/Right, two
    stile brackets, 2 x 0.51 cm^3): the base opens between the stack holes and the upright is two
    stiles with a slot open at the top. Its CAD volume is the closed form; it is under 75 % of the
    solid L it replaces (2.32 cm^3); every camera hole (Pi camera v2 drawing: 21 x 12.5 mm, M2)
    keeps the M2 head's 3.8 mm circle on solid stile, and every stack hole the M2 head's circle."""
    from cogniframe.export.mesh import contains
    from cogniframe.families.camera_mount import camera_upright_matrix
    from cogniframe.materials import SCREWS

    d = built_preset("carbon")
    p = d.parts["front_camera_mount"]
    g = dict(p.params)
    assert g["tilt_deg"] == 0.0 and g["slot"] > 0 and g["base_window"]
    cad = d.built["front_camera_mount"].volume_mm3
    assert cad == pytest.approx(_camera_mount_closed_form(p, g["stack_hole_d"]), rel=1e-3)
    assert cad < 0.75 * 2322.5
    hx = {abs(x) for x, _ in g["camera_holes"]}
    assert hx == {10.5} and sorted({z for _, z in g["camera_holes"]}) == pytest.approx([12.5, 25.0])
    mesh, m = d.meshes["front_camera_mount"], np.asarray(d.built["front_camera_mount"].print_from_local)
    r = SCREWS["M2"].head_d / 2
    up = camera_upright_matrix(g)
    for x, z in g["camera_holes"]:
        ring = _ring((x, z - g["base_t"]), r)
        pts = np.c_[ring[:, 0], np.full(24, -g["wall"] / 2), ring[:, 1], np.ones(24)]
        assert contains(mesh, (pts @ (m @ up).T)[:, :3]).all(), (x, z)
    for h in g["stack_holes"]:
        ring = _ring(h, r)
        pts = np.c_[ring, np.full(24, g["base_t"] / 2), np.ones(24)]
        assert contains(mesh, (pts @ m.T)[:, :3]).all(), h
    # the stiles are wider than two nozzle lines
    assert g["width"] / 2 - g["slot"] >= 2 * d.spec.printer.nozzle


@pytest.mark.parametrize("overrides", [
    {"core": {"stack_pattern": "30.5x30.5", "stack_screw": "M2.5", "camera": {"tilt_deg": 30.0},
              "computer": {"hole_spacing": [30.0, 20.0]}},
     "printer": {"nozzle": 0.8}, "joints": {"wall": 1.6}},
    {"core": {"plate_thickness": 6.0, "camera": {"tilt_deg": -20.0}, "computer": {"hole_spacing": [58.0, 49.0]}}},
], ids=["30.5-M2.5-nozzle0.8", "thick-plate-pi4-holes"])
@pytest.mark.cad
def test_open_mounts_build_across_the_design_space(overrides, tmp_path):
    """Off the preset (the wider stack, M2.5 stack screws, a 0.8 mm nozzle, a small computer or a
    Raspberry Pi 4's 58 x 49 mm holes, a tilted camera, a thick plate): both mounts build as one
    closed solid, flat, without supports, the computer mount's volume is its closed form and its
    frame still carries every nut."""
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl, overhangs

    data = spec_mod.load(ROOT / "params" / "carbon.yaml").model_dump(mode="json")

    def merge(node, over):
        for k, v in over.items():
            if isinstance(v, dict) and isinstance(node.get(k), dict):
                merge(node[k], v)
            else:
                node[k] = v

    merge(data, overrides)
    spec = spec_mod.from_dict(data)
    frame = frame_mod.frame_of(spec)
    parts = [p for p in partlist.part_list(spec, frame) if p.family in ("camera_mount", "computer_mount")]
    assert len(parts) == 2
    for b, p in zip(build_parts(spec, frame, parts, tmp_path), parts):
        m = load_stl(tmp_path / b.stl)
        assert m.is_watertight and m.body_count == 1 and m.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
        assert overhangs(m)["fraction"] < 0.03
        assert abs(p.estimate.volume / b.volume_mm3 - 1) < 0.05
        if p.family == "computer_mount":
            assert b.volume_mm3 == pytest.approx(_computer_mount_closed_form(p), rel=1e-3)
            _assert_computer_mount_frame_carries_its_screws(spec, p, m, b.print_from_local)


# -- the overhang measure itself ---------------------------------------------------------------

def _mesh(shape):
    from cogniframe.export.mesh import tessellate

    return tessellate(shape)


@pytest.mark.cad
def test_overhang_measure_flags_a_cantilever_and_a_wide_hole_but_not_a_small_hole():
    import cadquery as cq

    from cogniframe.export.mesh import overhangs

    mushroom = cq.Workplane().box(4, 4, 10, centered=(True, True, False)).faces(">Z").workplane().rect(20, 20).extrude(3)
    assert overhangs(_mesh(mushroom))["fraction"] > 0.3
    block = cq.Workplane().box(30, 16, 16, centered=(True, True, False))
    small = block.cut(cq.Workplane("YZ").center(0, 8).circle(1.6).extrude(40, both=True))
    wide = block.cut(cq.Workplane("YZ").center(0, 8).circle(5.0).extrude(40, both=True))
    assert overhangs(_mesh(small))["area"] < 0.5
    assert overhangs(_mesh(wide))["area"] > 20  # a 10 mm hole is not a bridge


@pytest.mark.cad
def test_flat_contact_ratio_of_a_ball_is_tiny():
    import cadquery as cq

    from cogniframe.export.mesh import flat_contact_ratio

    ball = cq.Workplane().sphere(5).translate((0, 0, 5)).cut(cq.Workplane().box(20, 20, 0.2, centered=(True, True, False)))
    assert flat_contact_ratio(_mesh(ball.translate((0, 0, -0.2)))) < 0.2


# -- registry, bed fit ---------------------------------------------------------------------

def test_registry_lists_families_and_rejects_unknown_ones():
    assert registry.families() == ("battery_holder", "camera_mount", "computer_mount", "core_plate", "joint",
                                   "motor_mount", "net", "sensor_mount")
    assert set(registry.sizes()) == set(FAMILIES)
    with pytest.raises(ValueError) as e:
        registry.get("wing")
    for f in FAMILIES:
        assert f in str(e.value)


def test_a_new_family_is_one_module_and_one_registry_line(monkeypatch):
    """A family module registered in `registry.FAMILIES` is planned into the part list (after the
    others, with its digest), found by name and listed: nothing else needs to know it."""
    import types

    from cogniframe.parts.record import Estimate, PartSpec, Placement

    fam = types.ModuleType("gps_mount")
    fam.NAME, fam.SIZE_KEY, fam.DOC = "gps_mount", "core.plate_size", "ABS/PLA GPS puck mount"
    fam.plan = lambda spec, frame: (PartSpec("gps_mount", "gps_mount", "core", spec.core.material, spec.core.infill,
                                             (Placement("core", 0.0, (0.0, 0.0, 30.0)),), (), 1.6,
                                             Estimate(1000.0, 500.0, 200.0, (20.0, 20.0, 2.5))),)
    fam.print_from_local = lambda part: np.eye(4)
    monkeypatch.setattr(registry, "FAMILIES", (*registry.FAMILIES, fam))
    spec, frame, before = planned("carbon")
    after = partlist.part_list(spec, frame)
    assert [p.name for p in after] == [*PART_NAMES["carbon"], "gps_mount"]
    assert after[:-1] == before and len(after[-1].digest) == 16
    assert registry.get("gps_mount") is fam and registry.sizes()["gps_mount"] == fam.DOC
    assert np.array_equal(registry.print_from_local(after[-1]), np.eye(4))


@pytest.mark.cad
def test_part_larger_than_the_bed_is_a_user_error(tmp_path):
    from cogniframe.export.part_files import build_parts

    spec = spec_mod.from_dict({"printer": {"bed": [60, 60, 60]}})
    frame = frame_mod.frame_of(spec)
    parts = [p for p in partlist.part_list(spec, frame) if p.name == "computer_mount"]
    with pytest.raises(UserError) as e:
        build_parts(spec, frame, parts, tmp_path)
    msg = str(e.value)
    assert "computer_mount" in msg and "65.0 x 30.0" in msg and "60 x 60 x 60" in msg
    assert "printer.bed" in msg and "core.computer.hole_spacing" in msg


@pytest.mark.cad
def test_part_that_fits_only_turned_is_turned(tmp_path):
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl

    spec = spec_mod.from_dict({"printer": {"bed": [40, 70, 60]}})
    frame = frame_mod.frame_of(spec)
    parts = [p for p in partlist.part_list(spec, frame) if p.name == "computer_mount"]
    (b,) = build_parts(spec, frame, parts, tmp_path)
    m = load_stl(tmp_path / b.stl)
    assert m.extents[0] <= 40 and m.extents[1] <= 70
    # the turn is part of print_from_local: the Pi holes still land where the transform says
    hole = np.r_[parts[0].param("computer_holes")[0], 0.0, 1.0]
    p = (b.print_from_local @ hole)[:3]
    from cogniframe.export.mesh import contains

    assert not contains(m, [p])[0]


# -- socket walls and the knee hinge, measured on the mesh -----------------------------------

def _rays_to_surface(mesh, origin, dirs):
    from cogniframe.export.mesh import ray_first_hit

    return ray_first_hit(mesh, np.tile(origin, (len(dirs), 1)), dirs)


@pytest.mark.parametrize("preset,name", [(p, n) for p in PRESETS for n in ("corner_top", "corner_bottom", "knee", "core_link")])
@pytest.mark.cad
def test_socket_bore_and_walls(preset, name):
    """At mid-depth the hole radius is bore/2, and the wall around it and behind its bottom is >= wall."""
    from cogniframe.export.mesh import ray_first_hit
    from cogniframe.parts.joint_plan import map_sockets

    d = built_preset(preset)
    part, m = d.parts[name], d.meshes[name]
    for s in map_sockets(part, d.built[name].print_from_local):
        mid = s.at(s.seat + s.depth / 2)
        u = np.cross(s.direction, [0.3, 0.5, 0.8])
        u /= np.linalg.norm(u)
        v = np.cross(s.direction, u)
        ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        dirs = np.outer(np.cos(ang), u) + np.outer(np.sin(ang), v)
        radius = _rays_to_surface(m, mid, dirs)
        assert np.allclose(radius, s.bore / 2, atol=0.02), (s.rod, radius)
        # wall: from just outside the hole to the outer surface (rays that leave through the bed
        # or the flat cut are fine: that is where the wall is the sleeve's flat side)
        outer = ray_first_hit(m, mid + dirs * (s.bore / 2 + 0.01), dirs) + 0.01
        assert outer.min() >= part.wall - 0.05, (s.rod, outer.min())
        back = ray_first_hit(m, s.bottom - s.direction * 0.01, -s.direction[None, :])[0] + 0.01
        assert back >= part.wall - 0.05, (s.rod, back)


@pytest.mark.cad
def test_knee_living_hinge_is_a_thin_web_between_slots():
    import dataclasses

    from cogniframe.export.mesh import contains, ray_first_hit, tessellate
    from cogniframe.families import joint as joint_family
    from cogniframe.parts import joint_plan

    d = built_preset("carbon")
    knee = d.parts["knee"]
    for h in (1.2, 1.6):
        part = dataclasses.replace(knee, params=tuple((k, h if k == "hinge_thickness" else v) for k, v in knee.params))
        web = joint_plan.knee_hinge(part)
        m = tessellate(joint_family.solid(part).shape)
        mid = np.r_[web.probe, web.height / 2]
        n = np.r_[web.normal, 0.0]
        # through the web: material exactly hinge_thickness thick ...
        start = mid - n * (h / 2 + joint_plan.HINGE_GAP / 2)  # in the slot
        t_in = ray_first_hit(m, [start], [n])[0]
        t_out = ray_first_hit(m, [start + n * (t_in + 0.01)], [n])[0] + 0.01
        assert t_out == pytest.approx(h, abs=0.05)
        # ... with open slots on both sides of it
        assert not contains(m, [mid + n * (h / 2 + joint_plan.HINGE_GAP / 2), mid - n * (h / 2 + joint_plan.HINGE_GAP / 2)]).any()


@pytest.mark.cad
@pytest.mark.fe
def test_frame_without_struts_builds_and_fails_the_drop_check(tmp_path):
    """frame.struts: false leaves the core links with the arm pair only: it must still build,
    and the model must say what it means (the struts carry the payload)."""
    import yaml

    from cogniframe import spec as spec_mod
    from cogniframe.analysis import verdict
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl

    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    data["frame"]["struts"] = False
    s = spec_mod.from_dict(data)
    r = verdict.check(s)
    link = next(p for p in r.design.parts if p.name == "core_link")
    assert len(link.sockets) == 2
    built = build_parts(s, r.design.frame, [link], tmp_path)
    mesh = load_stl(tmp_path / built[0].stl)
    assert mesh.is_watertight and mesh.volume == pytest.approx(built[0].volume_mm3, rel=1e-3)
    # arm-only links: the estimate's print plane is the one across the arm pair (as the CAD's), ~8 % high
    assert link.estimate.volume == pytest.approx(mesh.volume, rel=0.15)
    assert r.verdict == "FAIL" and r.drop.max_safe_height_cm < 10

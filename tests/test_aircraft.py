"""Issue 13: the whole aircraft. Vitamins placed and tied to the mass budget, the core that
carries them, the clash check (and its negative controls), the battery's way out, the flow
sensor's view, and the flight numbers against a hand calculation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tiers
import trimesh

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe.families import battery_holder
from cogniframe.analysis import verdict
from cogniframe import spec as spec_mod
from cogniframe.errors import UserError
from test_parts import PRESETS, ROOT, built_preset


def _bodies(d):
    from cogniframe.export.assembly import bodies

    return bodies(d.spec, d.frame, tuple(d.parts.values()), tuple(d.built.values()), d.meshes)


@pytest.fixture(scope="module")
@tiers.needs('cad')
def scenes():
    """Per preset: the design and its clash result (one clash check per preset)."""
    from cogniframe.analysis import clash
    from cogniframe.export.assembly import not_clashes, press_fits

    out = {}
    for p in PRESETS:
        d = built_preset(p)
        b = _bodies(d)
        out[p] = (d, b, clash.check(b, prop_margin=d.spec.requirements.prop_margin,
                                    ignore=not_clashes(d.spec, d.frame, tuple(d.parts.values())),
                                    allowed=press_fits(d.spec, d.frame)))
    return out


# -- clash-free ---------------------------------------------------------------------------------

@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_assembly_is_clash_free(scenes, preset):
    """Every pair of printed parts, rods and vitamins overlaps < 0.5 mm^3 and every propeller clears
    everything by prop_margin (the core links once cut 11.9 mm^3 into the carbon battery holder,
    36.0 mm^3 on bamboo)."""
    d, bodies, r = scenes[preset]
    assert r.ok, r.messages()
    names = {b.name for b in bodies}
    assert {"battery_holder", "core_link_fr", "core_link_fl", "battery", "motor_fl", "propeller_rr"} <= names
    from cogniframe.vitamins import vitamins

    assert r.bodies == len(bodies) == sum(p.qty for p in d.parts.values()) + len(d.frame.rods) + len(vitamins(d.spec, d.frame))
    assert r.pairs_tested < r.pairs_total / 5  # the bounding-box prefilter does its job
    a, b, v = r.max_overlap  # below the tolerance, or a rod pressed into its socket by no more than its ring
    from cogniframe.export.assembly import press_fits

    assert v < 0.5 or v < 0.5 + press_fits(d.spec, d.frame)[frozenset((a, b))]
    # every propeller was tested against something within its margin box, and cleared it
    assert {p for p, _, _ in r.prop_gaps} == {f"propeller_{k}" for k in frame_mod.CORNERS}
    assert all(g >= d.spec.requirements.prop_margin for _, _, g in r.prop_gaps)


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_mirror_pairs_of_core_links_are_mirror_images(preset):
    """front-left/rear-right and front-right/rear-left links are mirror images through x = 0 (they
    were 90 deg rotations of one chiral part, so the two pairs met the rectangular holder differently)."""
    from cogniframe.export.mesh import intersection_volume

    d = built_preset(preset)
    world = {b.name: b for b in _bodies(d)}

    def placed(name):
        m = world[name].mesh.copy()
        m.apply_transform(world[name].transform)
        return m

    for a, b in (("core_link_fl", "core_link_fr"), ("core_link_rr", "core_link_rl")):
        ma, mb = placed(a), placed(b)
        mb.apply_transform(np.diag([-1.0, 1.0, 1.0, 1.0]))  # mirror through x = 0 (trimesh re-winds the faces)
        assert mb.is_volume
        common = intersection_volume(ma, mb)
        assert common == pytest.approx(ma.volume, rel=0.002), (a, b, common, ma.volume)
    assert d.parts["core_link"].qty == d.parts["core_link_mirrored"].qty == 2


@pytest.mark.fe
def test_moving_one_part_into_another_is_a_fail_naming_both(scenes):
    """Negative control: the battery holder raised 3 mm into the sensor mount and plate; a rod moved
    under a propeller. The check names both solids, the overlap and the gap; verdict.check FAILs."""
    from cogniframe.analysis import clash
    from cogniframe.export.assembly import own_motor_pairs

    d, bodies, _ = scenes["carbon"]
    up = np.eye(4)
    up[2, 3] = 3.0
    moved = [clash.Body(b.name, b.kind, b.mesh, up @ b.transform, b.disc) if b.name == "battery_holder" else b for b in bodies]
    r = clash.check(moved, ignore=own_motor_pairs(d.frame))
    pairs = {frozenset((c.a, c.b)): c for c in r.clashes}
    hit = pairs[frozenset(("battery_holder", "sensor_mount"))]
    assert hit.kind == "overlap" and hit.volume_mm3 > 10
    assert any("battery_holder" in m and "sensor_mount" in m and "mm^3" in m for m in r.messages())
    # a rod 3 mm under the front-left propeller disc: closer than the 5 mm margin, not touching
    prop = next(b for b in bodies if b.name == "propeller_fl")
    lo, hi = prop.mesh.bounds
    c = (lo + hi) / 2
    rod = trimesh.creation.cylinder(radius=1.5, segment=[[c[0] - 20, c[1], lo[2] - 4.5], [c[0] + 20, c[1], lo[2] - 4.5]])
    r2 = clash.check([prop, clash.Body("rod_test", "rod", rod)], prop_margin=5.0)
    (m,) = r2.clashes
    assert (m.a, m.b, m.kind) == ("propeller_fl", "rod_test", "prop_margin")
    assert m.gap_mm == pytest.approx(3.0, abs=0.1) and m.volume_mm3 == 0
    # the check turns clashes into FAIL problems
    result = verdict.check(d.spec, clash=r)
    assert result.verdict == "FAIL" and any("battery_holder" in p and "sensor_mount" in p for p in result.problems)


@pytest.mark.cad
def test_screws_are_in_the_clash_check_and_one_off_its_hole_is_a_clash(scenes):
    """The motor screws are bodies of the clash check; in its own clearance hole a screw touches
    nothing (its head on the seat's underside, its tip in the motor's thread, which is exempt);
    moved 1 mm sideways it cuts the mount, and the check names both."""
    from cogniframe.analysis import clash
    from cogniframe.export.assembly import not_clashes

    d, bodies, r = scenes["carbon"]
    screws = [b for b in bodies if b.name.startswith("screw_motor_")]
    assert len(screws) == 4 * len(d.parts["motor_mount"].param("holes"))
    assert any(b.name.startswith("nut_") for b in bodies)
    ignore = not_clashes(d.spec, d.frame, tuple(d.parts.values()))
    assert frozenset(("screw_motor_fl_1", "motor_fl")) in ignore
    assert frozenset(("screw_motor_fl_1", "motor_mount_fl")) not in ignore
    near = [b for b in bodies if b.name in ("screw_motor_fl_1", "motor_mount_fl", "motor_fl")]
    assert clash.check(near, ignore=ignore).ok
    side = np.eye(4)
    side[0, 3] = 1.0
    moved = [clash.Body(b.name, b.kind, b.mesh, side, b.disc) if b.name == "screw_motor_fl_1" else b for b in near]
    (c,) = clash.check(moved, ignore=ignore).clashes
    assert {c.a, c.b} == {"screw_motor_fl_1", "motor_mount_fl"} and c.volume_mm3 > 0.5


# -- vitamins -------------------------------------------------------------------------------------

@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.fe
def test_every_vitamin_has_its_mass_in_exactly_one_budget_line(preset):
    from cogniframe.vitamins import vitamins

    spec = spec_mod.load(ROOT / "params" / f"{preset}.yaml")
    res = verdict.check(spec)
    items = {i.name: i for i in res.mass.items}
    vits = vitamins(spec, res.design.frame)
    for v in vits:
        assert v.budget_line in items, v.name
    # every components line that names a vitamin is drawn, and nothing is drawn twice for one line
    drawn = {v.budget_line for v in vits}
    for c in spec.components:
        assert (c.name in drawn) == (c.vitamin is not None)
    assert sum(v.family == "motor" for v in vits) == items[f"motor {spec.motor.name}"].qty == 4
    assert sum(v.family == "propeller" for v in vits) == 4
    bat = next(v for v in vits if v.family == "battery")
    lo, hi = bat.bounds
    b = spec.core.battery
    assert tuple(np.round(hi - lo, 6)) == (b.width, b.length, b.height)


def test_motor_and_prop_solids_follow_the_presets():
    from cogniframe.vitamins import PROP_DISC_T, to_trimesh, vitamins

    spec = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    fr = frame_mod.frame_of(spec)
    v = {x.name: x for x in vitamins(spec, fr)}
    motor, prop = to_trimesh(v["motor_fl"]), to_trimesh(v["propeller_fl"])
    m = fr.motors[0]
    assert motor.extents[0] == pytest.approx(spec.motor.bell_d, abs=0.05)  # 18 mm bell of the 1404
    assert motor.bounds[0, 2] == pytest.approx(m.seat_z)  # stands on the mount's seat
    r = spec.motors.prop_diameter / 2
    assert prop.extents[2] == pytest.approx(PROP_DISC_T)
    assert prop.volume == pytest.approx(math.pi * r * r * PROP_DISC_T, rel=0.01)  # a disc of the prop diameter
    assert prop.bounds[0, 2] > m.prop_z  # above the bell, in the propeller plane


@pytest.mark.cad
def test_vitamins_are_in_the_assembly_step_with_names_and_colours(tmp_path):
    """Round trip through cq.Assembly.importStep: every vitamin by name, with its colour."""
    import cadquery as cq

    from cogniframe.export.assembly import write_assembly
    from cogniframe.vitamins import vitamins

    d = built_preset("carbon")
    step, glb = write_assembly(d.spec, d.frame, tuple(d.parts.values()), tuple(d.built.values()), d.out)
    assy = cq.Assembly.importStep(str(step))
    colour = {c.name: c.color.toTuple()[:3] for c in assy.children if c.color is not None}
    vits = vitamins(d.spec, d.frame)
    names = {v.name for v in vits}
    assert {"motor_fl", "propeller_rr", "battery", "flight_controller", "esc", "computer", "camera", "flow_sensor"} <= names
    for v in vits:
        assert v.name in colour, v.name
        assert colour[v.name] == pytest.approx(v.colour, abs=0.01), v.name
    child = next(c for c in assy.children if c.name == "battery")
    bb = child.obj.moved(child.loc).BoundingBox() if child.obj is not None else child.toCompound().BoundingBox()
    box = d.frame.core.battery
    assert (bb.xlen, bb.ylen, bb.zlen) == pytest.approx(tuple(box.size), abs=0.01)
    assert glb.stat().st_size > 10_000
    # and in the GLB: a scene node named after each vitamin
    glb_nodes = set(trimesh.load(glb).graph.nodes)
    for v in vits:
        assert v.name in glb_nodes, v.name


# -- the core that carries it ---------------------------------------------------------------------

@pytest.mark.cad
def test_camera_and_sensor_mounts_are_printed_flat_watertight_and_on_the_plates():
    from cogniframe.export import plates as plates_mod
    from cogniframe.export.mesh import flat_contact_ratio, overhangs

    d = built_preset("carbon")
    for name in ("front_camera_mount", "sensor_mount"):
        m = d.meshes[name]
        assert m.is_watertight and m.is_volume and m.body_count == 1, name
        assert m.bounds[0, 2] == pytest.approx(0.0, abs=1e-6) and flat_contact_ratio(m) > 0.3, name
        assert overhangs(m)["fraction"] < 0.01, name
    items = [plates_mod.PlateItem(b.name, b.material, b.qty, d.meshes[b.name]) for b in d.built.values()]
    plates = plates_mod.pack_plates(items, d.spec.printer.bed, d.spec.printer.margin)
    on_plates = {c.part for pl in plates for c in pl.copies}
    assert {"front_camera_mount", "sensor_mount", "core_link_mirrored"} <= on_plates
    # every copy is a build item of its plate's 3MF (trimesh drops scene nodes named "camera...")
    import io
    import zipfile

    for pl in plates:
        model = zipfile.ZipFile(io.BytesIO(plates_mod.plate_3mf_bytes(pl))).read("3D/3dmodel.model").decode()
        for c in pl.copies:
            assert f'partnumber="{c.name}"' in model, c.name


def test_camera_tilt_turns_the_camera_and_its_upright():
    from cogniframe.vitamins import camera_vitamin

    data = spec_mod.load(ROOT / "params" / "carbon.yaml").model_dump(mode="json")
    axes = {}
    for tilt in (0.0, 20.0):
        data["core"]["camera"]["tilt_deg"] = tilt
        s = spec_mod.from_dict(data)
        v = camera_vitamin(s, frame_mod.frame_of(s))
        apex, axis, _ = v.view
        axes[tilt] = np.asarray(axis)
    assert axes[0.0] == pytest.approx([0, 1, 0])  # default: looking straight forward
    assert math.degrees(math.atan2(axes[20.0][2], axes[20.0][1])) == pytest.approx(20.0)
    data["core"]["camera"]["tilt_deg"] = 60
    with pytest.raises(UserError, match="tilt_deg"):
        spec_mod.from_dict(data)


def _cone(apex, axis, half_angle_deg: float, length: float, sections: int = 48) -> trimesh.Trimesh:
    """A solid cone from `apex` along `axis`, `length` long."""
    r = length * math.tan(math.radians(half_angle_deg))
    cone = trimesh.creation.cone(radius=r, height=length, sections=sections)  # base at z = 0, apex at z = length
    cone.apply_translation([0, 0, -length])
    cone.apply_transform(np.diag([1.0, 1.0, -1.0, 1.0]))  # apex at 0, base at +length (faces re-wound)
    z = np.asarray(axis, float) / np.linalg.norm(axis)
    from cogniframe.vitamins import _frame_z

    m = np.eye(4)
    m[:3, :3] = _frame_z(z)
    m[:3, 3] = apex
    cone.apply_transform(m)
    return cone


def test_flow_sensor_sees_the_ground_unobstructed(scenes):
    """The PMW3901's 42 deg cone from the board down to the ground meets no solid."""
    from cogniframe.export.mesh import intersection_volume

    d, bodies, _ = scenes["carbon"]
    flow = next(b for b in bodies if b.name == "flow_sensor")
    from cogniframe.vitamins import flow_vitamin

    apex, axis, half = flow_vitamin(d.spec, d.frame).view
    cone = _cone(apex, axis, half, apex[2])  # down to the ground plane
    assert cone.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    for b in bodies:
        if b is flow:
            continue
        m = b.mesh.copy()
        if b.transform is not None:
            m.apply_transform(b.transform)
        lo, hi = np.maximum(m.bounds[0], cone.bounds[0]), np.minimum(m.bounds[1], cone.bounds[1])
        if np.any(lo > hi):
            continue
        assert intersection_volume(cone, m) < 0.5, b.name
    # negative control: the same cone from the core's centre runs into the battery and its holder
    for name in ("battery", "battery_holder"):
        body = next(b for b in bodies if b.name == name)
        bm = body.mesh.copy()
        if body.transform is not None:
            bm.apply_transform(body.transform)
        assert intersection_volume(_cone((0, 0, apex[2] + 8.0), axis, half, apex[2] + 8.0), bm) > 20, name


@pytest.mark.parametrize("preset", PRESETS)
def test_battery_slides_out_along_its_axis_without_meeting_any_solid(scenes, preset):
    """Sweep the pack's box forward (+y, out of the holder's mouth) by its length plus the mouth:
    the swept box overlaps no solid. Backwards it runs into the back stop (negative control)."""
    from cogniframe.export.mesh import intersection_volume

    d, bodies, _ = scenes[preset]
    box = d.frame.core.battery
    travel = box.size[1] + d.frame.core.mouth + 5.0
    lo, hi = box.lo.copy(), box.hi.copy()
    hi_fwd = hi + np.array([0.0, travel, 0.0])
    swept = trimesh.creation.box(bounds=[lo, hi_fwd])
    seen = 0
    for b in bodies:
        if b.name == "battery":
            continue
        m = b.mesh.copy()
        if b.transform is not None:
            m.apply_transform(b.transform)
        if np.any(np.maximum(m.bounds[0], lo) > np.minimum(m.bounds[1], hi_fwd)):
            continue
        seen += 1
        assert intersection_volume(swept, m) < 0.5, b.name
    assert seen >= 1  # the holder itself was tested (the pack slides inside it)
    back = trimesh.creation.box(bounds=[lo - np.array([0.0, 10.0, 0.0]), hi])
    holder = next(b for b in bodies if b.name == "battery_holder")
    hm = holder.mesh.copy()
    hm.apply_transform(holder.transform)
    assert intersection_volume(back, hm) > 100


def test_holder_has_strap_slots_and_a_lead_exit_that_passes_the_connector():
    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    fr = frame_mod.frame_of(spec)
    f = battery_holder.holder_features(spec, fr)
    ys, _, s_len, s_w = f["strap_slot"]
    assert s_len == spec.core.strap_width + 1.0
    # the slot lies wholly in front of the pack (so a strap through it crosses the mouth)
    pack_front = -fr.core.holder.size[1] / 2 + spec.core.holder_wall + spec.core.battery.length
    assert ys - (s_len + s_w) / math.sqrt(8) > pack_front
    assert f["lead_exit"][0] > 10.2  # XT30 housing 10.2 mm wide
    assert f["lead_exit"][1] == pytest.approx(pack_front)  # the notch starts at the pack's front face
    data = spec.model_dump(mode="json")
    data["core"]["battery"]["connector"] = "XT60"
    s60 = spec_mod.from_dict(data)
    assert battery_holder.holder_features(s60, frame_mod.frame_of(s60))["lead_exit"][0] > 15.8
    data["core"]["battery"]["connector"] = "EC5"
    with pytest.raises(UserError, match="connector"):
        spec_mod.from_dict(data)


def test_camera_without_a_budget_line_is_a_user_error():
    data = spec_mod.load(ROOT / "params" / "carbon.yaml").model_dump(mode="json")
    data["components"] = [c for c in data["components"] if c.get("vitamin") != "pi_camera_v2"]
    with pytest.raises(UserError, match=r"core\.camera.*components"):
        spec_mod.from_dict(data)


# -- flight ---------------------------------------------------------------------------------------

def test_bamboo_flight_matches_a_hand_calculation():
    """1404 3000KV, 4024, 2S 2000 mAh at 248 g: each motor lifts 62 g. Table points (47 g, 0.97 A,
    50 %) and (66 g, 1.59 A, 60 %): I = 0.97 + 15/19 x 0.62 = 1.4595 A a motor, throttle 57.9 %;
    FC 0.5 W through the 85 % BEC at 7.4 V: 0.0795 A; total 5.9174 A; usable 1600 mAh ->
    16.22 min; T/W = 4 x 165 / 248 = 2.661."""
    from cogniframe.analysis import flight

    spec = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    f = flight.evaluate(spec, 248.0)
    i_motor = 0.97 + 15 / 19 * (1.59 - 0.97)
    i_total = 4 * i_motor + 0.5 / 0.85 / 7.4
    assert f.hover_current_a == pytest.approx(i_total, rel=1e-9)
    assert f.hover_current_a == pytest.approx(5.9174, abs=1e-3)
    assert f.hover_throttle == pytest.approx(0.5 + 15 / 19 * 0.1, rel=1e-9)
    assert f.hover_time_min == pytest.approx(1.6 / i_total * 60, rel=1e-9)
    assert f.hover_time_min == pytest.approx(16.22, abs=0.01)
    assert f.thrust_to_weight == pytest.approx(4 * 165 / 248, rel=1e-9)
    assert f.hover_power_w == pytest.approx(i_total * 7.4, rel=1e-9)


@pytest.mark.fe
def test_bamboo_hover_time_is_near_the_reported_17_min():
    """The authors report about 17 min for the bamboo build (2S 2000 mAh). The preset's estimate
    is within 15 % (it cannot be exact: the table is representative, the real pack's usable
    fraction, sag, wind and manoeuvring are not modelled)."""
    spec = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    f = verdict.check(spec).flight
    assert f.hover_time_min == pytest.approx(17.0, rel=0.15)


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.fe
def test_hover_power_matches_momentum_theory_with_a_figure_of_merit(preset):
    """Table hover power against T^1.5 / sqrt(2 rho A) / (FM x eta) with FM x eta = 0.30: within 20 %."""
    f = verdict.check(spec_mod.load(ROOT / "params" / f"{preset}.yaml")).flight
    assert f.hover_power_w == pytest.approx(f.momentum_hover_power_w, rel=0.20)


def test_momentum_theory_closed_form():
    """A 0.6 N rotor of 4 in: ideal power 0.6^1.5 / sqrt(2 x 1.225 x pi x 0.0508^2) = 3.29 W."""
    from cogniframe.analysis.flight import momentum_hover_power_w

    ideal = 0.6**1.5 / math.sqrt(2 * 1.225 * math.pi * 0.0508**2)
    assert momentum_hover_power_w(0.6, 101.6, fom_eta=1.0) == pytest.approx(ideal, rel=1e-12)
    assert ideal == pytest.approx(3.29, abs=0.01)


def test_max_thrust_per_motor_and_voltage_scaling():
    from cogniframe.analysis.flight import max_thrust_g

    bamboo = spec_mod.load(ROOT / "params" / "bamboo.yaml")
    carbon = spec_mod.load(ROOT / "params" / "carbon.yaml")
    assert max_thrust_g(carbon) == 175.0 and max_thrust_g(bamboo) == 165.0
    data = bamboo.model_dump(mode="json")
    data["core"]["battery"]["cells"] = 3  # the 2S table on 3S: thrust ~ V^2
    assert max_thrust_g(spec_mod.from_dict(data)) == pytest.approx(165.0 * (3 / 2) ** 2)
    data = carbon.model_dump(mode="json")
    data["motors"]["kv"] = 7500
    assert max_thrust_g(spec_mod.from_dict(data)) == 215.0


@pytest.mark.fe
def test_thrust_to_weight_below_the_requirement_fails(run_cli, tmp_path):
    import json

    import yaml

    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    code, out, _ = run_cli("check", ROOT / "params" / "carbon.yaml", "--json")
    f = json.loads(out)["flight"]
    assert code == 0 and set(f) >= {"thrust_to_weight", "hover_throttle", "hover_current_a", "hover_time_min"}
    assert f["thrust_to_weight"] > 2.0
    data["requirements"]["min_thrust_to_weight"] = 3.5
    p = tmp_path / "weak.yaml"
    p.write_text(yaml.safe_dump(data))
    code, out, _ = run_cli("check", p, "--json")
    res = json.loads(out)
    assert code == 1 and res["verdict"] == "FAIL"
    assert any("thrust-to-weight" in x and "min_thrust_to_weight" in x for x in res["problems"])


@pytest.mark.cad
@pytest.mark.fe
@pytest.mark.slicer
def test_a_build_with_a_clash_exits_1_naming_both_solids(run_cli, tmp_path, monkeypatch):
    """Bamboo with its plate on the holder (level_arms false, the tab link) and without its 2 mm
    spacer: the core links sit on the battery holder's top edges again. The build runs the clash check, writes clash.json and FAILs (exit 1) with a
    problem naming both solids. (Plates, slicing and renders are skipped: not what is tested.)"""
    import json

    import yaml

    from cogniframe.pipeline import steps

    keep = ("estimate", "part:{material}/{part}", "budget", "physics", "clash", "check")
    monkeypatch.setattr(steps, "STEPS", tuple(s for s in steps.STEPS if s.name in keep))
    data = yaml.safe_load((ROOT / "params" / "bamboo.yaml").read_text())
    data["core"]["spacer_thickness"] = 0
    data["frame"]["level_arms"] = False
    data["core"]["link"] = "tab"  # the pegs need level arms
    p = tmp_path / "nospacer.yaml"
    p.write_text(yaml.safe_dump(data))
    code, _, _ = run_cli("build", p, "-o", tmp_path / "out")
    assert code == 1
    check = json.loads((tmp_path / "out" / "check.json").read_text())
    clash = json.loads((tmp_path / "out" / "clash.json").read_text())
    assert check["verdict"] == "FAIL" and not clash["ok"]
    pairs = {frozenset((c["a"], c["b"])): c["volume_mm3"] for c in clash["clashes"]}
    for link in ("core_link_fl", "core_link_fr", "core_link_rr", "core_link_rl"):
        assert pairs[frozenset((link, "battery_holder"))] > 0.5
    assert any("core_link_fr" in x and "battery_holder" in x and "mm^3" in x for x in check["problems"])


@pytest.mark.cad
def test_zip_tie_slots_strap_slots_and_lead_exit_go_through():
    """Rays through the openings meet no material; rays beside them do (measured on the STLs)."""
    from cogniframe.export.mesh import ray_first_hit

    d = built_preset("carbon")
    mount, part = d.meshes["sensor_mount"], d.parts["sensor_mount"]
    slots = part.param("zip_slots")
    assert len(slots) == 4  # receiver + flow board (a pair), antenna (a pair)
    for x, y in slots:
        assert math.isinf(ray_first_hit(mount, [[x, y, 10.0]], [[0, 0, -1.0]])[0]), (x, y)
        assert ray_first_hit(mount, [[x, y + 3.0, 10.0]], [[0, 0, -1.0]])[0] == pytest.approx(10.0 - part.param("thickness"))
    # battery holder, in its world placement: strap slots across the mouth, lead notch over the mouth
    holder = next(b for b in _bodies(d) if b.name == "battery_holder")
    hm = holder.mesh.copy()
    hm.apply_transform(holder.transform)
    h = d.frame.core.holder
    ys, _, _, _ = d.parts["battery_holder"].param("strap_slot")
    zc = d.frame.core.battery.centre[2] + 0.5  # cavity centre (1 mm slack above the pack)
    y_slot = h.centre[1] + ys
    far = h.size[0]
    assert math.isinf(ray_first_hit(hm, [[-far, y_slot, zc]], [[1.0, 0, 0]])[0])  # through both walls and the mouth
    assert ray_first_hit(hm, [[-far, y_slot - 8.0, zc + 2.0]], [[1.0, 0, 0]])[0] == pytest.approx(far - h.size[0] / 2, abs=0.01)
    lw, y0 = d.parts["battery_holder"].param("lead_exit")
    y_notch = h.centre[1] + (y0 + h.size[1] / 2) / 2  # half way from the pack's front to the mouth
    skin = (h.size[2] - d.parts["battery_holder"].param("inner")[2]) / 2
    # down through the notch: the first material is the floor's top face; beside it, the top wall
    assert ray_first_hit(hm, [[0.0, y_notch, h.hi[2] + 5.0]], [[0, 0, -1.0]])[0] == pytest.approx(5.0 + h.size[2] - skin, abs=0.01)
    assert ray_first_hit(hm, [[lw / 2 + 2.0, y_notch, h.hi[2] + 5.0]], [[0, 0, -1.0]])[0] == pytest.approx(5.0, abs=0.01)


def test_vitamin_bom_rows_name_their_budget_lines():
    from cogniframe.vitamins import bom_rows

    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    rows = {bom: (qty, line) for bom, qty, line in bom_rows(spec, frame_mod.frame_of(spec))}
    motor = next(k for k in rows if k.startswith("brushless motor 1104 6000KV"))
    assert rows[motor] == (4, "motor 1104")
    assert rows["Raspberry Pi camera module v2"] == (1, "Raspberry Pi camera v2 + ribbon")
    assert any(k.startswith("LiPo 3S 650 mAh") and v == (1, "battery") for k, v in rows.items())


@pytest.mark.parametrize("tilt", [20.0, -15.0])
@pytest.mark.cad
def test_tilted_camera_mount_prints_without_support_and_carries_the_camera(tilt, tmp_path):
    """Tilted uprights still print as they sit (lean < 45 deg) and the camera board stays on the
    upright's front face: the board's back corners lie on the mount's surface (ray from behind)."""
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl, overhangs
    from cogniframe.vitamins import camera_vitamin, to_trimesh

    data = spec_mod.load(ROOT / "params" / "carbon.yaml").model_dump(mode="json")
    data["core"]["camera"]["tilt_deg"] = tilt
    s = spec_mod.from_dict(data)
    fr = frame_mod.frame_of(s)
    part = next(p for p in partlist.part_list(s, fr) if p.name == "front_camera_mount")
    (b,) = build_parts(s, fr, [part], tmp_path)
    m = load_stl(tmp_path / b.stl)
    assert m.is_watertight and m.body_count == 1 and m.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    assert overhangs(m)["fraction"] < 0.01
    # world placement of the mount vs the camera vitamin: touching, not overlapping
    from cogniframe.export.mesh import intersection_volume

    mw = m.copy()
    mw.apply_transform(part.placements[0].matrix() @ np.linalg.inv(b.print_from_local))
    cam = to_trimesh(camera_vitamin(s, fr))
    assert intersection_volume(mw, cam) < 0.5
    grown = cam.copy()
    grown.apply_translation(-0.3 * np.asarray(camera_vitamin(s, fr).view[1]))  # 0.3 mm back into the upright
    assert intersection_volume(mw, grown) > 10


@pytest.mark.cad
@pytest.mark.fe
def test_vitamins_are_items_of_the_report_3d_view():
    """Each vitamin is a `vitamin` item of the report's 3D view with its budget line's mass."""
    from cogniframe.report.renders import vitamin_viewer_items
    from cogniframe.vitamins import vitamins

    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    res = verdict.check(spec)
    items = vitamin_viewer_items(spec, res.design.frame, res.mass)
    vits = vitamins(spec, res.design.frame)
    assert [i.name for i in items] == [v.name for v in vits] and {i.kind for i in items} == {"vitamin"}
    by = {i.name: i for i in items}
    assert by["motor_fl"].mass_g == spec.motor.mass_g and by["motor_fl"].qty == 4
    assert by["battery"].mass_g == spec.core.battery.mass and by["battery"].colour == "#f2c71a"
    cam = trimesh.Trimesh(by["camera"].mesh.vertices, by["camera"].mesh.faces)
    assert cam.is_volume and cam.volume == pytest.approx(25 * 24 * 1.0 + 8.5 * 5.0 * 8.5, rel=1e-6)  # board + lens

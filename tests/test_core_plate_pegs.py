"""The core plate with the pegged core link (`core.link: pegs`): one ABS tube per peg (the peg's
6.8 mm bore, a 1.2 mm wall, as long as the peg) hanging under the plate, its top flush with the
plate's top; per link a bar under its tubes, a ribbed stem to its stack hole and a strip to the
centre (an X like the authors' plus-shaped MainBase); the plate printed upside down. The pegs
must go into the tubes (their axes one line), the frame must hang the plate so, the closed form
must be the CAD's volume, the stem must be as strong as the square plate's corner was, the part
must print, nothing may clash in either preset, and the presets with pegs must meet the paper's
masses (the spacer keeps only its pad on the two rear standoffs).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from presets import preset_spec

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe.errors import UserError
from cogniframe.frame import PEG_SNAP
from cogniframe.parts.peg_plan import peg_axes, pegged_plan

PRESETS = ("carbon", "bamboo")
R_BORE, WALL, PEG_LEN = 3.4, 1.2, 9.0  # the authors' MainBase bore and the connector's peg; three 0.4 mm lines


def _planned(name: str, **changes):
    spec = preset_spec(name, core__link="pegs", **changes)
    frame = frame_mod.frame_of(spec)
    parts = {p.name: p for p in partlist.part_list(spec, frame)}
    return spec, frame, parts


def _links(parts):
    return [p for p in parts.values() if dict(p.params).get("kind", p.name) == "core_link"]


def _placed(part, pl, p) -> np.ndarray:
    m = pl.matrix()
    return m[:3, :3] @ np.asarray(p, float) + m[:3, 3]


@pytest.mark.parametrize("preset", PRESETS)
def test_each_arm_rods_axis_carries_a_peg(preset):
    """`peg_axes` against the sockets themselves: one peg per column of the link's plan, and on
    each arm socket's axis (port + direction s) a peg from s = seat - peg_gap - peg_len to
    seat - peg_gap, radius peg_d / 2. To 1e-5 mm: the sockets are stored to 1e-6 (ports and unit
    directions, the latter over ~12 mm), and the plan stands both columns at the first's height."""
    _, _, parts = _planned(preset)
    for link in _links(parts):
        params = dict(link.params)
        axes = peg_axes(link.sockets, params)
        assert len(axes) == len(pegged_plan(link.sockets, params).columns) >= 2
        arms = [s for s in link.sockets if "arm" in s.rod]
        assert len(arms) == 2
        gap, length = float(params["peg_gap"]), float(params["peg_len"])
        for s in arms:
            p, d = np.asarray(s.port, float), np.asarray(s.direction, float)
            ax = min(axes, key=lambda a: float(np.linalg.norm(a.end - (p + d * (s.seat - gap - length)))))
            assert ax.end == pytest.approx(p + d * (s.seat - gap - length), abs=1e-5)
            assert ax.shoulder == pytest.approx(p + d * (s.seat - gap), abs=1e-5)
            assert ax.radius == pytest.approx(float(params["peg_d"]) / 2)
            assert abs(ax.radius - (s.bore / 2 + float(params["column_wall"]))) >= PEG_SNAP / 2  # a peg, not the column


@pytest.mark.parametrize("preset", PRESETS)
def test_one_tube_per_peg_coaxial_with_it(preset):
    """The plate carries pegs per link x 4 tubes; every placed link's every peg (its axis taken to
    the frame through the link copy's placement, then into the plate's frame) has a tube whose
    axis ends coincide with the peg's to 1e-6 mm and whose bore is the peg's diameter; the tubes
    are level with their tops flush with the plate's top: two per link, the arms' (the strut
    hangs on the link's arch)."""
    spec, frame, parts = _planned(preset)
    plate = parts["core_plate"]
    tubes = [tuple(np.asarray(p, float) for p in t) for t in plate.param("tubes")]
    links = _links(parts)
    per_link = {len(pegged_plan(link.sockets, dict(link.params)).columns) for link in links}
    assert len(per_link) == 1 and sum(len(link.placements) for link in links) == 4
    assert len(tubes) == per_link.pop() * 4
    assert plate.param("tube_bore") == pytest.approx(2 * R_BORE) and plate.param("tube_wall") == WALL
    centre = np.asarray(frame.core.plate.centre, float)
    left = list(tubes)
    for link in links:
        for pl in link.placements:
            for ax in peg_axes(link.sockets, dict(link.params)):
                e, s = _placed(link, pl, ax.end) - centre, _placed(link, pl, ax.shoulder) - centre
                i = int(np.argmin([np.linalg.norm(t[0] - e) + np.linalg.norm(t[1] - s) for t in left]))
                assert left[i][0] == pytest.approx(e, abs=1e-6) and left[i][1] == pytest.approx(s, abs=1e-6)
                left.pop(i)
    assert not left
    t = spec.core.plate_thickness
    assert len(tubes) == 2 * 4  # the arm pair's two per link
    for e, s in tubes:
        assert np.linalg.norm(s - e) == pytest.approx(PEG_LEN, abs=1e-6)
        assert e[2] == pytest.approx(s[2], abs=1e-6)
        top = e[2] + R_BORE + WALL
        assert top == pytest.approx(t / 2, abs=1e-6)  # the tube's top in the plate's top plane (the bed in print)


@pytest.mark.parametrize("preset", PRESETS)
def test_the_plate_hangs_higher_by_the_tubes_drop(preset):
    """With pegs the arms run below the plate's mid-plane by the tube radius 4.6 less half the plate
    (3.1 mm under a 3 mm plate, 2.6 under the carbon preset's 4 mm), and the plate's standoffs make
    that up to the whole millimetre: the hang is round(knee height + drop - the plate on the
    spacer), the standoff line in the BOM says so, and the core links' nodes (and the level knees)
    sit the drop under the plate's centre."""
    tab = frame_mod.frame_of(preset_spec(preset, core__link="tab"))
    spec, frame, parts = _planned(preset)
    drop = R_BORE + WALL - spec.core.plate_thickness / 2
    assert frame_mod.peg_drop(spec) == pytest.approx(drop)
    assert drop == pytest.approx({3.0: 3.1, 4.0: 2.6}[spec.core.plate_thickness])
    base = tab.core.plate.centre[2] - tab.core.hang  # the plate resting on the spacer
    spacer = spec.core.spacer_thickness
    z_knee = spec.frame.height * spec.frame.knee_height
    assert frame.core.hang == round(z_knee + drop - base)
    assert tab.core.hang == round(z_knee - base)  # the tab's arms at the plate's mid-plane: no drop
    assert frame.core.plate.centre[2] == pytest.approx(base + frame.core.hang)
    for k in frame_mod.CORNERS:
        assert frame.nodes[f"core_link_{k}"].pos[2] == pytest.approx(frame.core.plate.centre[2] - drop, abs=1e-9)
        assert frame.nodes[f"knee_{k}"].pos[2] == pytest.approx(frame.nodes[f"core_link_{k}"].pos[2], abs=1e-9)
    # the rear two on the spacer's bar, the front two on the holder, the spacer's 2 mm longer
    standoff = {h.item: h.qty for h in parts["core_plate"].hardware if "standoff, female-female" in h.item}
    assert sorted(standoff.values()) == [2, 2]
    assert any(f"x {frame.core.hang:g} mm" in i and "rear" in i for i in standoff)
    assert any(f"x {frame.core.hang + spacer:g} mm" in i and "front" in i for i in standoff)


def test_the_bom_drops_the_link_screws_and_the_plate_their_holes():
    """Pegs press in: no core-link screw anywhere in the hardware, and the plate keeps only the
    four stack holes (the tab link's four bolt holes go)."""
    _, _, parts = _planned("carbon")
    items = [h.item for p in parts.values() for h in p.hardware]
    assert not [i for i in items if "core link" in i]
    assert len(parts["core_plate"].param("holes")) == 4
    tab_spec = preset_spec("carbon", core__link="tab")
    tab = {p.name: p for p in partlist.part_list(tab_spec, frame_mod.frame_of(tab_spec))}
    assert [h.item for p in tab.values() for h in p.hardware if "core link to plate" in h.item]
    assert len(tab["core_plate"].param("holes")) == 8


def _signed_area(q) -> float:
    x, y = np.asarray(q, float).T
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _union(pieces):
    import manifold3d as m3

    out = None
    for q in pieces:
        cs = m3.CrossSection([[tuple(map(float, v)) for v in q]])
        out = cs if out is None else out + cs
    return out


@pytest.mark.parametrize("preset", PRESETS)
def test_closed_form_is_outline_ribs_and_tubes_by_hand(preset):
    """The estimate by hand: the outline's union (manifold3d's 2-D boolean) 3 mm thick less four
    2.4 mm stack holes; four ribs 7 x 3.5 mm times their length; each tube's ring above the slab:
    9 (pi 4.6^2 - seg - pi 3.4^2), seg the circle below a chord h under its centre: 1.6 mm for a
    tube flush with the plate's top, more for the strut's, sunk into its slab."""
    spec, _, parts = _planned(preset)
    p = parts["core_plate"]
    t = spec.core.plate_thickness
    r_o = R_BORE + WALL
    assert len(p.param("outline")) == 4 * 4 and len(p.param("ribs")) == 4
    union = _union(p.param("outline"))
    assert len(union.to_polygons()) == 1  # one piece, no enclosed hole
    by_hand = union.area() * t - 4 * math.pi * 1.2**2 * t
    for a, b in p.param("ribs"):
        by_hand += 7.0 * 3.5 * float(np.linalg.norm(np.subtract(b, a)))
    for e, _ in p.param("tubes"):
        h = (t / 2 - e[2]) - t  # the axis's height in print (upside down) over the slab's top
        seg = r_o**2 * math.acos(h / r_o) - h * math.sqrt(r_o**2 - h * h)
        by_hand += PEG_LEN * (math.pi * r_o**2 - seg - math.pi * R_BORE**2)
    # 1e-8: the 2-D boolean rounds to its integer grid, union by union (1e-5 mm^2 apart)
    assert p.estimate.volume == pytest.approx(by_hand, rel=1e-8)


@pytest.mark.parametrize("preset", PRESETS)
def test_every_tube_stands_on_the_slab_and_every_hole_in_it(preset):
    """Each tube's footprint (its axis 4.6 mm either side) lies inside the outline (a bar under the
    whole tube: it prints on it, and its load goes into it); each stack hole has at least 2.3 mm of
    slab round its 2.4 mm clearance (points on a 3.5 mm circle round it inside the outline), so a
    4 mm standoff seats on it; the outline keeps clear of the sliver rule everywhere (no strip
    under 4 mm: ten 0.4 mm lines)."""
    import manifold3d as m3

    _, _, parts = _planned(preset)
    p = parts["core_plate"]
    union = _union(p.param("outline"))
    for e, s in p.param("tubes"):
        e, s = np.asarray(e, float)[:2], np.asarray(s, float)[:2]
        u = (s - e) / np.linalg.norm(s - e)
        n = np.array([-u[1], u[0]]) * (R_BORE + WALL - 1e-3)
        foot = m3.CrossSection([[tuple(q) for q in (e - n, s - n, s + n, e + n)]])
        assert (foot - union).area() < 1e-6
    for x, y in p.param("holes"):
        ring = m3.CrossSection.circle(3.5, 64).translate((x, y))
        assert (ring - union).area() < 1e-6
    assert union.offset(-2.0 + 1e-3, m3.JoinType.Miter).offset(2.0 - 1e-3, m3.JoinType.Miter).area() == pytest.approx(union.area(), rel=0.02)


@pytest.mark.parametrize("preset", PRESETS)
def test_each_stem_is_as_strong_as_the_square_plates_corner(preset):
    """A link's pull bends its stem as a cantilever off the stack standoffs (analysis/load_cases.py
    `core_plate_mpa_per_n`). The rib makes the stem 7 mm wide and 3 + 3.5 = 6.5 mm deep from 2.5 mm
    past the stack hole: bending modulus 7 x 6.5^2 / 6 = 49.3 mm^3, more than the 40 mm square's
    corner across the hole had (2 sqrt 2 x 10 = 28.3 mm of 3 mm plate: 42.4). Where the rib stops,
    1 mm before the tubes, the 20 mm gusset (20 x 3^2 / 6 = 30 mm^3) carries a shorter lever: its
    stress (lever / modulus, from the link's node) under the rib's."""
    spec, frame, parts = _planned(preset)
    p = parts["core_plate"]
    assert p.param("rib_width") == 7.0 and p.param("rib_depth") == 3.5
    z_rib = 7.0 * (3.0 + 3.5) ** 2 / 6
    assert z_rib == pytest.approx(49.29, abs=0.01)
    assert z_rib > 2 * math.sqrt(2) * 10.0 * 3.0**2 / 6
    for a, b in p.param("ribs"):
        a, b = np.asarray(a, float), np.asarray(b, float)
        hole = min((np.asarray(h, float) for h in p.param("holes")), key=lambda h: np.linalg.norm(h - a))
        assert np.linalg.norm(a - hole) == pytest.approx(2.5, abs=1e-6)
        k = next(k for k in frame_mod.CORNERS if np.sign(frame.nodes[f"core_link_{k}"].pos[0]) == np.sign(a[0])
                 and np.sign(frame.nodes[f"core_link_{k}"].pos[1]) == np.sign(a[1]))
        node = np.asarray(frame.nodes[f"core_link_{k}"].pos[:2]) - np.asarray(frame.core.plate.centre[:2])
        u = (b - a) / np.linalg.norm(b - a)
        at_rib = float((node - a) @ u) / z_rib
        at_gusset = float((node - b) @ u) / (20.0 * 3.0**2 / 6)
        assert at_gusset < at_rib
        # the rib stops 1 mm before the nearest tube footprint (no face of it on a tube's)
        feet = []
        for e, s in p.param("tubes"):
            e, s = np.asarray(e, float)[:2], np.asarray(s, float)[:2]
            if np.sign(e[0]) == np.sign(a[0]) and np.sign(e[1]) == np.sign(a[1]):
                v = (s - e) / np.linalg.norm(s - e)
                n = np.array([-v[1], v[0]]) * (R_BORE + WALL)
                feet += [e - n, e + n, s - n, s + n]
        assert min(float((f - b) @ u) for f in feet) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.cad
@pytest.mark.fe
def test_the_pegged_presets_meet_the_papers_masses():
    """With core.link: pegs the carbon preset's central ABS parts are within 10 % of the paper's
    25 g and its all-up mass within 5 % of 236 g; bamboo's all-up at most 245 g (issue: room for a
    heavier pack). Estimates, as `check` gives them."""
    from cogniframe.analysis import verdict

    carbon = verdict.check(preset_spec("carbon", core__link="pegs")).mass
    assert carbon.by_material["abs"] == pytest.approx(25, rel=0.10)
    assert carbon.total_g == pytest.approx(236, rel=0.05)
    bamboo = verdict.check(preset_spec("bamboo", core__link="pegs")).mass
    assert bamboo.total_g <= 245.0


@pytest.mark.parametrize("preset", PRESETS)
def test_the_spacer_keeps_only_its_pad_on_the_rear_standoffs(preset):
    """With pegs (level arms, no link bolt) the spacer carries only its pad (carbon: the flow board
    behind the holder, on a 10 mm neck; bamboo: the receiver, right behind the bar, on the
    holder): one 7 mm bar under the two rear stack standoffs, 3.5 mm past each hole, no link holes
    or nut traps; its closed form the bar, the neck between bar and pad and the pad, less two
    2.4 mm holes and four 3.2 x 1.8 mm zip slots, 2 mm thick. The tab keeps its X with the links'
    holes."""
    spec, frame, parts = _planned(preset)
    m = parts["sensor_mount" if spec.core.flow_sensor else "core_spacer"]
    assert m.param("link_holes") == () and m.param("stack_holes") == ((-10.0, -10.0), (10.0, -10.0))
    pieces = m.param("pieces")
    assert len(pieces) == (3 if spec.core.flow_sensor else 2)  # bar, (neck,) pad
    xs, ys = [x for x, _ in pieces[-1]], [y for _, y in pieces[-1]]
    pad_half, pad_y0, pad_y1 = max(xs), max(ys), min(ys)
    if not spec.core.flow_sensor:
        assert (pad_half, pad_y0, pad_y1) == (10.0, -13.5, -24.0)
    area = 27.0 * 7.0 + 10.0 * (-10.0 - 3.5 - pad_y0) + 2 * pad_half * (pad_y0 - pad_y1)
    openings = 2 * math.pi / 4 * 2.4**2 + 4 * 3.2 * 1.8
    assert _union(pieces).area() == pytest.approx(area, rel=1e-9)
    assert m.estimate.volume == pytest.approx((area - openings) * spec.core.spacer_thickness, rel=1e-9)
    tab_spec = preset_spec(preset, core__link="tab")
    tab = {p.name: p for p in partlist.part_list(tab_spec, frame_mod.frame_of(tab_spec))}
    t = tab["sensor_mount" if spec.core.flow_sensor else "core_spacer"]
    assert len(t.param("link_holes")) == 4 and len(t.param("stack_holes")) == 4


def test_climbing_arms_refuse_the_pegs_naming_the_key():
    """The tubes lie on the bed under the upside-down plate, level with the arms: with climbing
    arms the params are refused, naming core.link and the fix."""
    with pytest.raises(UserError) as e:
        preset_spec("carbon", core__link="pegs", frame__level_arms=False)
    msg = str(e.value)
    assert "core.link" in msg and "frame.level_arms: true" in msg


def _zmax(shape) -> float:
    """The solid's exact top (OCC's optimal box on its surfaces; the plain box adds a tolerance)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape.wrapped, box, False, False)
    return box.CornerMax().Z()


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_plate_with_tubes_is_one_watertight_solid_printed_upside_down(preset, tmp_path):
    """The CAD: one watertight solid, its volume the closed form's within test_parts' 0.5 % (the
    BRep's volume; the STL's faceting within it too), lying on its top (the plate's top plane, the
    webs and the tubes' tops on the bed: z = 0 over 3 mm of plate), no unsupported overhang, and
    every tube's bore where its peg goes: points on the peg's axis and 0.05 mm inside its radius
    are outside the solid, 0.05 mm outside its radius inside it."""
    from cogniframe.export.mesh import contains, flat_contact_ratio, overhangs, write_stl
    from cogniframe.families import registry

    spec, _, parts = _planned(preset)
    p = parts["core_plate"]
    built = registry.solid(p)
    mesh = write_stl(built.shape, tmp_path / "core_plate.stl", name="core_plate")  # raises unless watertight
    assert mesh.is_watertight and mesh.body_count == 1
    assert built.shape.Volume() == pytest.approx(p.estimate.volume, rel=0.005)
    assert mesh.volume == pytest.approx(p.estimate.volume, rel=0.005)
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    t = spec.core.plate_thickness
    assert _zmax(built.shape) == pytest.approx(max(t / 2 - e[2] for e, _ in p.param("tubes")) + R_BORE + WALL, abs=1e-3)
    assert flat_contact_ratio(mesh) >= 0.20
    oh = overhangs(mesh)
    assert oh["area"] < 1.0 and oh["fraction"] < 0.01, oh
    m = built.print_from_local
    assert m[2, 2] == -1.0  # upside down
    for e, s in p.param("tubes"):
        pe, ps = (m[:3, :3] @ np.asarray(q, float) + m[:3, 3] for q in (e, s))
        d = (ps - pe) / np.linalg.norm(ps - pe)
        n1 = np.cross(d, [0.0, 0.0, 1.0])
        n1 /= np.linalg.norm(n1)
        n2 = np.cross(d, n1)
        probes_in, probes_bore = [], []
        for f in (0.1, 0.5, 0.9):
            c = pe + (ps - pe) * f
            probes_bore.append(c)
            for ang in np.linspace(0, 2 * math.pi, 8, endpoint=False):
                radial = math.cos(ang) * n1 + math.sin(ang) * n2
                probes_bore.append(c + radial * (R_BORE - 0.05))
                probes_in.append(c + radial * (R_BORE + 0.05))
        assert not contains(mesh, probes_bore).any()
        assert contains(mesh, probes_in).all()


@pytest.mark.process
def test_build_with_pegs_gives_a_watertight_plate_and_no_clash(tmp_path):
    """`cogniframe build` of carbon with core.link: pegs: the core plate's STL is one watertight
    volume with the eight tubes' mass in it, and the build's clash check (every part copy, rod
    and vitamin; the pegs in their tubes) finds nothing."""
    import json
    import subprocess
    import sys

    import trimesh
    import yaml

    from presets import preset_doc
    from conftest import ROOT

    doc = preset_doc("carbon", core__link="pegs")
    params = tmp_path / "carbon-pegs.yaml"
    params.write_text(yaml.safe_dump(doc), encoding="utf-8")
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "cogniframe", "build", str(params), "-o", str(out), "--no-server"],
                       cwd=ROOT, capture_output=True, text=True, timeout=1200,
                       env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert (out / "clash.json").exists(), r.stdout[-2000:] + r.stderr[-2000:]
    mesh = trimesh.load(out / "stl" / "abs" / "core_plate.stl")  # the STLs sorted by material
    assert mesh.is_watertight and mesh.body_count == 1
    spec, _, parts = _planned("carbon")
    assert mesh.volume == pytest.approx(parts["core_plate"].estimate.volume, rel=0.005)
    clash = json.loads((out / "clash.json").read_text())
    assert clash["ok"] and clash["clashes"] == []
    assert clash["pairs_tested"] > 0


@pytest.mark.cad
def test_bamboo_with_pegs_has_no_clash(tmp_path):
    """The clash check over bamboo's built parts with core.link: pegs (no analysis): 0 clashes,
    the pegs in their tubes included."""
    from cogniframe.export.assembly import check_clashes
    from cogniframe.export.part_files import build_parts

    spec, frame, parts = _planned("bamboo")
    plist = list(parts.values())
    built = build_parts(spec, frame, plist, tmp_path)
    res = check_clashes(spec, frame, plist, built, tmp_path)
    assert res.ok and res.clashes == (), res.messages()


def test_assembly_steps_press_the_pegs_in_rather_than_bolt():
    """The builder is told to press each link's pegs into the plate's tubes, with no screw, and
    the tab link's bolting text is gone (it stays for the tab)."""
    from cogniframe import design as design_mod
    from cogniframe.report.assembly_steps import assembly_steps

    core = next(s for s in assembly_steps(design_mod.design(preset_spec("carbon", core__link="pegs"))) if s.title == "Core")
    assert "pegs all the way into the pair of tubes" in core.text and "screw down through the link tab" not in core.text
    assert "pressed in" in core.glue
    tab = next(s for s in assembly_steps(design_mod.design(preset_spec("carbon", core__link="tab"))) if s.title == "Core")
    assert "screw down through the link tab" in tab.text


def _random_pegged_parts(rnd):
    """tests/design_space.py's next random edit with core.link: pegs and level arms (the plate's
    tubes lie level with the arms): its parts by name, or None when the params are refused."""
    import design_space
    from cogniframe import spec as spec_mod

    doc = design_space.random_design(rnd, "edit")
    doc["core"]["link"] = "pegs"
    doc["frame"]["level_arms"] = True
    try:
        spec = spec_mod.from_dict(doc, "random.yaml")
        return {p.name: p for p in partlist.part_list(spec, frame_mod.frame_of(spec))}
    except UserError:
        return None


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.cad
def test_random_designs_with_pegs_give_one_watertight_plate(seed, tmp_path):
    """tests/design_space.py's random edits (other boxes, rectangles with the arms off the
    diagonal, other plates and motors) with core.link: pegs and level arms: the first two designs
    the params accept each give a plate with pegs per link x 4 tubes, one outline piece and four
    ribs, that is one watertight solid, its closed form within 0.5 % of the CAD, printable without
    supports."""
    import random

    from cogniframe.export.mesh import overhangs, write_stl
    from cogniframe.families import registry

    rnd = random.Random(700 + seed)
    done = 0
    for _ in range(100):
        parts = _random_pegged_parts(rnd)
        if parts is None:
            continue
        p = parts["core_plate"]
        link = parts["core_link"]
        assert len(p.param("tubes")) == 4 * len(pegged_plan(link.sockets, dict(link.params)).columns)
        # one outer loop: slivers the bars, stems and gussets enclose where they nearly meet are filled
        # (`core_plate.outline_union`; 700's first design leaves four)
        outer = [q for q in _union(p.param("outline")).to_polygons() if _signed_area(q) > 0]
        assert len(outer) == 1 and len(p.param("ribs")) == 4
        built = registry.solid(p)
        mesh = write_stl(built.shape, tmp_path / f"plate{done}.stl", name="core_plate")  # raises unless watertight
        assert mesh.body_count == 1 and mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
        assert p.estimate.volume == pytest.approx(built.shape.Volume(), rel=0.005)
        assert overhangs(mesh)["area"] < 1.0
        done += 1
        if done == 2:
            break
    assert done == 2, "fewer than two accepted designs in 100 draws"


def test_random_pegged_designs_plan_or_are_refused_never_an_internal_error():
    """tests/design_space.py's random edits with core.link: pegs (level arms), plans only: each
    design gives a part list whose plate has a tube per peg, or is refused with a UserError;
    nothing else (a deep joints.seat once left the strut's tube off the plate as a RuntimeError)."""
    import random

    rnd = random.Random(11)
    planned = refused = 0
    for _ in range(60):
        parts = _random_pegged_parts(rnd)
        if parts is None:
            refused += 1
            continue
        link = parts["core_link"]
        assert len(parts["core_plate"].param("tubes")) == 4 * len(pegged_plan(link.sockets, dict(link.params)).columns)
        planned += 1
    assert planned >= 10 and refused >= 1, (planned, refused)

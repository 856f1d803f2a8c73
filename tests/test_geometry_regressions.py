"""Joint geometry that used to fall apart or not build at all (parts/joint_solid.py), each case as reported.

* frame.knee_inset 0 (straight sides): the knee's upper and lower legs are one vertical line, their
  cross product is zero, and the print orientation was NaN ("no parallel arm sockets", exit 3).
* 2.3 mm rods in a 91-92 mm tall frame: the knee's rigid lower leg leans back from the arms
  (107 deg) and its sleeve, 2.4 mm in radius, no longer reached the arm block ("joint geometry
  produced 2 solids instead of 1", exit 3); behind it, the core link's tab top sat exactly on the
  strut sleeve's top (bore 2.4 mm = M2 clearance) and its STL was not watertight.
* rectangles: rounding of the stored sockets left the two arm sleeves ~1e-5 mm apart (zero-area
  faces the FE mesher rejected), and OCC's many-piece fuse left a 0 mm^3 solid on a bottom corner.

Found by sweeping the schema (random designs and every geometry key across its bounds, one and two
at a time, each part built and written as an STL):

* a large joints.seat (d22: 174.1 x 155.4 x 111.6 box, seat 5.98): the knee's lower leg leaves
  the knee square to the arms and the seat puts the arm block's back face beyond its sleeve;
  `rigid_leg_start` answered a start 51 mm behind the knee (its test looked at one side of the
  block only) and the knee still printed in two. No start can join them: a hub does.
* a small seat for the walls (joints.seat 0, or joints.wall 2.9 mm and more with the 3 mm seat):
  the hinge slot cut off the end of the upper leg that the hinge web holds; the knee's seat is now
  raised until the hinge has room (frame._hinge_seat).
* a flat top level with a round sleeve top (the knee's hinge web, the core link's hub): OCC's
  mesher left that face out of the STL now and then (bamboo, joints.fit_clearance 0.22).
* the corner's hub had the sleeves' own radius with its axis through theirs, and every sleeve
  started at that point (degenerate equal-radius intersections): OCC's fuse of all pieces at once
  dropped most of a bottom corner's strut sleeve and still gave one watertight solid (8 of 249
  random designs), or gave 0 solids.
* the motor mount: two clip sleeves 2e-6 mm out of line (stored rods, a rectangle) fused into
  slivers where thick walls overlap them; a level arm got a bare cylinder 0.5 mm above the seat;
  a bolt pattern as wide as the seat cut its corners off; a seat only as wide as the clips (thin
  rods, a wide arm pair) had its sides tangent to them; carbon with 1.45 mm walls (the studio's
  test edit) came out of OCC's exact cut as two solids, the second a phantom piece of a clip.
* the camera mount: a thick core plate brings the link bolts in until the base's two corner cuts
  meet in front of the upright and cut it off.
* the knee's STL at many carbon heights (107.14; 5 of 21 heights from 121.85 to 122.85 mm): a
  zero-area sliver closing a T-junction of OCC's mesh was dropped and left a crack (a build failed
  with MeshError, the studio never showed a view). export.mesh now splits the face across it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from presets import preset_doc

ROOT = Path(__file__).resolve().parents[1]


def _variant(base: str, **changes) -> spec_mod.Spec:
    """A preset with keys changed: `joints__seat=6` (`joints__fit_clearance__tpu_95a` one level deeper)."""
    data = preset_doc(base, **changes)
    data["name"] = f"{base}-variant"
    return spec_mod.from_dict(data)


def _parts(spec, names):
    return [p for p in design_mod.design(spec).parts if p.name in names]


def _one_watertight_solid(part):
    """The part builds as one valid solid and its STL, written and read back, is closed (the
    build's own check, export.mesh.write_stl)."""
    import tempfile

    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry

    built = registry.solid(part)  # the builders raise unless it is one solid
    assert built.shape.isValid() and len(built.shape.Solids()) == 1, part.name
    with tempfile.TemporaryDirectory() as tmp:
        mesh = write_stl(built.shape, Path(tmp) / "part.stl", name=part.name)  # raises unless watertight
    assert mesh.body_count == 1, part.name
    return built


def _joints(spec, names=None):
    return [p for p in design_mod.design(spec).parts if p.family == "joint" and (names is None or p.name in names)]


# -- straight sides ----------------------------------------------------------------------------

def test_straight_sides_have_a_finite_print_orientation():
    """Pure numpy: the knee's lateral axis is the legs' and arms' plane normal, not 0/0."""
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import map_sockets, split_arms

    (knee,) = _joints(_variant("carbon", frame__knee_inset=0), ["knee"])
    m = print_from_local(knee)
    assert np.isfinite(m).all() and np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3))
    socks = map_sockets(knee, m)
    arms, legs = split_arms(socks)
    assert len(arms) == 2 and len(legs) == 2
    assert max(abs(s.direction[2]) for s in socks) < 1e-9  # every socket parallel to the bed


def test_straight_sides_check_with_closed_form_joints(run_cli, tmp_path):
    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text(encoding="utf-8"))
    data["frame"]["knee_inset"] = 0
    data["model"]["stiffness_model"] = "analytic"
    data["core"]["link"] = "tab"  # the closed forms' link
    data["name"] = "straight"
    path = tmp_path / "straight.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    code, _, err = run_cli("check", path, "--json")
    assert code in (0, 1), err


@pytest.mark.parametrize("base", ["carbon", "bamboo"])
@pytest.mark.cad
def test_straight_sides_build_every_joint_as_one_solid(base):
    from cogniframe.families import registry

    for part in _joints(_variant(base, frame__knee_inset=0)):
        built = registry.solid(part)  # finish() raises unless it is one solid
        assert built.shape.isValid() and built.shape.Volume() > 100, part.name


# -- thin rods, short frame ----------------------------------------------------------------------

@pytest.mark.parametrize("base", ["carbon", "bamboo"])
@pytest.mark.parametrize("height", [91, 92])
@pytest.mark.cad
def test_thin_rods_in_a_short_frame_keep_the_knee_in_one_piece(base, height):
    from cogniframe.families import registry

    (knee,) = _joints(_variant(base, rods__diameter=2.3, frame__height=height), ["knee"])
    built = registry.solid(knee)
    assert built.shape.isValid() and built.shape.Volume() > 100


@pytest.mark.parametrize("base, height", [("carbon", 91), ("bamboo", 91.5)])
@pytest.mark.cad
def test_thin_rods_core_links_mesh_watertight(base, height):
    """With 2.3 mm rods the bore (2.4 mm) equals the M2 clearance, so the core link's tab top met the
    strut sleeve's top exactly and the STL of one of the two links had open edges (build: MeshError)."""
    from cogniframe.export.mesh import tessellate
    from cogniframe.families import registry

    links = _joints(_variant(base, rods__diameter=2.3, frame__height=height), ["core_link", "core_link_mirrored"])
    assert len(links) == 2
    for part in links:
        mesh = tessellate(registry.solid(part).shape)
        assert mesh.is_watertight and mesh.volume > 0, part.name


def _arm_and_rigid_leg(knee):
    """(arm socket, rigid leg socket, sleeve radius, the arm block's back) of a knee, in print."""
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import map_sockets, split_arms

    arms, legs = split_arms(map_sockets(knee, print_from_local(knee)))
    a = arms[0]
    rigid = max(legs, key=lambda s: float(s.direction @ a.direction))
    return a, rigid, a.bore / 2 + knee.wall, a.seat - knee.wall


def test_rigid_leg_reaches_into_the_arm_block():
    """Pure numpy: where the rigid leg's sleeve joins the arm bridge (its start moved back from
    seat - wall far enough; the presets' 25 mm knees), its inner back corner lies at least JOIN
    inside the bridge's footprint; where no start can (2.3 mm rods in a 91 mm frame), a hub joins it."""
    from cogniframe.parts.joint_plan import JOIN, horizontal, rigid_leg_start

    starts = []
    for spec in (_variant("carbon", rods__diameter=2.3, frame__height=91),
                 spec_mod.load(ROOT / "params" / "carbon.yaml"), spec_mod.load(ROOT / "params" / "bamboo.yaml")):
        (knee,) = _joints(spec, ["knee"])
        a, rigid, r, s_back = _arm_and_rigid_leg(knee)
        t = rigid_leg_start(a, rigid, r, s_back, knee.wall)
        starts.append(t)
        if t is None:
            continue
        assert t < rigid.seat - knee.wall  # moved back to reach the bridge
        dx, u = horizontal(a.direction), horizontal(rigid.direction)
        lat = np.array([-dx[1], dx[0], 0.0])
        n = np.array([-u[1], u[0], 0.0])
        n = n if n @ dx >= 0 else -n
        corner = (rigid.port - a.port) * [1, 1, 0] + u * t + n * r
        assert corner @ dx - s_back >= JOIN - 1e-9
        assert r - abs(corner @ lat) >= JOIN - 1e-9
    assert starts[0] is None and None not in starts[1:]


# -- rectangles ---------------------------------------------------------------------------------

@pytest.mark.parametrize("box", [(212, 210), (240, 180)])
@pytest.mark.cad
def test_rectangle_joints_have_no_sliver_faces(box):
    """Every joint of a near-square and of a clearly rectangular box is one valid solid with no
    face under 1e-4 mm^2 (the arm sleeves 1e-5 mm apart gave faces of 1e-8 mm^2 and 0 mm^2, and
    gmsh: 'Invalid boundary mesh (overlapping facets)')."""
    from cogniframe.families import registry

    width, depth = box
    for part in _joints(_variant("carbon", frame__width=width, frame__depth=depth)):
        shape = registry.solid(part).shape
        assert shape.isValid(), part.name
        assert min(f.Area() for f in shape.Faces()) > 1e-4, part.name


# -- what the schema sweep found ------------------------------------------------------------------

# d22 (tools' random designs): a small, tall box and a 5.98 mm seat
D22 = {"frame__width": 174.1, "frame__depth": 155.4, "frame__height": 111.6, "joints__seat": 5.979,
       "motors__radius": 60.7, "motors__prop_diameter": 56.4}


def test_a_large_seat_joins_the_lower_leg_by_a_hub():
    """Pure numpy: with the d22 seat no start of the lower leg's sleeve reaches the arm block
    (`rigid_leg_start` is None, where it used to answer 51 mm behind the knee), and the hub that
    joins them overlaps both and stays clear of the hinge web and its slots."""
    from cogniframe.parts.joint_plan import HINGE_GAP, convex_hull, footprint_rect, knee_hinge, knee_hub, rigid_leg_start

    for knee in _joints(_variant("carbon", **D22), ["knee", "knee_mirrored"]):
        a, rigid, r, s_back = _arm_and_rigid_leg(knee)
        assert rigid_leg_start(a, rigid, r, s_back, knee.wall) is None, knee.name
        web = knee_hinge(knee)
        hub = knee_hub(a, rigid, r, s_back, knee.wall, web)
        # it overlaps the block's back and the leg's back face (their hull is what it is cut from)
        block = convex_hull(np.array(footprint_rect(a, s_back, s_back + 1.0, r)))
        leg = footprint_rect(rigid, rigid.seat - knee.wall, rigid.seat - knee.wall + 1.0, r)
        inside = [p for p in np.array(block) if _in_polygon(p, hub)]
        assert inside, knee.name
        assert any(_in_polygon(p, hub) for p in np.array(leg)), knee.name
        # and keeps the web and the slot either side of it free
        side = (hub - web.start) @ web.normal
        assert np.all(side >= web.thickness / 2 + HINGE_GAP - 1e-9) or np.all(side <= -(web.thickness / 2 + HINGE_GAP) + 1e-9)


def _in_polygon(p, poly) -> bool:
    """Point in a convex polygon (either winding), boundary included."""
    poly = np.asarray(poly)
    def cross(u, v) -> float:
        return float(u[0] * v[1] - u[1] * v[0])

    sides = [cross(poly[(i + 1) % len(poly)] - poly[i], p - poly[i]) for i in range(len(poly))]
    return all(c >= -1e-9 for c in sides) or all(c <= 1e-9 for c in sides)


@pytest.mark.cad
def test_d22_knees_build_in_one_piece():
    """The reported case: `registry.solid` raised "joint geometry produced 2 solids instead of 1"
    for knee and knee_mirrored."""
    for knee in _parts(_variant("carbon", **D22), ["knee", "knee_mirrored"]):
        built = _one_watertight_solid(knee)
        assert built.shape.Volume() > 1000


@pytest.mark.parametrize("base", ["carbon", "bamboo"])
@pytest.mark.parametrize("change", [{"joints__seat": 0.0}, {"joints__seat": 1.0}, {"joints__wall": 2.88},
                                    {"joints__wall": 6.0}, {}])
def test_knee_seat_leaves_the_hinge_room(base, change):
    """Pure numpy: the hinged leg's back-face centre lies at least two slots (2 x HINGE_GAP)
    behind the arm block's back face: the web crosses its slot and as much again. The presets'
    3 mm seat already does and is kept."""
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import HINGE_GAP, horizontal, map_sockets, split_arms

    (knee,) = _joints(_variant(base, **change), ["knee"])
    socks = map_sockets(knee, print_from_local(knee))
    arms, legs = split_arms(socks)
    a = arms[0]
    hinged = min(legs, key=lambda s: float(s.direction @ a.direction))
    c = hinged.at(hinged.seat - knee.wall)
    behind = (a.seat - knee.wall) - float((c - a.port) @ horizontal(a.direction))
    assert behind >= 2 * HINGE_GAP - 0.01  # the seat is kept to 0.01 mm
    if not change:
        assert knee.sockets[0].seat == 3.0


@pytest.mark.parametrize("base", ["carbon", "bamboo"])
@pytest.mark.parametrize("change", [{"joints__seat": 0.0}, {"joints__wall": 2.88}, {"joints__wall": 6.0},
                                    {"joints__seat": 12.0}, {"rods__diameter": 1.0}])
@pytest.mark.cad
def test_knees_build_across_seats_and_walls(base, change):
    for knee in _parts(_variant(base, **change), ["knee"]):
        _one_watertight_solid(knee)


@pytest.mark.parametrize("change", [{"joints__fit_clearance__tpu_95a": v} for v in (0.12, 0.22, 0.38, 0.68, 0.76)]
                         + [{"joints__wall": 5.48}])
@pytest.mark.cad
def test_core_link_hub_top_clears_the_strut_sleeve(change):
    """The hub's top was level with the strut sleeve's round top (and, with 5.48 mm walls, 0.03 mm
    above the upper arm's axis): one of the two links' STL had a hole where the top face was."""
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import TAB_CLEAR, map_sockets

    for link in _parts(_variant("bamboo", core__link="tab", **change), ["core_link", "core_link_mirrored"]):
        built = _one_watertight_solid(link)
        socks = map_sockets(link, print_from_local(link))
        r = socks[0].bore / 2 + link.wall
        top = built.shape.BoundingBox().zmax
        hub_top = max(f.Center().z for f in built.shape.Faces() if f.geomType() == "PLANE" and f.normalAt().z > 0.99
                      and f.Center().z < top - 1e-6)
        for s in socks:
            for level in (s.port[2], s.port[2] + r):
                assert abs(hub_top - level) >= TAB_CLEAR - 1e-6, (link.name, hub_top, level)


@pytest.mark.cad
def test_knee_web_top_clears_the_legs_top():
    """carbon in a 153 x 190.6 x 168.2 box: the web's top, level with the upper leg's round top,
    went missing from the knee's STL."""
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import TAB_CLEAR, knee_hinge, map_sockets

    spec = _variant("carbon", frame__width=153.0, frame__depth=190.6, frame__height=168.2, motors__radius=59.7,
                    motors__prop_diameter=55.5, core__link="tab")  # the pegs refuse a strut this steep
    for knee in _parts(spec, ["knee", "knee_mirrored"]):
        _one_watertight_solid(knee)
        socks = map_sockets(knee, print_from_local(knee))
        r = socks[0].bore / 2 + knee.wall
        web = knee_hinge(knee)
        assert all(abs(web.height - z) >= TAB_CLEAR - 1e-9 for s in socks for z in (s.port[2], s.port[2] + r))


@pytest.mark.parametrize("base, change", [
    # a rectangle and thick walls: the clips overlap, their stored rods 2e-6 mm out of line
    ("carbon", {"frame__width": 242.8, "frame__depth": 188.5, "frame__height": 143.8, "joints__wall": 5.767,
                "core__spacer_thickness": 6.064, "motors__radius": 73.6, "motors__prop_diameter": 68.4}),
    ("carbon", {"frame__width": 242.8, "frame__depth": 188.5, "frame__height": 143.8, "joints__wall": 5.5,
                "motors__radius": 73.6, "motors__prop_diameter": 68.4}),
    ("carbon", {"frame__arm_spacing": 26.4, "rods__diameter": 1.0}),  # the seat's sides were tangent to the clips
    ("bamboo", {"frame__knee_height": 0.38}),  # the arm is level: no web under a bare cylinder
    ("bamboo", {"motors__bolt_spacing": 19.992}),  # the bolt holes cut the seat's corners off
    ("bamboo", {"motors__bolt_spacing": 40.0}),
    ("carbon", {"frame__arm_spacing": 25.0}),  # the authors' spacing: all four holes
    ("carbon", {"motors__model": "1505", "frame__arm_spacing": 25.0}),  # 12 mm holes across the shaft
    ("carbon", {"joints__wall": 1.45}),  # OCC's exact cut gave the mount and a phantom 210 mm^3 solid
    ("bamboo", {"frame__knee_height": 0.38, "frame__arm_spacing": 25.0}),  # level arms, the authors' spacing
    ("carbon", {"frame__arm_spacing": 30.0, "joints__wall": 3.0}),  # long bridges, thick sleeves
    ("carbon", {"frame__arm_spacing": 15.0, "joints__socket_depth": 16.0}),  # sleeves longer than the seat
])
@pytest.mark.cad
def test_motor_mount_builds(base, change):
    from cogniframe.families.motor_mount import sleeve_length

    spec = _variant(base, **change)
    (mount,) = _parts(spec, ["motor_mount"])
    _one_watertight_solid(mount)
    seat = float(mount.param("seat_d"))
    # the seat carries the motor's bell and every screw head's seat with two extrusion lines outside it
    reach = max(math.hypot(x, y) for x, y in mount.param("holes"))
    assert seat >= spec.motor.bell_d - 1e-9
    assert seat >= 2 * (reach + float(mount.param("counterbore_d")) / 2 + 2 * spec.printer.nozzle) - 1e-5
    assert seat <= max(spec.motor.bell_d, 2 * (reach + float(mount.param("counterbore_d")) / 2 + 2 * spec.printer.nozzle)) + 4.0
    # the sleeves hold the rods as deep as a socket does
    least = sleeve_length(spec.rods.diameter)
    assert least - 1e-9 <= float(mount.param("clip_len")) <= least + 4.0


def test_motor_mount_clips_are_built_on_one_line():
    """Pure numpy: the second clip's rod is moved onto the line exactly parallel to the first (the
    stored rods of a rectangle are 2e-6 mm out of line); the presets' pair is kept as it is."""
    from cogniframe.families.motor_mount import _parallel

    rect = _variant("carbon", frame__width=242.8, frame__depth=188.5, frame__height=143.8, motors__radius=73.6,
                    motors__prop_diameter=68.4)
    for spec, moved in ((rect, True), (spec_mod.load(ROOT / "params" / "carbon.yaml"), False),
                        (spec_mod.load(ROOT / "params" / "bamboo.yaml"), False)):
        (mount,) = _parts(spec, ["motor_mount"])
        rods = [(np.asarray(p, float), np.asarray(d, float) / np.linalg.norm(d)) for p, d in mount.param("arm_rods")]
        clips = _parallel(rods)
        assert (clips is not rods) == moved
        (p0, d0), (p1, d1) = clips
        assert float(np.abs(d1 - d0).max()) <= 1e-9 and abs(float((p1 - p0) @ d0)) <= 1e-9
        assert np.linalg.norm(clips[1][0] - rods[1][0]) < 1e-5  # moved by the rounding only


@pytest.mark.parametrize("thickness", [6.05, 8.0])
@pytest.mark.cad
def test_camera_mount_keeps_its_upright_on_a_thick_plate(thickness):
    """core.plate_thickness 6.05 on the 40 mm carbon plate: the base's corner cuts met on the centre
    line in front of the upright ("camera_mount geometry produced 2 solids instead of 1"); the base
    keeps a spine 2 x CAMERA_SPINE wide."""
    from cogniframe.families.camera_mount import CAMERA_SPINE

    (mount,) = _parts(_variant("carbon", core__plate_thickness=thickness), ["front_camera_mount"])
    built = _one_watertight_solid(mount)
    # the spine: material on the centre line just behind the upright, through the base's thickness
    yf, wall, bt = (float(mount.param(k)) for k in ("y_front", "wall", "base_t"))
    import cadquery as cq

    probe = cq.Solid.makeBox(2 * CAMERA_SPINE - 0.2, 0.5, bt - 0.2, cq.Vector(-CAMERA_SPINE + 0.1, yf - wall - 0.6, 0.1))
    assert built.shape.intersect(probe).Volume() == pytest.approx(probe.Volume(), rel=1e-6)


@pytest.mark.parametrize("box", [
    (154.1, 175.9, 128.5, 60.2, 55.9),  # the corner_bottom lost 424 mm^3 of its strut sleeve, silently
    (274.4, 554.488, 113.1, 107.1, 76.2),  # ... 459 of 648 mm^3, both corner_bottom parts
    (262.9, 225.8, 122.4, 88.2, 76.2),  # corner_bottom_mirrored: "0 solids", corner_bottom: 248 mm^3 short
    (184.7, 169.7, 81.8, 66.3, 61.6),  # leg and strut, equal cylinders from one point: 781 of 1534 mm^3
    (284.4, 289.1, 141.2, 111.1, 76.2),  # the leg run through the bed: corner_top's STL had a hole
])
@pytest.mark.cad
def test_corner_hub_keeps_every_sleeve(box, monkeypatch):
    """Carbon boxes as a maker resizes them: every union the corner is built from holds all its
    pieces (fused all at once as built = fused one by one), and each mirrored corner has its
    original's volume."""
    from cogniframe.parts import joint_solid

    at_once = joint_solid.fuse_all

    def checked(shapes):
        union = at_once(shapes)
        one_by_one = shapes[0]
        for s in shapes[1:]:
            one_by_one = one_by_one.fuse(s)
        assert union.Volume() == pytest.approx(one_by_one.Volume(), rel=1e-3)
        return union

    monkeypatch.setattr(joint_solid, "fuse_all", checked)
    width, depth, height, radius, prop = box
    spec = _variant("carbon", frame__width=width, frame__depth=depth, frame__height=height, motors__radius=radius,
                    motors__prop_diameter=prop)
    corners = {p.name: _one_watertight_solid(p).shape.Volume() for p in _parts(spec, ["corner_top", "corner_top_mirrored",
                                                                                      "corner_bottom", "corner_bottom_mirrored"])}
    for kind in ("corner_top", "corner_bottom"):
        assert corners[f"{kind}_mirrored"] == pytest.approx(corners[kind], rel=1e-4)


@pytest.mark.parametrize("height", [107.14, 121.85, 122.3])
@pytest.mark.cad
def test_the_knee_stl_is_closed_where_its_mesh_had_a_sliver(height):
    (knee,) = _joints(_variant("carbon", frame__height=height), ["knee"])
    built = _one_watertight_solid(knee)
    assert built.shape.Volume() > 1000

"""cadread: rods, sockets and joints read back from small STEP / FreeCAD assemblies built here
(no network, no authors' files)."""

from __future__ import annotations

import math
import zipfile

import numpy as np
import pytest

import tiers

cq = pytest.importorskip("cadquery")

from cogniframe.cadread import read_exoskeleton  # noqa: E402
from cogniframe.cadread.load import load_solids  # noqa: E402
from cogniframe.cadread.part_materials import MaterialMap, load_material_map  # noqa: E402
from cogniframe.errors import UserError  # noqa: E402

ROD_D, BORE, DEPTH = 3.0, 2.7, 7.5
AXIS = np.array([1.0, 0.5, 2.0]) / np.linalg.norm([1.0, 0.5, 2.0])  # a tilted socket
BOTTOM = np.array([5.0, -3.0, 10.0])
LENGTH = 60.0


def _v(p) -> "cq.Vector":
    return cq.Vector(*[float(x) for x in p])


def blind_block(bottom, axis, bore=BORE, depth=DEPTH, size=14.0):
    """A cube whose face the socket opens through: centred `size / 2 - depth` behind the bottom, with
    a blind hole of `bore` from `bottom` out along `axis`."""
    axis = np.asarray(axis, float)
    centre = np.asarray(bottom) + axis * (depth - size / 2)
    # a cube turned so that its +z face is square to the axis
    z = cq.Vector(0, 0, 1)
    rot = z.cross(_v(axis))
    ang = math.degrees(math.acos(float(np.clip(axis[2], -1, 1))))
    box = cq.Solid.makeBox(size, size, size, cq.Vector(-size / 2, -size / 2, -size / 2))
    if rot.Length > 1e-9:
        box = box.rotate(cq.Vector(0, 0, 0), rot, ang)
    box = box.translate(_v(centre))
    hole = cq.Solid.makeCylinder(bore / 2, depth + 5, _v(bottom), _v(axis))
    return box.cut(hole)


def through_block(point, axis, bore=3.2, length=8.0, size=8.0):
    axis = np.asarray(axis, float)
    start = np.asarray(point) - axis * length / 2
    outer = cq.Solid.makeCylinder(size / 2, length, _v(start), _v(axis))
    return outer.cut(cq.Solid.makeCylinder(bore / 2, length, _v(start), _v(axis)))


def rod(a, b, d=ROD_D):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return cq.Solid.makeCylinder(d / 2, float(np.linalg.norm(b - a)), _v(a), _v(b - a))


def write_step(tmp_path, parts: dict, name="frame.step"):
    assy = cq.Assembly(name="frame")
    for n, shape in parts.items():
        assy.add(shape, name=n)
    path = tmp_path / name
    assy.export(str(path))
    return path


@pytest.fixture(scope="module")
@tiers.needs('cad')
def socket_assembly(tmp_path_factory):
    """A TPU block with a blind tilted socket, a rod home in it, a sleeve on the rod, and a second
    joint (a through hole) at the rod's far end."""
    tmp = tmp_path_factory.mktemp("cadread")
    far = BOTTOM + AXIS * LENGTH
    parts = {
        "Flex_Corner": blind_block(BOTTOM, AXIS),
        "rod_1": rod(BOTTOM, far),
        "MotorMount": through_block(BOTTOM + AXIS * 30.0, AXIS),
        "MainBase_link": through_block(far, AXIS, bore=3.0, length=6.0, size=10.0),  # the rod ends mid-bore
    }
    return read_exoskeleton(write_step(tmp, parts))


@pytest.mark.cad
def test_the_rod_is_found(socket_assembly):
    exo = socket_assembly
    assert [r.name for r in exo.rods] == ["rod_1"]
    r = exo.rods[0]
    assert r.diameter == pytest.approx(ROD_D, abs=1e-6)
    assert r.length == pytest.approx(LENGTH, abs=1e-6)
    ends = sorted([np.asarray(r.a), np.asarray(r.b)], key=lambda p: float(np.dot(p - BOTTOM, AXIS)))
    assert np.allclose(ends[0], BOTTOM, atol=1e-6)


@pytest.mark.cad
def test_blind_socket_axis_bore_depth(socket_assembly):
    exo = socket_assembly
    s = next(s for s in exo.sockets if s.joint == "Flex_Corner")
    assert s.kind == "blind" and s.blind
    assert s.bore == pytest.approx(BORE, abs=1e-6)  # the face's own radius: true across a tilted hole
    assert s.depth == pytest.approx(DEPTH, abs=1e-6)
    assert s.gap == pytest.approx(0.0, abs=1e-6)
    assert np.allclose(s.direction, AXIS, atol=1e-9)  # out of the socket, along the rod
    assert np.allclose(s.bottom, BOTTOM, atol=1e-6)
    assert np.allclose(s.mouth, BOTTOM + AXIS * DEPTH, atol=1e-6)
    assert s.offset == pytest.approx(0.0, abs=1e-6) and s.tilt_deg == pytest.approx(0.0, abs=1e-3)


@pytest.mark.cad
def test_through_socket_and_sleeve(socket_assembly):
    exo = socket_assembly
    far = next(s for s in exo.sockets if s.joint == "MainBase_link")
    assert far.kind == "through" and far.bore == pytest.approx(3.0, abs=1e-6)
    assert far.depth == pytest.approx(3.0, abs=1e-6)  # the rod's last 3 mm are in the 6 mm bore
    assert np.allclose(far.direction, -AXIS, atol=1e-9)
    sleeve = next(s for s in exo.sockets if s.joint == "MotorMount")
    assert sleeve.kind == "sleeve" and sleeve.end is None
    assert sleeve.bore == pytest.approx(3.2, abs=1e-6) and sleeve.depth == pytest.approx(8.0, abs=1e-6)
    r = exo.rods[0]
    from_a = 30.0 if np.allclose(r.a, BOTTOM, atol=1e-6) else LENGTH - 30.0
    assert sleeve.station == pytest.approx(from_a, abs=1e-6)


def test_joints_and_materials(socket_assembly):
    exo = socket_assembly
    mats = {j.name: (j.material, j.material_from) for j in exo.joints}
    assert mats == {"Flex_Corner": ("tpu_95a", "name"), "MotorMount": ("tpu_95a", "default"),
                    "MainBase_link": ("abs", "name")}
    assert exo.unplaced == () and exo.loose_ends == () and exo.warnings == ()


@pytest.mark.cad
def test_unplaced_part_and_loose_end_are_named(tmp_path):
    parts = {
        "Flex_Corner": blind_block(BOTTOM, AXIS),
        "rod_lonely": rod(BOTTOM, BOTTOM + AXIS * LENGTH),
        "Flex_Orphan": cq.Solid.makeBox(5, 5, 5, cq.Vector(200, 200, 200)),
    }
    exo = read_exoskeleton(write_step(tmp_path, parts))
    assert exo.unplaced == ("Flex_Orphan",)
    far_end = "b" if exo.socket_at("rod_lonely", "a") else "a"
    assert exo.loose_ends == (f"rod_lonely:{far_end}",)
    text = "\n".join(exo.warnings)
    assert "Flex_Orphan" in text and "neither a rod nor connected" in text
    assert f"rod_lonely:{far_end}" in text and "no joint's socket" in text


@pytest.mark.cad
def test_a_rod_pushed_past_the_bottom_reads_a_negative_gap_and_a_short_one_a_positive(tmp_path):
    parts = {"Flex_A": blind_block(BOTTOM, AXIS), "rod_deep": rod(BOTTOM - AXIS * 0.3, BOTTOM + AXIS * 40)}
    s = read_exoskeleton(write_step(tmp_path, parts, "deep.step")).sockets[0]
    assert s.gap == pytest.approx(-0.3, abs=1e-6) and s.depth == pytest.approx(DEPTH + 0.3, abs=1e-6)
    parts = {"Flex_A": blind_block(BOTTOM, AXIS), "rod_short": rod(BOTTOM + AXIS * 1.5, BOTTOM + AXIS * 40)}
    s = read_exoskeleton(write_step(tmp_path, parts, "short.step")).sockets[0]
    assert s.gap == pytest.approx(1.5, abs=1e-6) and s.depth == pytest.approx(DEPTH - 1.5, abs=1e-6)


@pytest.mark.cad
def test_placements_of_the_assembly_tree_are_applied(tmp_path):
    assy = cq.Assembly(name="top")
    sub = cq.Assembly(name="corner", loc=cq.Location(cq.Vector(100, 0, 0)))
    sub.add(cq.Solid.makeBox(2, 2, 2), name="Flex_Knee", loc=cq.Location(cq.Vector(0, 0, 10)))
    assy.add(sub)
    path = tmp_path / "tree.step"
    assy.export(str(path))
    (s,) = load_solids(path)
    bb = s.solid.BoundingBox()
    assert s.name == "Flex_Knee" and (bb.xmin, bb.zmin) == pytest.approx((100.0, 10.0), abs=1e-6)


# -- FreeCAD documents ----------------------------------------------------------------------

def _fcstd(path, objects):
    """A minimal .FCStd: objects = [(label, shape, placement (Px, Py, Pz, Q0..Q3) or None, bake)];
    `bake` stores the shape with the placement already in its location (what FreeCAD does)."""
    from OCP.BRepTools import BRepTools

    rows, files = [], {}
    for i, (label, shape, pl, bake) in enumerate(objects):
        px, py, pz, q0, q1, q2, q3 = pl or (0, 0, 0, 0, 0, 0, 1)
        if bake and pl:
            from cogniframe.cadread.load import _location, _placement_matrix
            import xml.etree.ElementTree as ET

            el = ET.Element("PropertyPlacement", {k: str(v) for k, v in zip(("Px", "Py", "Pz", "Q0", "Q1", "Q2", "Q3"), pl)})
            shape = shape.located(_location(_placement_matrix(el)))
        fname = f"Shape{i}.brp"
        tmp = path.parent / fname
        BRepTools.Write_s(shape.wrapped, str(tmp))
        files[fname] = tmp.read_bytes()
        rows.append(f'''<Object name="Feature{i}"><Properties Count="4">
<Property name="Label" type="App::PropertyString"><String value="{label}"/></Property>
<Property name="Placement" type="App::PropertyPlacement"><PropertyPlacement Px="{px}" Py="{py}" Pz="{pz}" Q0="{q0}" Q1="{q1}" Q2="{q2}" Q3="{q3}" A="0" Ox="0" Oy="0" Oz="1"/></Property>
<Property name="Shape" type="Part::PropertyPartShape"><Part file="{fname}"/></Property>
<Property name="Visibility" type="App::PropertyBool"><Bool value="true"/></Property>
</Properties></Object>''')
    doc = f'<?xml version="1.0" encoding="utf-8"?><Document SchemaVersion="4"><ObjectData Count="{len(rows)}">{"".join(rows)}</ObjectData></Document>'
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("Document.xml", doc)
        for k, v in files.items():
            z.writestr(k, v)
    return path


@pytest.mark.cad
def test_fcstd_placements_baked_or_not(tmp_path):
    s = math.sqrt(0.5)
    turn_z_90 = (50.0, 0.0, 0.0, 0.0, 0.0, s, s)  # move 50 in x, turn 90 deg about z
    box = cq.Solid.makeBox(10, 2, 2)
    path = _fcstd(tmp_path / "doc.FCStd", [("Raw", box, turn_z_90, False), ("Baked", box, turn_z_90, True)])
    got = {n.name: n.solid.BoundingBox() for n in load_solids(path)}
    for bb in got.values():  # both end at x 48..50, y 0..10: moved once, not twice
        assert (bb.xmin, bb.xmax, bb.ymin, bb.ymax) == pytest.approx((48.0, 50.0, 0.0, 10.0), abs=1e-6)


@pytest.mark.cad
def test_fcstd_exoskeleton(tmp_path):
    path = _fcstd(tmp_path / "frame.FCStd", [("Flex_Corner", blind_block(BOTTOM, AXIS), None, False),
                                             ("Rod", rod(BOTTOM, BOTTOM + AXIS * LENGTH), None, False)])
    exo = read_exoskeleton(path)
    assert len(exo.rods) == 1 and exo.rods[0].length == pytest.approx(LENGTH)
    (s,) = exo.sockets
    assert (s.joint, s.kind) == ("Flex_Corner", "blind") and s.bore == pytest.approx(BORE) and s.depth == pytest.approx(DEPTH)


# -- clean errors -----------------------------------------------------------------------------

@pytest.mark.parametrize("name, content, words", [
    ("broken.step", b"ISO-10303-21;\nHEADER;\nthis is not a step body\n", "could not be read"),
    ("notstep.step", b"solid cube\nendsolid\n", "not a STEP file"),
    ("frame.stl", b"solid cube\nendsolid\n", "not a CAD assembly"),
    ("broken.FCStd", b"PK not really a zip", "not a FreeCAD document"),
])
def test_bad_files_are_user_errors(tmp_path, name, content, words):
    p = tmp_path / name
    p.write_bytes(content)
    with pytest.raises(UserError) as e:
        read_exoskeleton(p)
    assert words in str(e.value) and str(p) in str(e.value)


def test_missing_file_and_zip_without_document(tmp_path):
    with pytest.raises(UserError, match="no such file"):
        read_exoskeleton(tmp_path / "nope.step")
    p = tmp_path / "empty.FCStd"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("x.txt", "hi")
    with pytest.raises(UserError, match="no Document.xml"):
        read_exoskeleton(p)


def test_materials_file_overrides_patterns(tmp_path):
    assert MaterialMap().of("Flex_Foot3") == ("tpu_95a", "name")
    assert MaterialMap().of("MainBase") == ("abs", "name")
    f = tmp_path / "m.yaml"
    f.write_text("parts:\n  Foot: petg\ndefault: pla\n")
    m = load_material_map(f)
    assert m.of("Flex_Foot3") == ("petg", "file") and m.of("widget") == ("pla", "default")
    f.write_text("parts:\n  Foot: unobtainium\n")
    with pytest.raises(UserError, match="unknown material 'unobtainium'"):
        load_material_map(f)


@pytest.mark.cad
def test_a_bspline_socket_reads_like_a_cylindrical_one(tmp_path):
    """A CAD program's mirror or export can store a hole as a B-spline surface (one socket of each
    mirrored pair in the authors' FreeCAD document): it is still a socket, with its bore and depth."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert

    block = cq.Shape.cast(BRepBuilderAPI_NurbsConvert(blind_block(BOTTOM, AXIS).wrapped, True).Shape())
    assert "CYLINDER" not in {f.geomType() for f in block.Faces()}
    exo = read_exoskeleton(write_step(tmp_path, {"Flex_Mirrored": block, "rod_1": rod(BOTTOM, BOTTOM + AXIS * 40)}))
    (s,) = exo.sockets
    assert s.kind == "blind" and s.bore == pytest.approx(BORE, abs=1e-3) and s.depth == pytest.approx(DEPTH, abs=1e-3)
    assert np.allclose(s.direction, AXIS, atol=1e-4) and s.offset < 1e-3


@pytest.mark.cad
def test_unnamed_solids_are_named_after_matching_part_files(tmp_path):
    from cogniframe.cadread.identify import file_signature, identify
    from cogniframe.cadread.load import NamedSolid

    part = blind_block((0, 0, 0), (0, 0, 1))
    cq.exporters.export(cq.Workplane().add(part), str(tmp_path / "Flex_Corner.stl"), tolerance=0.01, angularTolerance=0.1)
    other = cq.Solid.makeBox(4, 5, 30)
    cq.exporters.export(cq.Workplane().add(other), str(tmp_path / "Strut.stl"))
    refs = {p.stem: file_signature(p) for p in tmp_path.glob("*.stl")}
    turned = blind_block(BOTTOM, AXIS)  # the same part, placed and turned
    solids = [NamedSolid("body#1", turned), NamedSolid("body#2", blind_block((50, 0, 0), (1, 0, 0))),
              NamedSolid("body#3", cq.Solid.makeSphere(3))]
    named, renamed = identify(solids, refs)
    assert [s.name for s in named] == ["Flex_Corner_1", "Flex_Corner_2", "body#3"]
    assert renamed == {"Flex_Corner_1": "body#1", "Flex_Corner_2": "body#2"}


def test_json_ready(socket_assembly):
    import json

    from cogniframe.cadread import as_dict

    d = json.loads(json.dumps(as_dict(socket_assembly)))
    assert d["rods"][0]["length"] == pytest.approx(LENGTH)
    assert {s["kind"] for s in d["sockets"]} == {"blind", "through", "sleeve"}


@pytest.mark.cad
def test_module_entry_point(tmp_path, capsys):
    from cogniframe.cadread.summary import main

    path = write_step(tmp_path, {"Flex_Corner": blind_block(BOTTOM, AXIS), "rod_1": rod(BOTTOM, BOTTOM + AXIS * 40)})
    assert main([str(path)]) == 0
    out = capsys.readouterr().out
    assert "1 rods, 1 joints" in out and "rod_1:a blind 2.70 x 7.50" in out and "warning: 1 rod end(s)" in out
    bad = tmp_path / "x.step"
    bad.write_text("nope")
    assert main([str(bad)]) == 2 and "not a STEP file" in capsys.readouterr().err

"""Print plates: every copy placed once, inside the bed, apart by the margin; byte-stable files."""

from __future__ import annotations

import hashlib
import re
import zipfile

import numpy as np
import pytest
import trimesh

from cogniframe.errors import UserError
from cogniframe.export.plates import PlateItem, pack_plates, parse_plate_name, part_of, plate_3mf_bytes, write_plates
from meshes import box as _box, cylinder as _cyl

BED = (120.0, 120.0, 120.0)
MARGIN = 4.0


def _items():
    return [
        PlateItem("knee", "tpu_95a", 4, _cyl(8, 12)),
        PlateItem("corner_top", "tpu_95a", 4, _box(20, 18, 15)),
        PlateItem("motor_mount", "tpu_95a", 4, _box(22, 22, 6)),
        PlateItem("core_plate", "abs", 1, _box(40, 40, 3)),
        PlateItem("battery_holder", "abs", 1, _box(39, 18, 72)),
    ]


def _rects_apart(plate, margin):
    boxes = [(c.mesh.bounds[0][:2], c.mesh.bounds[1][:2]) for c in plate.copies]
    for i, (alo, ahi) in enumerate(boxes):
        for blo, bhi in boxes[i + 1:]:
            gap_x = max(blo[0] - ahi[0], alo[0] - bhi[0])
            gap_y = max(blo[1] - ahi[1], alo[1] - bhi[1])
            assert max(gap_x, gap_y) >= margin - 1e-6, "two parts closer than the margin"


def test_every_copy_once_inside_the_bed_and_apart():
    plates = pack_plates(_items(), BED, MARGIN)
    names = [c.name for p in plates for c in p.copies]
    expected = [f"{n}_{k}" for n, q in (("knee", 4), ("corner_top", 4), ("motor_mount", 4), ("core_plate", 1),
                                        ("battery_holder", 1)) for k in range(1, q + 1)]
    assert sorted(names) == sorted(expected)
    for p in plates:
        assert {c.part for c in p.copies} <= {"knee", "corner_top", "motor_mount", "core_plate", "battery_holder"}
        mats = {"abs" if c.part in ("core_plate", "battery_holder") else "tpu_95a" for c in p.copies}
        assert mats == {p.material}, "one material per plate"
        for c in p.copies:
            lo, hi = c.mesh.bounds
            assert lo[0] >= MARGIN / 2 - 1e-6 and lo[1] >= MARGIN / 2 - 1e-6
            assert hi[0] <= BED[0] - MARGIN / 2 + 1e-6 and hi[1] <= BED[1] - MARGIN / 2 + 1e-6
            assert abs(lo[2]) < 1e-9 and hi[2] <= BED[2]
            assert np.allclose((c.x, c.y), lo[:2], atol=1e-6)
        _rects_apart(p, MARGIN)
    # the copies keep their volume (no scaling or mirroring by the layout)
    knee = next(c for p in plates for c in p.copies if c.part == "knee")
    # (to 1e-4: its vertices move to the 1e-4 mm grid the 3MF states, cogniframe/numfmt.py; a scale is % off)
    assert knee.mesh.volume == pytest.approx(_cyl(8, 12).volume, rel=1e-4)


def test_as_many_plates_as_needed():
    # 54 mm footprints (50 + margin): 2 x 2 fit on a 120 mm bed (2 * 54 <= 120), 3 x 3 do not
    plates = pack_plates([PlateItem("big", "abs", 10, _box(50, 50, 5))], BED, MARGIN)
    assert [len(p.copies) for p in plates] == [4, 4, 2]
    assert [p.index for p in plates] == [1, 2, 3]
    assert [p.name for p in plates] == ["abs_1", "abs_2", "abs_3"]


def test_part_turned_to_its_smallest_footprint():
    bar = _box(100, 8, 5)
    bar.apply_transform(trimesh.transformations.rotation_matrix(np.radians(40), [0, 0, 1]))
    bar.apply_translation(-bar.bounds[0])
    assert bar.extents[0] > 80 and bar.extents[1] > 60  # diagonal: a big square footprint
    (plate,) = pack_plates([PlateItem("bar", "abs", 3, bar)], BED, MARGIN)
    for c in plate.copies:
        assert sorted(c.size[:2]) == pytest.approx([8, 100], abs=1e-6)


def test_part_larger_than_the_bed_is_a_user_error():
    with pytest.raises(UserError) as e:
        pack_plates([PlateItem("core_plate", "abs", 1, _box(130, 40, 3))], BED, MARGIN)
    msg = str(e.value)
    assert "core_plate" in msg and "130.0 x 40.0 x 3.0" in msg and "printer.bed" in msg and "120 x 120 x 120" in msg
    with pytest.raises(UserError, match="battery_holder.*printer.bed"):
        pack_plates([PlateItem("battery_holder", "abs", 1, _box(30, 30, 121))], BED, MARGIN)


def test_mesh_not_in_print_orientation_is_refused():
    m = _box(10, 10, 10)
    m.apply_translation([0, 0, 5])
    with pytest.raises(ValueError, match="print orientation"):
        pack_plates([PlateItem("x", "abs", 1, m)], BED, MARGIN)


def test_zero_quantity_makes_no_plate():
    assert pack_plates([PlateItem("x", "abs", 0, _box(10, 10, 10))], BED, MARGIN) == ()


def test_3mf_names_every_copy_shares_each_shape_and_is_byte_stable(tmp_path):
    from cogniframe.export.plates import read_3mf_items

    plates = pack_plates(_items(), BED, MARGIN)
    a = write_plates(plates, tmp_path / "a")
    b = write_plates(pack_plates(_items(), BED, MARGIN), tmp_path / "b")
    assert [f.name for f in a] == ["abs_1", "tpu_95a_1"]
    for fa, fb in zip(a, b):
        assert fa.threemf.read_bytes() == fb.threemf.read_bytes()
        assert fa.preview.read_bytes() == fb.preview.read_bytes()
    tpu = a[1]
    plate = next(p for p in plates if p.material == "tpu_95a")
    with zipfile.ZipFile(tpu.threemf) as z:
        assert all(i.date_time == (1980, 1, 1, 0, 0, 0) for i in z.infolist())
        model = z.read("3D/3dmodel.model").decode()
        prusa = z.read("Metadata/Slic3r_PE_model.config").decode()
    parts = re.findall(r'partnumber="([^"]+)"', model)
    assert sorted(parts) == sorted(tpu.copies) and len(parts) == 12
    # one mesh per shape: 3 parts, each laid out one or two ways round (a turned copy is another shape)
    shapes = {(c.part, c.rotation_deg) for c in plate.copies}
    assert model.count("<mesh>") == len(shapes) and 3 <= len(shapes) <= 6
    assert model.count("<component ") == 12 - len(shapes)
    # PrusaSlicer's instance counts add up to the copies, per part
    counts = re.findall(r'instances_count="(\d+)">\n  <metadata type="object" key="name" value="([^"]+)"', prusa)
    per_part = {}
    for n, part in counts:
        per_part[part] = per_part.get(part, 0) + int(n)
    assert per_part == {"corner_top": 4, "knee": 4, "motor_mount": 4}
    # read back (our reader; trimesh's can swap the names of identical copies): every copy where it was laid out
    items = read_3mf_items(tpu.threemf)
    assert sorted(n for n, _, _ in items) == sorted(c.name for c in plate.copies)
    assert len({id(m) for _, m, _ in items}) == len(shapes)
    for name, base, tf in items:
        c = next(c for c in plate.copies if c.name == name)
        m = base.copy()
        m.apply_transform(tf)
        assert m.is_watertight and m.is_volume
        assert np.allclose(m.bounds, c.mesh.bounds, atol=1e-6)
        assert m.volume == pytest.approx(c.mesh.volume, rel=1e-9)
    # trimesh reads the same geometry (names aside)
    scene = trimesh.load(tpu.threemf, force="scene")
    assert len(scene.graph.nodes_geometry) == 12
    assert sum(scene.geometry[scene.graph[n][1]].volume for n in scene.graph.nodes_geometry) == pytest.approx(
        plate.volume_mm3, rel=1e-9)


def test_preview_png(tmp_path):
    from PIL import Image

    (f,) = write_plates(pack_plates([PlateItem("knee", "tpu_95a", 4, _cyl(8, 12))], BED, MARGIN), tmp_path)
    img = np.asarray(Image.open(f.preview).convert("RGB")).astype(int)
    assert img.shape[1] == 600
    red = (img[..., 0] > 150) & (img[..., 1] < 100) & (img[..., 2] < 100)
    assert 0.01 < red.mean() < 0.5  # the four TPU parts are drawn
    assert img.std() > 10


def test_plate_3mf_items_are_what_reading_the_file_back_gives(tmp_path):
    """The build draws a preview from the items plate_3mf returns instead of reading the 3MF it just
    wrote; a cached plate's preview is drawn from the file. Both must be the same numbers, bit for
    bit (same shared meshes, names, transforms), so the PNG is the same bytes either way."""
    from cogniframe.export.plates import plate_3mf, plot_plate, read_3mf_items, read_plate

    plate = next(p for p in pack_plates(_items(), BED, MARGIN) if p.material == "tpu_95a")
    data, items = plate_3mf(plate, "; fill_density = 20%\n")
    assert data == plate_3mf_bytes(plate, "; fill_density = 20%\n")
    f = tmp_path / f"{plate.name}.3mf"
    f.write_bytes(data)
    back = read_3mf_items(f)
    assert [n for n, _, _ in items] == [n for n, _, _ in back] and len(items) == 12
    for (_, m, tf), (_, mb, tfb) in zip(items, back):
        assert np.array_equal(m.vertices, mb.vertices) and m.vertices.dtype == mb.vertices.dtype
        assert np.array_equal(m.faces, mb.faces) and m.faces.dtype == mb.faces.dtype
        assert np.array_equal(tf, tfb)
    # copies of one shape share one mesh in both
    assert [[j for j, (_, o, _) in enumerate(items) if o is m] for _, m, _ in items] == [
        [j for j, (_, o, _) in enumerate(back) if o is m] for _, m, _ in back]
    a = plot_plate(read_plate(f, BED, MARGIN), tmp_path / "from_file.png")
    b = plot_plate(read_plate(f, BED, MARGIN, items=items), tmp_path / "from_memory.png")
    assert a.read_bytes() == b.read_bytes()
    # the slicer's pre-check (slicer.check_plate) reads them the same way
    from cogniframe.export import slicer

    assert slicer.check_plate(f, BED, items=items) == slicer.check_plate(f, BED)


def test_preview_silhouette_is_the_union_of_upward_faces_counter_clockwise():
    """The preview fills one path of the upward faces with the nonzero rule: that is the top-view
    silhouette only if every projected triangle turns counter-clockwise and, for a convex solid, they
    tile its footprint once (area of the box 20 x 18 and of the 32-gon of radius 8)."""
    from cogniframe.export.plates import _silhouettes

    plates = pack_plates([PlateItem("box", "tpu_95a", 1, _box(20, 18, 15)), PlateItem("disc", "tpu_95a", 1, _cyl(8, 12))],
                         BED, MARGIN)
    for c in plates[0].copies:
        tri = _silhouettes([c]).vertices.reshape(-1, 4, 2)
        assert np.array_equal(tri[:, 0], tri[:, 3])  # each closed
        a, b, d = tri[:, 0], tri[:, 1], tri[:, 2]
        areas = 0.5 * ((b[:, 0] - a[:, 0]) * (d[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (d[:, 0] - a[:, 0]))
        assert (areas > 0).all()
        expected = 20 * 18 if c.part == "box" else 0.5 * 32 * 8 ** 2 * np.sin(2 * np.pi / 32)
        # once, not twice (to 1e-4: the vertices sit on the 1e-4 mm grid the 3MF states, cogniframe/numfmt.py)
        assert areas.sum() == pytest.approx(expected, rel=1e-4)


def test_rewriting_removes_stale_plates(tmp_path):
    write_plates(pack_plates([PlateItem("big", "abs", 10, _box(50, 50, 5))], BED, MARGIN), tmp_path)
    assert len(list(tmp_path.glob("*.3mf"))) == 3
    write_plates(pack_plates([PlateItem("big", "abs", 2, _box(50, 50, 5))], BED, MARGIN), tmp_path)
    assert sorted(p.name for p in tmp_path.glob("*")) == ["abs_1.3mf", "abs_1.png"]


def test_names():
    assert parse_plate_name("tpu_95a_12") == ("tpu_95a", 12)
    with pytest.raises(ValueError):
        parse_plate_name("tpu")
    assert part_of("corner_top_3") == "corner_top" and part_of("knee") == "knee"


def test_3mf_bytes_depend_only_on_the_plate():
    p1 = pack_plates(_items(), BED, MARGIN)
    p2 = pack_plates(list(reversed(_items())), BED, MARGIN)  # input order does not matter
    assert [hashlib.sha256(plate_3mf_bytes(p)).hexdigest() for p in p1] == [
        hashlib.sha256(plate_3mf_bytes(p)).hexdigest() for p in p2]


_WRITE_IN_CHILD = """
import sys, trimesh
from cogniframe.export.plates import PlateItem, pack_plates, write_plates
def box(x, y, z):
    m = trimesh.creation.box((x, y, z)); m.apply_translation(-m.bounds[0]); return m
def cyl(r, h):
    m = trimesh.creation.cylinder(radius=r, height=h, sections=32); m.apply_translation(-m.bounds[0]); return m
items = [PlateItem("knee", "tpu_95a", 4, cyl(8, 12)), PlateItem("corner_top", "tpu_95a", 4, box(20, 18, 15)),
         PlateItem("motor_mount", "tpu_95a", 4, box(22, 22, 6)), PlateItem("core_plate", "abs", 1, box(40, 40, 3)),
         PlateItem("battery_holder", "abs", 1, box(39, 18, 72))]
write_plates(pack_plates(items, (120.0, 120.0, 120.0), 4.0), sys.argv[1])
"""


@pytest.mark.process
def test_same_bytes_in_another_process(tmp_path):
    import os
    import subprocess
    import sys

    write_plates(pack_plates(_items(), BED, MARGIN), tmp_path / "here")
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    subprocess.run([sys.executable, "-c", _WRITE_IN_CHILD, str(tmp_path / "there")], check=True, env=env, timeout=120)
    here = sorted(p.name for p in (tmp_path / "here").iterdir())
    assert here == sorted(p.name for p in (tmp_path / "there").iterdir())
    for name in here:
        assert (tmp_path / "here" / name).read_bytes() == (tmp_path / "there" / name).read_bytes(), name


def test_3mf_carries_prusaslicer_settings_and_stays_byte_stable(tmp_path):
    configs = {"tpu_95a": "; generated\n; fill_density = 100%\n", "abs": "; generated\n; fill_density = 10%\n"}
    a = write_plates(pack_plates(_items(), BED, MARGIN), tmp_path / "a", configs=configs)
    b = write_plates(pack_plates(_items(), BED, MARGIN), tmp_path / "b", configs=configs)
    plain = write_plates(pack_plates(_items(), BED, MARGIN), tmp_path / "c")
    for fa, fb, fc in zip(a, b, plain):
        assert fa.threemf.read_bytes() == fb.threemf.read_bytes()
        with zipfile.ZipFile(fa.threemf) as z, zipfile.ZipFile(fc.threemf) as zc:
            assert z.read("Metadata/Slic3r_PE.config").decode() == configs[fa.material]
            assert z.getinfo("Metadata/Slic3r_PE.config").date_time == (1980, 1, 1, 0, 0, 0)
            assert "Metadata/Slic3r_PE.config" not in zc.namelist()
            assert z.read("3D/3dmodel.model") == zc.read("3D/3dmodel.model")  # geometry untouched


def test_model_sha256_ignores_the_settings_beside_the_geometry():
    from cogniframe.export.plates import model_sha256

    plate = pack_plates(_items(), BED, MARGIN)[1]
    a, b, c = plate_3mf_bytes(plate), plate_3mf_bytes(plate, "; fill_density = 100%\n"), plate_3mf_bytes(plate, "; x = 1\n")
    assert len({a, b, c}) == 3 and len({model_sha256(a), model_sha256(b), model_sha256(c)}) == 1
    moved = pack_plates(_items(), (130.0, 120.0, 120.0), MARGIN)[1]  # centred on a wider bed: other coordinates
    assert model_sha256(plate_3mf_bytes(moved)) != model_sha256(a)

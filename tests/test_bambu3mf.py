"""Plates for OrcaSlicer / Bambu Studio: the 3MF their loader (bbs_3mf.cpp) reads as its own, each object
with its filament slot and print settings in Metadata/model_settings.config; every 3MF checked with lib3mf."""

from __future__ import annotations

import io
import shutil
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest
import trimesh
import yaml

from cogniframe import spec as spec_mod
from cogniframe.export import bambu3mf
from cogniframe.export.plates import PlateItem, pack_plates, plate_3mf, read_3mf_items
from threemf import NS, check_3mf
from meshes import box as _box, cylinder as _cyl

ROOT = Path(__file__).resolve().parents[1]
BED = (180.0, 180.0, 180.0)  # the A1 mini's


def _plates():
    items = [PlateItem("knee", "tpu_95a", 4, _cyl(8, 12)), PlateItem("corner_top", "tpu_95a", 2, _box(20, 18, 15)),
             PlateItem("core_plate", "abs", 1, _box(40, 40, 3)), PlateItem("battery_holder", "abs", 1, _box(39, 18, 72))]
    return {p.material: p for p in pack_plates(items, BED, 4.0)}


@pytest.fixture(scope="module")
def a1_mini():
    return spec_mod.from_dict({"printer": {"preset": "bambu_a1_mini"}, "core": {"infill": 0.15}})


def _orca(plate, spec, infill):
    return bambu3mf.plate_3mf(plate, bambu3mf.object_settings(spec, plate.material, infill))


def test_objects_settings_have_the_ids_of_the_models_build_objects(a1_mini):
    plates = _plates()
    data, _ = _orca(plates["tpu_95a"], a1_mini, 1.0)
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        names = z.namelist()
        root = ElementTree.fromstring(z.read("3D/3dmodel.model"))
        config = ElementTree.fromstring(z.read(bambu3mf.MODEL_SETTINGS))
    assert names == ["[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model", "Metadata/model_settings.config"]
    objects = {o.get("id"): o for o in root.iter(f"{NS}object")}
    built = [i.get("objectid") for i in root.iter(f"{NS}item")]
    assert len(built) == 6  # 4 knees + 2 corners, one build item each
    # one <object id=N> per build object, the same ids; each made of the mesh object its <part> names
    entries = config.findall("object")
    assert [e.get("id") for e in entries] == built
    for e in entries:
        obj = objects[e.get("id")]
        comp = obj.find(f"{NS}components/{NS}component").get("objectid")
        part = e.find("part")
        assert part.get("id") == comp and part.get("subtype") == "normal_part"
        assert objects[comp].find(f"{NS}mesh") is not None
        meta = {m.get("key"): m.get("value") for m in e.findall("metadata")}
        assert meta["name"] == obj.get("name")
    # the plate lists every object once
    plate_ids = [m.get("value") for m in config.iter("metadata") if m.get("key") == "object_id"]
    assert plate_ids == built


def test_tpu_objects_print_solid_and_rigid_objects_at_the_core_infill(a1_mini):
    plates = _plates()
    tpu = bambu3mf.read_object_settings(_orca(plates["tpu_95a"], a1_mini, 1.0)[0])
    rigid = bambu3mf.read_object_settings(_orca(plates["abs"], a1_mini, a1_mini.core.infill)[0])
    assert len(tpu) == 6 and len(rigid) == 2
    for s in tpu.values():
        assert s["extruder"] == "1" and s["sparse_infill_density"] == "100%" and "sparse_infill_pattern" not in s
    for s in rigid.values():
        assert s["extruder"] == "1" and s["sparse_infill_density"] == "15%" and s["sparse_infill_pattern"] == "grid"
    for s in (*tpu.values(), *rigid.values()):  # the shells of `printer:`, as the PrusaSlicer profile has them
        assert (s["wall_loops"], s["top_shell_layers"], s["bottom_shell_layers"], s["layer_height"]) == ("2", "4", "4", "0.2")


def test_application_is_neither_prusaslicer_nor_bambu_studio(a1_mini):
    """OrcaSlicer hands a 3MF whose Application metadata mentions PrusaSlicer to its PrusaSlicer loader,
    which ignores model_settings.config; cogniframe does not claim to be Bambu Studio either."""
    data, _ = _orca(_plates()["tpu_95a"], a1_mini, 1.0)
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        text = z.read("3D/3dmodel.model").decode()
        assert not any(n.startswith("Metadata/Slic3r_PE") for n in z.namelist())
    root = ElementTree.fromstring(text)
    meta = {m.get("name"): m.text for m in root.iter(f"{NS}metadata")}
    assert meta["Application"] == "cogniframe" and meta["BambuStudio:3mfVersion"] == "1"
    assert "PrusaSlicer" not in text and "slic3rpe" not in text


def test_orca_plate_is_byte_stable_and_reads_back_as_its_items(a1_mini, tmp_path):
    plate = _plates()["tpu_95a"]
    data, items = _orca(plate, a1_mini, 1.0)
    assert _orca(plate, a1_mini, 1.0)[0] == data
    f = tmp_path / "tpu_95a_1.3mf"
    f.write_bytes(data)
    back = read_3mf_items(f)
    assert [n for n, _, _ in back] == [n for n, _, _ in items] == sorted(c.name for c in plate.copies)
    for (_, m1, t1), (_, m2, t2) in zip(back, items):
        assert np.array_equal(m1.vertices, m2.vertices) and np.array_equal(m1.faces, m2.faces) and np.allclose(t1, t2)
    # every copy where the layout put it, with the volume of its part
    placed = {c.name: c for c in plate.copies}
    for name, mesh, tf in back:
        lo = mesh.bounds[0] + tf[:3, 3]
        assert np.allclose(lo[:2], (placed[name].x, placed[name].y), atol=1e-6)
        assert mesh.volume == pytest.approx(placed[name].mesh.volume, rel=1e-9)


@pytest.mark.parametrize("material", ["tpu_95a", "abs"])
def test_lib3mf_loads_both_kinds_of_plate_manifold_and_oriented(a1_mini, material):
    plate = _plates()[material]
    copies = len(plate.copies)
    shapes = len({c.part for c in plate.copies})
    orca = check_3mf(_orca(plate, a1_mini, 1.0)[0])
    # Orca / Bambu: a mesh object per shape, a components object per copy
    assert (orca["meshes"], orca["components"], orca["items"]) == (shapes, copies, copies)
    prusa = check_3mf(plate_3mf(plate, "; printer_technology = FFF\n")[0])
    # PrusaSlicer: the first copy of a shape is its mesh object, further copies components
    assert (prusa["meshes"], prusa["components"], prusa["items"]) == (shapes, copies - shapes, copies)


def test_a_broken_mesh_fails_the_lib3mf_check(a1_mini):
    """The check is not vacuous: a plate with a face missing is not manifold."""
    bad = _box(20, 20, 10)
    bad = trimesh.Trimesh(bad.vertices, bad.faces[:-1], process=False)
    plate = pack_plates([PlateItem("lid", "tpu_95a", 1, bad)], BED, 4.0)[0]
    with pytest.raises(AssertionError, match="not manifold"):
        check_3mf(_orca(plate, a1_mini, 1.0)[0])


@pytest.mark.skipif(shutil.which("prusa-slicer") is None, reason="PrusaSlicer not installed")
@pytest.mark.slicer
def test_prusaslicer_measures_an_orca_plate_as_the_prusaslicer_plate(a1_mini, tmp_path):
    """What `build` reports for Bambu presets: PrusaSlicer slices the Orca / Bambu 3MF with cogniframe's
    profile; the geometry is the plate's, so the grams are the PrusaSlicer plate's."""
    from cogniframe.export import slicer

    plate = _plates()["tpu_95a"]
    ini = tmp_path / "tpu_95a.ini"
    ini.write_text(slicer.profile_ini(a1_mini, "tpu_95a", 1.0), encoding="utf-8")
    out = {}
    for kind, data in (("orca", _orca(plate, a1_mini, 1.0)[0]), ("prusa", plate_3mf(plate)[0])):
        d = tmp_path / kind
        d.mkdir()
        (d / "tpu_95a_1.3mf").write_bytes(data)
        out[kind] = slicer.slice_plate(d / "tpu_95a_1.3mf", ini, BED, gcode=d / "tpu_95a_1.gcode")
    assert [n for n, _ in out["orca"].objects] == [n for n, _ in out["prusa"].objects]
    assert out["orca"].grams == pytest.approx(out["prusa"].grams, rel=0.01)
    assert out["orca"].time_s == pytest.approx(out["prusa"].time_s, rel=0.02)
    # 4 knees (pi 8^2 12) and 2 boxes (20 18 15) solid in TPU at 1.21 g/cm^3 less the little a slicer drops
    solid_g = (4 * np.pi * 64 * 12 + 2 * 20 * 18 * 15) / 1000 * a1_mini.material("tpu_95a").density_g_cm3
    assert out["orca"].grams == pytest.approx(solid_g, rel=0.08)


@pytest.mark.cad
@pytest.mark.slicer
@pytest.mark.fe
def test_build_for_the_a1_mini_writes_orca_bambu_plates(tmp_path):
    """The acceptance check: `printer: {preset: bambu_a1_mini}` builds plates that lib3mf loads, each
    object with its filament slot, the TPU objects at 100 % infill and the rigid ones at core.infill."""
    from cogniframe.pipeline import run_build

    doc = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text(encoding="utf-8"))
    doc["name"] = "a1mini"
    doc["printer"] = {k: v for k, v in doc["printer"].items() if k not in ("preset", "bed", "nozzle")}
    doc["printer"]["preset"] = "bambu_a1_mini"
    params = tmp_path / "a1mini.yaml"
    params.write_text(yaml.safe_dump(doc), encoding="utf-8")
    spec = spec_mod.load(params)
    assert spec.printer.bed == BED
    out = tmp_path / "out"
    run_build(spec, params, out, jobs=2)
    plates = sorted((out / "plates").glob("*.3mf"))
    assert {p.stem.rsplit("_", 1)[0] for p in plates} == {"tpu_95a", "abs"}
    for p in plates:
        data = p.read_bytes()
        counts = check_3mf(data)
        settings = bambu3mf.read_object_settings(data)
        assert len(settings) == counts["items"] > 0
        with zipfile.ZipFile(p) as z:
            assert "Metadata/Slic3r_PE.config" not in z.namelist()
        expected = "100%" if p.stem.startswith("tpu") else f"{round(100 * spec.core.infill, 2):g}%"
        for s in settings.values():
            assert s["extruder"] == "1" and s["sparse_infill_density"] == expected
    if shutil.which("prusa-slicer"):  # the report says whose grams and time these are
        assert "measuring plates written for Bambu Studio / OrcaSlicer" in (out / "report.html").read_text(encoding="utf-8")

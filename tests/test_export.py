"""Export: byte-identical STL/STEP for the same params, STEP round trip, the part cache, assembly."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from cogniframe import frame as frame_mod
from cogniframe import partlist
from cogniframe import spec as spec_mod
from test_parts import PART_NAMES, PRESETS, ROOT, built_preset


def _sha(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _design(preset="carbon", **changes):
    data = spec_mod.load(ROOT / "params" / f"{preset}.yaml").model_dump(mode="json")
    for key, value in changes.items():
        section, name = key.split("__")
        data[section][name] = value
    spec = spec_mod.from_dict(data)
    fr = frame_mod.frame_of(spec)
    return spec, fr, partlist.part_list(spec, fr)


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_same_params_give_byte_identical_stl_and_step(preset, tmp_path):
    from cogniframe.export.part_files import build_parts

    first = built_preset(preset)
    spec, fr, parts = first.spec, first.frame, tuple(first.parts.values())
    again = build_parts(spec, fr, parts, tmp_path)
    for b in again:
        a = first.built[b.name]
        assert _sha(tmp_path / b.stl) == _sha(first.out / a.stl), b.name
        assert _sha(tmp_path / b.step) == _sha(first.out / a.step), b.name


@pytest.mark.cad
def test_parallel_build_gives_the_same_bytes(tmp_path):
    from cogniframe.export.part_files import build_parts

    first = built_preset("carbon")
    parts = tuple(first.parts.values())[:4]
    from cogniframe.runtime.pools import cad_workers

    with cad_workers(2) as submit:
        again = build_parts(first.spec, first.frame, parts, tmp_path, submit=submit)
    for b in again:
        assert _sha(tmp_path / b.stl) == _sha(first.out / first.built[b.name].stl)
        assert _sha(tmp_path / b.step) == _sha(first.out / first.built[b.name].step)
        assert np.allclose(b.print_from_local, first.built[b.name].print_from_local)


@pytest.mark.cad
def test_step_header_has_no_timestamp_or_counter():
    text = (built_preset("carbon").out / "step" / "knee.step").read_text(encoding="latin-1")
    assert "2000-01-01T00:00:00" in text
    assert "STEP translator" not in text
    assert "PRODUCT('knee'" in text.replace("\n", "").replace(" ", "")


@pytest.mark.parametrize("preset,name", [(p, n) for p in PRESETS for n in PART_NAMES[p]])
@pytest.mark.cad
def test_step_round_trip_is_one_solid_of_the_same_volume(preset, name):
    import cadquery as cq

    d = built_preset(preset)
    shape = cq.importers.importStep(str(d.out / d.built[name].step))
    solids = shape.solids().vals()
    assert len(solids) == 1
    assert solids[0].Volume() == pytest.approx(d.built[name].volume_mm3, rel=0.002)


@pytest.mark.cad
def test_files_are_laid_out_by_material(tmp_path):
    d = built_preset("carbon")
    for b in d.built.values():
        assert b.stl == f"stl/{b.material}/{b.name}.stl" and b.step == f"step/{b.name}.step"
        assert (d.out / b.stl).is_file() and (d.out / b.step).is_file()


@pytest.mark.cad
def test_cache_hit_builds_no_solid_is_identical_and_reports_progress(tmp_path, monkeypatch):
    from cogniframe.export import part_files
    from cogniframe.families import registry

    spec, fr, parts = _design()
    cache = tmp_path / "cache"
    part_files.build_parts(spec, fr, parts, tmp_path / "a", cache_dir=cache)
    seen, solids = [], []
    monkeypatch.setattr(registry, "solid", lambda part: solids.append(part.name))  # a hit copies the files
    again = part_files.build_parts(spec, fr, parts, tmp_path / "b", cache_dir=cache, progress=seen.append)
    assert solids == []
    assert sorted(seen) == sorted(p.name for p in parts)
    for b in again:
        assert _sha(tmp_path / "a" / b.stl) == _sha(tmp_path / "b" / b.stl)
        assert _sha(tmp_path / "a" / b.step) == _sha(tmp_path / "b" / b.step)


@pytest.mark.cad
def test_only_changed_parts_are_rebuilt(tmp_path, monkeypatch):
    from cogniframe.export import part_files as build_mod

    cache = tmp_path / "cache"
    spec, fr, parts = _design()
    build_mod.build_parts(spec, fr, parts, tmp_path / "a", cache_dir=cache)
    rebuilt = []
    real = build_mod.build_part_files
    monkeypatch.setattr(build_mod, "build_part_files", lambda p, *a: rebuilt.append(p.name) or real(p, *a))
    # rod material: no printed part changes
    spec2, fr2, parts2 = _design(rods__material="bamboo")
    build_mod.build_parts(spec2, fr2, parts2, tmp_path / "b", cache_dir=cache)
    assert rebuilt == []
    # frame width: the joints whose socket angles change (a rectangle's fr/rl copies become
    # mirrored parts of their own), and the core plate, whose peg tubes follow the links, and only those
    spec3, fr3, parts3 = _design(frame__width=230)
    build_mod.build_parts(spec3, fr3, parts3, tmp_path / "c", cache_dir=cache)
    before = {p.name: p.digest for p in parts}
    changed = {q.name for q in parts3 if before.get(q.name) != q.digest}
    assert set(rebuilt) == changed and changed
    assert "core_plate" in changed and "knee_mirrored" in changed and "battery_holder" not in changed


@pytest.mark.cad
def test_assembly_has_every_part_copy_and_rod_named_and_coloured(tmp_path):
    import cadquery as cq

    from cogniframe.export.assembly import write_assembly

    d = built_preset("carbon")
    step, glb = write_assembly(d.spec, d.frame, tuple(d.parts.values()), tuple(d.built.values()), d.out)
    assert glb.stat().st_size > 10_000
    assy = cq.Assembly.importStep(str(step))
    names = {c.name for c in assy.children}
    expected = {"knee_fl", "corner_top_rr", "core_link_rl", "motor_mount_fr", "core_plate", "battery_holder"}
    expected |= set(d.frame.rods)
    assert expected <= names
    from cogniframe.vitamins import vitamins

    assert len(names) == sum(p.qty for p in d.parts.values()) + len(d.frame.rods) + len(vitamins(d.spec, d.frame))
    colour = {c.name: c.color.toTuple()[:3] for c in assy.children if c.color is not None}
    assert colour["knee_fl"][0] > 0.5 > colour["knee_fl"][1]  # TPU red
    assert max(colour["rod_arm_fl_1"]) < 0.1  # rods black
    assert 0.01 < colour["core_plate"][0] < 0.5 and colour["core_plate"][0] == pytest.approx(colour["core_plate"][2])
    # a placed copy lands on its node: the knee's bounding box holds the knee node
    knee = next(c for c in assy.children if c.name == "knee_fl")
    bb = knee.toCompound().BoundingBox() if hasattr(knee, "toCompound") else knee.obj.moved(knee.loc).BoundingBox()
    node = d.frame.nodes["knee_fl"].pos
    assert bb.xmin - 1 <= node[0] <= bb.xmax + 1 and bb.zmin - 1 <= node[2] <= bb.zmax + 1
    first = _sha(step)
    write_assembly(d.spec, d.frame, tuple(d.parts.values()), tuple(d.built.values()), d.out)
    assert _sha(step) == first


@pytest.mark.cad
def test_glb_places_every_copy_rod_and_vitamin_y_up_in_mm_and_is_byte_stable(tmp_path):
    """assembly.glb from the build's meshes: one node per part copy, rod and vitamin, by name and
    colour; glTF's y up (world z -> y) in mm; copies share their part's mesh; same bytes twice."""
    import trimesh

    from cogniframe.export.assembly import write_glb
    from cogniframe.vitamins import vitamins

    d = built_preset("carbon")
    parts = tuple(d.parts.values())
    pfl = {n: b.print_from_local for n, b in d.built.items()}
    a = write_glb(d.spec, d.frame, parts, d.meshes, pfl, tmp_path / "a.glb")
    b = write_glb(d.spec, d.frame, parts, d.meshes, pfl, tmp_path / "b.glb")
    assert _sha(a) == _sha(b)
    scene = trimesh.load(a, force="scene")
    vits = vitamins(d.spec, d.frame)
    nodes = set(scene.graph.nodes_geometry)
    assert len(nodes) == sum(p.qty for p in parts) + len(d.frame.rods) + len(vits)
    assert {"knee_fl", "corner_top_rr", "core_link_rl", "motor_mount_fr", "core_plate", "battery"} | set(d.frame.rods) <= nodes
    assert len(scene.geometry) == len(parts) + len(d.frame.rods) + len(vits)  # copies share a mesh
    # the knee copy sits on its frame node; y up: world (x, y, z) is glTF (x, z, -y)
    tf, geom = scene.graph["knee_fl"]
    knee = scene.geometry[geom].copy()
    knee.apply_transform(tf)
    x, y, z = d.frame.nodes["knee_fl"].pos
    lo, hi = knee.bounds
    assert lo[0] - 1 <= x <= hi[0] + 1 and lo[1] - 1 <= z <= hi[1] + 1 and lo[2] - 1 <= -y <= hi[2] + 1
    assert knee.volume == pytest.approx(d.meshes["knee"].volume, rel=1e-6)
    # colours: TPU red, rods black
    red = scene.geometry[geom].visual.face_colors[0]
    assert red[0] > 150 > red[1]
    rod = scene.geometry[scene.graph["rod_arm_fl_1"][1]].visual.face_colors[0]
    assert max(rod[:3]) < 25
    # the whole aircraft's height is the glTF y extent
    assert scene.bounds[1][1] - scene.bounds[0][1] == pytest.approx(
        max(n.pos[2] for n in d.frame.nodes.values()) - min(n.pos[2] for n in d.frame.nodes.values()), abs=40)


def test_mesh_tolerances_agree_with_the_cache_key():
    from cogniframe.export import part_files as build, mesh

    assert (build.LINEAR_TOL, build.ANGULAR_TOL) == (mesh.LINEAR_TOL, mesh.ANGULAR_TOL)


# builds the joints of each (params, changes) and prints the sha256 of each one's STL and STEP
_JOINT_HASHES = """
import hashlib, json, sys, tempfile
from pathlib import Path
from cogniframe import api
from cogniframe.export.part_files import build_part_files
out = {}
for params, changes in json.loads(sys.argv[1]):
    d = api.load(params).with_values(changes)
    bed = tuple(float(b) for b in d.spec.printer.bed)
    for p in d.derived.parts:
        if p.family == "joint":
            folder = Path(tempfile.mkdtemp())
            v = build_part_files(p, bed, str(folder))
            out[f"{Path(params).stem} {changes} {p.name}"] = [hashlib.sha256((folder / v[k]).read_bytes()).hexdigest()
                                                              for k in ("stl", "step")]
print(json.dumps(out))
"""


def _openblas_picks_its_kernel_by_cpu() -> bool:
    import platform

    blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    return platform.machine() in ("x86_64", "AMD64") and "DYNAMIC_ARCH" in str(blas.get("openblas configuration", ""))


@pytest.mark.cad
@pytest.mark.process
def test_the_joints_files_do_not_follow_the_cpus_blas_kernel(tmp_path):
    """The joints' solids are built from small numpy products, which OpenBLAS computes with a kernel
    it picks by CPU. Before their numbers were rounded to numfmt.CAD_DECIMALS, its Haswell and
    Sandybridge kernels (every x86-64 CPU with AVX runs both) gave the knees' and core links' STEP
    of both presets, and most of their STLs, other bytes: the golden hashes held on one machine
    only. Built once with each kernel, every joint of both presets and two resized carbons must
    be the same bytes."""
    import json
    import os
    import subprocess
    import sys

    if not _openblas_picks_its_kernel_by_cpu():
        pytest.skip("numpy's BLAS is not an OpenBLAS that picks its kernel by CPU (OPENBLAS_CORETYPE)")
    designs = [[str(ROOT / "params" / "carbon.yaml"), {}], [str(ROOT / "params" / "bamboo.yaml"), {}],
               [str(ROOT / "params" / "carbon.yaml"), {"frame.width": 231.7, "frame.height": 117.3}],
               [str(ROOT / "params" / "carbon.yaml"), {"frame.depth": 251.3, "rods.diameter": 2.7}]]
    found = {}
    for kernel in ("Haswell", "Sandybridge"):
        env = {**os.environ, "OPENBLAS_CORETYPE": kernel}
        run = subprocess.run([sys.executable, "-c", _JOINT_HASHES, json.dumps(designs)], env=env, cwd=tmp_path,
                             capture_output=True, text=True, timeout=900)
        assert run.returncode == 0, run.stderr[-2000:]
        found[kernel] = json.loads(run.stdout.strip().splitlines()[-1])
    assert len(found["Haswell"]) >= 20  # corners, knees, core links of four designs
    assert found["Haswell"] == found["Sandybridge"]


def test_a_sliver_at_a_t_junction_is_mended_not_left_as_a_crack():
    """A unit tetrahedron whose face (0, 2, 1) is split at M, the midpoint of edge 0-1, and a
    zero-area sliver (0, M, 1) closing the T-junction, as OCC's mesher leaves them: clean() drops
    the sliver AND splits the face across 0-1 at M, so the mesh stays closed with the tetrahedron's
    volume (1/6); dropping the sliver alone left edges 0-M, M-1 and 0-1 with one face each."""
    import trimesh

    from cogniframe.export.mesh import clean

    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0, 0]], float)
    f = np.array([[0, 2, 4], [4, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3], [0, 4, 1]])
    raw = trimesh.Trimesh(v, f, process=False)
    assert raw.is_watertight and raw.nondegenerate_faces().sum() == 5  # one face of zero area
    m = clean(raw)
    assert m.is_watertight and m.is_winding_consistent and len(m.faces) == 6
    assert m.nondegenerate_faces().all()
    assert abs(m.volume) == pytest.approx(1 / 6, rel=1e-12)


def test_glb_rod_cylinder_is_a_closed_prism_of_the_polygon_area():
    """The GLB's rods: a closed, outward-facing 48-gon prism from start to end; its volume is the
    polygon's area (n/2 r^2 sin(2 pi / n)) times the length, whatever the axis direction."""
    import trimesh

    from cogniframe.export.assembly import cylinder_arrays

    for start, end in (((0, 0, 0), (0, 0, 30)), ((10, -5, 2), (40, 15, -8)), ((1, 1, 1), (1, 1, -4))):
        v, f = cylinder_arrays(start, end, 2.5)
        m = trimesh.Trimesh(v, f, process=True)
        length = float(np.linalg.norm(np.subtract(end, start)))
        assert m.is_watertight and m.is_winding_consistent and m.volume > 0  # outward faces
        assert m.volume == pytest.approx(48 / 2 * 2.5 ** 2 * np.sin(2 * np.pi / 48) * length, rel=1e-9)
        assert np.allclose(v[-2], start) and np.allclose(v[-1], end)


def test_a_process_pools_cad_workers_run_behind_the_build_on_one_thread_each():
    """Without the CAD server the build's own pool's workers are as nice as the server's
    (`runtime.pools.start_worker`): BACKGROUND_NICE steps nicer than the build."""
    import os

    from cogniframe.runtime.pools import BACKGROUND_NICE, make_pool

    with make_pool(1, fe=False) as pool:
        got = pool.submit(os.getpriority, os.PRIO_PROCESS, 0).result()
        # OpenCascade's algorithms on the worker's own thread: one worker per core already
        occ_threads = pool.submit(eval, "__import__('OCP.OSD', fromlist=['OSD_ThreadPool'])"
                                        ".OSD_ThreadPool.DefaultPool_s(-1).NbThreads()").result()
    assert got == min(19, os.getpriority(os.PRIO_PROCESS, 0) + BACKGROUND_NICE)
    assert occ_threads == 1

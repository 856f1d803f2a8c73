"""Renders: real pixels (size, frame in view, TPU red present, not uniform), byte-stable PNGs.

Meshes are made here (cylinders at the joints, boxes for the core), placed with the part list's
placements, so the test does not depend on the CAD layer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.report import renders

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def scene():
    d = design_mod.design(spec_mod.load(ROOT / "params" / "carbon.yaml"))
    meshes = {}
    for p in d.parts:
        if p.family in ("joint", "motor_mount"):
            m = trimesh.creation.cylinder(radius=7, height=8, sections=24)
        else:
            m = trimesh.creation.box(p.estimate.envelope)
        meshes[p.name] = m
    return d, meshes


def test_world_meshes_follow_the_placements(scene):
    d, meshes = scene
    world = renders.world_meshes(d.parts, meshes)
    assert len(world) == sum(p.qty for p in d.parts)
    knee = next(w for w in world if w.name == "knee_fr")
    assert np.allclose(knee.mesh.centroid, d.frame.nodes["knee_fr"].pos, atol=1e-6)
    # print_from_local: a mesh stored 5 mm up in print space lands back on the node
    shift = np.eye(4)
    shift[2, 3] = 5.0
    moved = {n: m.copy().apply_transform(shift) for n, m in meshes.items()}
    world2 = renders.world_meshes(d.parts, moved, {n: shift for n in meshes})
    knee2 = next(w for w in world2 if w.name == "knee_fr")
    assert np.allclose(knee2.mesh.centroid, knee.mesh.centroid, atol=1e-6)
    segs = renders.rod_segments(d.frame)
    assert len(segs) == len(d.frame.rods)
    r = d.frame.rods["rod_arm_fl_1"]
    seg = next(s for s in segs if s.name == r.name)
    assert np.linalg.norm(np.subtract(seg.end, seg.start)) == pytest.approx(r.length)


def test_assembly_renders_show_the_frame(scene, tmp_path):
    d, meshes = scene
    out = renders.render_assembly(renders.world_meshes(d.parts, meshes), renders.rod_segments(d.frame), tmp_path,
                                  title="carbon")
    assert set(out) == {"iso", "top", "front"}
    stats = {v: renders.image_stats(p) for v, p in out.items()}
    for v, s in stats.items():
        assert (s["width"], s["height"]) == renders.SIZE, v
        assert 0.05 < s["foreground"] < 0.90, (v, s)
        assert s["red"] > 0.002, (v, s)  # TPU joints are red
        assert s["dark"] > 0.01, (v, s)  # rods and core are black / dark grey
        assert s["std"] > 20, (v, s)
    # the three views differ
    data = {v: p.read_bytes() for v, p in out.items()}
    assert len(set(data.values())) == 3


def test_frame_is_centred_and_fills_the_top_view(scene, tmp_path):
    from PIL import Image

    d, meshes = scene
    out = renders.render_assembly([], renders.rod_segments(d.frame), tmp_path, views=("top",))
    img = np.asarray(Image.open(out["top"]).convert("RGB")).astype(int)
    fg = (img < 200).any(axis=2)
    ys, xs = np.where(fg.any(axis=1))[0], np.where(fg.any(axis=0))[0]
    h, w = img.shape[:2]
    assert (ys.max() - ys.min()) > 0.8 * h  # the square frame fills the height of the top view
    assert abs((xs.min() + xs.max()) / 2 - w / 2) < 0.05 * w and abs((ys.min() + ys.max()) / 2 - h / 2) < 0.05 * h


def test_part_renders(scene, tmp_path):
    d, meshes = scene
    out = renders.render_parts({"knee": ("tpu_95a", meshes["knee"]), "core_plate": ("abs", meshes["core_plate"])}, tmp_path)
    assert sorted(out) == ["core_plate", "knee"]
    knee, plate = renders.image_stats(out["knee"]), renders.image_stats(out["core_plate"])
    assert (knee["width"], knee["height"]) == renders.PART_SIZE
    assert 0.05 < knee["foreground"] < 0.9 and knee["red"] > 0.03
    assert 0.05 < plate["foreground"] < 0.9 and plate["red"] < 0.001 and plate["dark"] > 0.01


def test_same_scene_same_bytes(scene, tmp_path):
    d, meshes = scene
    world = renders.world_meshes(d.parts, meshes)
    a = renders.render_assembly(world, renders.rod_segments(d.frame), tmp_path / "a", views=("iso",))
    b = renders.render_assembly(world, renders.rod_segments(d.frame), tmp_path / "b", views=("iso",))
    assert a["iso"].read_bytes() == b["iso"].read_bytes()


_RENDER_IN_CHILD = """
import sys
from pathlib import Path
from cogniframe import spec as spec_mod
from cogniframe import design as design_mod
from cogniframe.report import renders
d = design_mod.design(spec_mod.load(Path(sys.argv[1])))
renders.render_assembly([], renders.rod_segments(d.frame), sys.argv[2], views=("iso",))
"""


@pytest.mark.process
def test_same_bytes_in_another_process(scene, tmp_path):
    import subprocess
    import sys

    d, _ = scene
    here = renders.render_assembly([], renders.rod_segments(d.frame), tmp_path / "here", views=("iso",))
    subprocess.run([sys.executable, "-c", _RENDER_IN_CHILD, str(ROOT / "params" / "carbon.yaml"), str(tmp_path / "there")],
                   check=True, timeout=180, capture_output=True)
    assert here["iso"].read_bytes() == (tmp_path / "there" / "assembly_iso.png").read_bytes()


def test_a_shared_part_plotter_gives_the_bytes_of_a_new_one(scene, tmp_path):
    """The build draws every part render in one plotter (pipeline.report_steps._part_plotter); a cached render
    was drawn in another order, or alone: the bytes must not depend on what the plotter drew before."""
    d, meshes = scene
    parts = {"knee": ("tpu_95a", meshes["knee"]), "core_plate": ("abs", meshes["core_plate"]),
             "battery_holder": ("abs", meshes["battery_holder"])}
    alone = {n: renders.render_parts({n: parts[n]}, tmp_path / "alone" / n)[n] for n in parts}
    shared = renders.part_plotter()
    try:
        out = {}
        for n in ("battery_holder", "knee", "core_plate", "knee"):  # knee twice: after a part and after itself
            out[n] = renders.render_parts({n: parts[n]}, tmp_path / "shared" / n, plotter=shared)[n]
            assert out[n].read_bytes() == alone[n].read_bytes(), n
        with pytest.raises(ValueError, match="not"):
            renders.render_parts({"knee": parts["knee"]}, tmp_path / "big", size=renders.SIZE, plotter=shared)
    finally:
        shared.close()
    assert len({p.read_bytes() for p in alone.values()}) == 3  # three different pictures


def _dark_box(png: Path, rows: int = 40, cols: int = 400):
    """(top, left, bottom, right) of the dark pixels in the upper-left corner of an image."""
    from PIL import Image

    a = np.asarray(Image.open(png))[:rows, :cols, :3]
    d = np.argwhere(a.min(axis=2) < 128)
    return (*d.min(axis=0), *d.max(axis=0))


def test_part_labels_are_one_height_in_the_corner_whatever_the_name(tmp_path):
    """Every part's label is PART_LABEL_PX high, LABEL_MARGIN_PX from the top-left corner: a short
    name is not drawn bigger (pyvista's corner annotation, used before, grew "knee" to 17 px)."""
    box = trimesh.creation.box((30.0, 30.0, 0.2))  # a flat plate: a thin diamond in the middle of the view
    parts = {"knee": ("tpu_95a", box), "core_link_mirrored": ("tpu_95a", box)}
    out = renders.render_parts(parts, tmp_path)
    short, long = _dark_box(out["knee"]), _dark_box(out["core_link_mirrored"])
    m = renders.LABEL_MARGIN_PX
    assert short[0] == long[0] == m and m - 1 <= short[1] <= m and m - 1 <= long[1] <= m  # "f" leans left a pixel
    # the same glyph heights ("(", "p"): the same rows, whatever the name's length
    assert short[2] == long[2] and abs((short[2] - short[0] + 1) - renders.PART_LABEL_PX) <= 1
    assert long[3] - long[1] > 1.5 * (short[3] - short[1])  # the longer name is wider, not smaller

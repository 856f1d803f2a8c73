"""tools/compare_parts.py reads each round hole across its own axis: bore, axis, depth and wall of
holes that run at a slant, on small meshes made with manifold3d (no CAD kernel), written to tmp_path."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import manifold3d as m3
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("compare_parts", ROOT / "tools" / "compare_parts.py")
compare_parts = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(compare_parts)

SEGMENTS = 128  # the 128-gon's area is the circle's less 0.04 %: 2.70 reads 2.6995


def _stl(solid: m3.Manifold, path: Path) -> Path:
    import trimesh

    mesh = solid.to_mesh()
    trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts)).export(path)
    return path


def _box(lo, hi) -> m3.Manifold:
    return m3.Manifold.cube(np.subtract(hi, lo).tolist()).translate(list(lo))


def _rot_x(deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _wall_to_box(lo, hi, centre, axis, r) -> float:
    """The true wall in the box's section perpendicular to `axis` through `centre` (inside it):
    the section is convex, so the bore's nearest boundary is the nearest of the six faces' lines;
    a face with normal m at distance h from `centre` cuts that plane in a line h / |m across the
    axis| from it."""
    best = np.inf
    for k in range(3):
        m = np.eye(3)[k]
        across = np.linalg.norm(m - (m @ axis) * axis)
        if across > 1e-9:
            best = min(best, (hi[k] - centre[k]) / across, (centre[k] - lo[k]) / across)
    return best - r


def _angle_deg(a, b) -> float:
    return float(np.degrees(np.arccos(np.clip(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b), -1, 1))))


def _z_section_bore(solid: m3.Manifold, z: float) -> float:
    """What the old tool read: the circle of the area of the interior loop of a section along z."""
    areas = [compare_parts._area(np.asarray(p, float)) for p in solid.slice(z).to_polygons()]
    return 2 * np.sqrt(-min(areas) / np.pi)


def _the_hole(solid, path: Path, material: str, kind: str, d: float, axis) -> dict:
    """The one hole the tool finds in `solid`: its kind, its bore within 0.03 mm, its axis within 1 deg."""
    found = compare_parts.measure(_stl(solid, path), material)["holes"]
    assert len(found) == 1
    h = found[0]
    assert h["kind"] == kind
    assert h["diameter"] == pytest.approx(d, abs=0.03)
    assert _angle_deg(h["axis"], axis) < 1.0
    return h


def test_tilted_blind_socket(tmp_path):
    """A 2.70 mm blind socket tilted 25 deg about x, 7.5 deep (its mouth on the block's top face),
    1.5 mm from the block's x faces (which run along it), as the authors' knee sockets are.

    The old tool cut the part along z: that section meets the socket in an ellipse with half-axes
    1.35 and 1.35 / cos 25 deg, the long axis 2.70 / cos 25 = 2.98, and it printed the circle of the
    ellipse's area, 2.70 / sqrt(cos 25) = 2.84: 0.14 too large, outside this test's 0.03 (the 2.83
    it printed for the authors' 2.69 knee sockets). Across the socket's own axis it reads 2.70."""
    d, depth, wall, tilt = 2.70, 7.5, 1.5, 25.0
    r = d / 2
    rot = _rot_x(tilt)
    axis = rot @ [0, 0, 1.0]  # out of the mouth
    lo, hi = np.array([-(r + wall), -8.0, -10.0]), np.array([r + wall, 8.0, 0.0])
    cutter = (m3.Manifold.cylinder(depth + 3.0, r, r, SEGMENTS).translate([0, 0, -depth])
              .transform(np.c_[rot, np.zeros(3)]))
    block = _box(lo, hi) - cutter
    h = _the_hole(block, tmp_path / "tilted.stl", "tpu_95a", "blind", d, axis)
    assert h["depth"] == pytest.approx(depth, abs=0.2)
    mid = -0.5 * depth * axis
    assert _wall_to_box(lo, hi, mid, axis, r) == pytest.approx(wall, abs=1e-9)  # the x faces decide it
    assert h["wall"] == pytest.approx(wall, abs=0.05)
    # The old axis section, for the record: the equal-area ellipse, which fails the tolerance.
    old = _z_section_bore(block, float(mid[2]))
    assert old == pytest.approx(d / np.sqrt(np.cos(np.radians(tilt))), abs=0.01)
    assert abs(old - d) > 0.1


def test_oblique_through_sleeve(tmp_path):
    """A 3.20 mm through hole along an axis 30 deg off z, turned 40 deg round z, through a 6 mm
    plate, as the authors' motor-seat sleeves (3.19-3.20) pass rods: 6 / cos 30 = 6.93 long; its
    wall, in the plane across the axis, is to the +x face: 4 / |x across the axis| - 1.6 = 2.73.
    A z section reads it as an ellipse of 3.20 / sqrt(cos 30) = 3.44."""
    d, tilt, turn = 3.20, 30.0, 40.0
    r = d / 2
    t, p = np.radians(tilt), np.radians(turn)
    axis = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    lo, hi = np.array([-9.0, -9.0, -3.0]), np.array([4.0, 9.0, 3.0])
    # z onto `axis`: a rotation about z by `turn` after one about y by `tilt`
    cz, sz, cy, sy = np.cos(p), np.sin(p), np.cos(t), np.sin(t)
    rot = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    assert rot @ [0, 0, 1.0] == pytest.approx(axis)
    cutter = m3.Manifold.cylinder(20.0, r, r, SEGMENTS, True).transform(np.c_[rot, np.zeros(3)])
    plate = _box(lo, hi) - cutter
    h = _the_hole(plate, tmp_path / "oblique.stl", "abs", "through", d, axis)  # through: its axis' z positive
    assert h["depth"] == pytest.approx(6.0 / np.cos(t), abs=0.2)
    assert h["wall"] == pytest.approx(_wall_to_box(lo, hi, np.zeros(3), axis, r), abs=0.05)
    assert _wall_to_box(lo, hi, np.zeros(3), axis, r) == pytest.approx(4.0 / np.sqrt(1 - axis[0] ** 2) - r)
    assert _z_section_bore(plate, 0.0) == pytest.approx(d / np.sqrt(np.cos(t)), abs=0.01)


def test_a_boss_and_a_flat_block_have_no_holes(tmp_path):
    """A round peg standing on a block is convex: not a hole."""
    peg = _box([-5, -5, -2], [5, 5, 0]) + m3.Manifold.cylinder(6.0, 1.5, 1.5, SEGMENTS)
    assert compare_parts.measure(_stl(peg, tmp_path / "peg.stl"), "abs")["holes"] == []


def test_the_tables(tmp_path, capsys):
    """The script's output: each part's holes grouped, then one line a hole with its axis."""
    theirs, build = tmp_path / "authors", tmp_path / "out"
    theirs.mkdir()
    (build / "stl" / "tpu_95a").mkdir(parents=True)
    rot = _rot_x(25.0)
    block = _box([-2.85, -8, -10], [2.85, 8, 0]) - (m3.Manifold.cylinder(10.5, 1.35, 1.35, SEGMENTS)
                                                    .translate([0, 0, -7.5]).transform(np.c_[rot, np.zeros(3)]))
    _stl(block, theirs / "Flex_socket.stl")
    _stl(block, build / "stl" / "tpu_95a" / "socket.stl")
    assert compare_parts.main([str(theirs), str(build)]) == 0
    out = capsys.readouterr().out
    assert out.count("blind 2.70 x 7.5, wall 1.50 (1)") == 2
    assert "| Flex_socket | blind | 2.70 | (0.00, -0.42, 0.91) | 7.50 | 1.50 |" in out

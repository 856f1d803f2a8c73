"""The clash check's shortcut for pairs with a rod (`clash._apart`): a pair it proves apart has
the volume the boolean gives (0), a pair it cannot prove gets the boolean, and the whole check
is the same with and without it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from cogniframe.analysis import clash

R_ROD = 3.0


def _rod(name: str, start, end) -> clash.Body:
    m = trimesh.creation.cylinder(radius=R_ROD, segment=np.array([start, end], float), sections=48)
    return clash.Body(name, "rod", m)


def _clip(inner_r: float, name: str = "clip") -> clash.Body:
    """A ring 12 mm long around the slanted rod's axis (a motor-mount clip), bore `inner_r`."""
    ring = trimesh.creation.annulus(r_min=inner_r, r_max=inner_r + 2.0, height=12.0, sections=48)
    d = np.array([1.0, 1.0, -0.6]) / np.linalg.norm([1.0, 1.0, -0.6])
    T = trimesh.geometry.align_vectors([0, 0, 1.0], d)
    T[:3, 3] = [10.0, 10.0, 4.0]  # on the rod's axis (below)
    return clash.Body(name, "part", ring, T)


def _slanted_rod() -> clash.Body:
    d = np.array([1.0, 1.0, -0.6]) / np.linalg.norm([1.0, 1.0, -0.6])
    c = np.array([10.0, 10.0, 4.0])
    return _rod("rod_arm", c - 40 * d, c + 40 * d)


def _without_shortcut(monkeypatch, bodies, **kw):
    monkeypatch.setattr(clash, "_apart", lambda *a: False)
    r = clash.check(bodies, **kw)
    monkeypatch.undo()
    return r


def _pair(bodies):
    a, b = bodies
    ma, mb = clash._manifold(a), clash._manifold(b)
    rod = ma if a.kind == "rod" else mb
    turn = clash._turn_to_z(clash._long_axis(rod))
    return ma, mb, turn


def test_rod_in_a_clip_with_clearance_is_proved_apart_and_gets_the_booleans_zero(monkeypatch):
    # the rod (r 3, 48 facets: its flats 3 cos(pi/48) from the axis) in a bore of r 3.05
    bodies = [_clip(3.05), _slanted_rod()]
    ma, mb, turn = _pair(bodies)
    assert clash._apart(ma, mb, 1, 1, turn)
    assert (ma ^ mb).volume() == 0.0  # what the boolean says
    proved = []
    real = clash._apart
    monkeypatch.setattr(clash, "_apart", lambda *a: proved.append(real(*a)) or proved[-1])
    r = clash.check(bodies)
    monkeypatch.undo()
    assert proved == [True]  # the check took the shortcut
    assert r.pairs_tested == 1 and r.ok and r.max_overlap == ("", "", 0.0)
    assert r == _without_shortcut(monkeypatch, bodies)


def test_rod_pressed_into_a_tight_clip_is_not_proved_and_gets_its_overlap(monkeypatch):
    # bore r 2.8 around a rod of r 3: the overlap is a 0.2 mm thick sleeve, ~ 2 pi r t L
    bodies = [_clip(2.8), _slanted_rod()]
    ma, mb, turn = _pair(bodies)
    assert not clash._apart(ma, mb, 1, 1, turn)
    r = clash.check(bodies)
    (c,) = r.clashes
    assert c.volume_mm3 == pytest.approx(math.pi * (3.0**2 - 2.8**2) * 12.0, rel=0.02)
    assert r == _without_shortcut(monkeypatch, bodies)


def test_a_rod_wholly_inside_a_block_is_not_proved_apart(monkeypatch):
    # surfaces 7 mm apart, but the rod is inside the block: the overlap is the whole rod
    block = clash.Body("block", "part", trimesh.creation.box(extents=(20.0, 20.0, 40.0)))
    rod = _rod("rod_in", (0, 0, -10.0), (0, 0, 10.0))
    ma, mb, turn = _pair([block, rod])
    assert not clash._apart(ma, mb, 1, 1, turn)
    (c,) = clash.check([block, rod]).clashes
    area = 48 / 2 * R_ROD**2 * math.sin(2 * math.pi / 48)  # the 48-gon's area
    assert c.volume_mm3 == pytest.approx(area * 20.0, rel=1e-6)


def test_a_piece_of_a_part_inside_the_rod_is_found_though_the_part_reaches_out(monkeypatch):
    # a part of two pieces: a 1 mm cube inside a fat rod and a block far away; the part's box is
    # not inside the rod's, the cube's is
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    far = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    far.apply_translation((0.0, 0.0, 30.0))
    part = clash.Body("two_pieces", "part", trimesh.util.concatenate([cube, far]))
    rod = _rod("rod_fat", (0, 0, -10.0), (0, 0, 10.0))
    assert len(clash._manifold(part).decompose()) == 2
    r = clash.check([part, rod])
    (c,) = r.clashes
    assert c.volume_mm3 == pytest.approx(1.0, rel=1e-9)
    assert r == _without_shortcut(monkeypatch, [part, rod])


def test_turn_to_z_is_a_rotation_taking_the_axis_to_z():
    rng = np.random.default_rng(5)
    for d in [*rng.normal(size=(5, 3)), (0, 0, 1.0), (0, 0, -1.0), (1e-14, 0, -1.0)]:
        d = np.asarray(d, float) / np.linalg.norm(d)
        R = clash._turn_to_z(d)[:, :3]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
        np.testing.assert_allclose(R @ d, (0, 0, 1.0), atol=1e-14)

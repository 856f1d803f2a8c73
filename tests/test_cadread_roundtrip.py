"""cadread against cogniframe's own frame: an assembly written from the carbon preset's frame graph
(its rods from `rod.start` to `rod.end`, as export/assembly.py writes them, and at every node a
stand-in joint: a boss around each socket with the socket's bore from its bottom to its mouth) reads
back as the frame's rods (count, lengths to 0.01 mm) and sockets (joint, rod end, direction, depth,
bore), and `toframe` gives rods whose lengths and mouths are the frame's.

The real `assembly.step` of `cogniframe build params/carbon.yaml` reads back the same way (to 1e-6
mm; the 0.5 mm mouth chamfers included): that needs the CAD build (minutes), so it is checked by
hand, not here."""

from __future__ import annotations

import numpy as np
import pytest

import tiers

cq = pytest.importorskip("cadquery")

from cogniframe import frame as frame_mod  # noqa: E402
from cogniframe.analysis.stiffness import mouth  # noqa: E402
from cogniframe.cadread import read_exoskeleton  # noqa: E402
from cogniframe.cadread.toframe import frame_nodes, frame_rods, part_sockets  # noqa: E402

WALL = 1.5


def _v(p):
    return cq.Vector(*[float(x) for x in p])


def stand_in_joint(frame, node: str, bore: float):
    """A hub at the node, a strut from it to each socket's port, a boss from the port to the mouth,
    and the socket bored from its bottom to its mouth."""
    n = frame.nodes[node]
    pos = np.asarray(n.pos, float)
    solid = cq.Solid.makeSphere(2.5, _v(pos))
    holes = []
    for rn in n.rods:
        r = frame.rods[rn]
        end = r.end_at(node)
        d = r.socket_direction(node)
        port = np.asarray(end.port, float)
        if np.linalg.norm(port - pos) > 1e-6:
            solid = solid.fuse(cq.Solid.makeCylinder(2.0, float(np.linalg.norm(port - pos)), _v(pos), _v(port - pos)))
        solid = solid.fuse(cq.Solid.makeSphere(bore / 2 + WALL, _v(port)))
        solid = solid.fuse(cq.Solid.makeCylinder(bore / 2 + WALL, end.seat + end.depth, _v(port), _v(d)))
        holes.append(cq.Solid.makeCylinder(bore / 2, end.depth, _v(port + d * end.seat), _v(d)))
    for h in holes:
        solid = solid.cut(h)
    return solid.clean()


@pytest.fixture(scope="module")
@tiers.needs('cad')
def carbon_roundtrip(tmp_path_factory):
    from cogniframe import spec as spec_mod
    import pathlib

    spec = spec_mod.load(pathlib.Path(__file__).resolve().parents[1] / "params" / "carbon.yaml")
    frame = frame_mod.frame_of(spec)
    assy = cq.Assembly(name="carbon")
    for node in frame.nodes:
        assy.add(stand_in_joint(frame, node, spec.bore), name=node)
    for r in frame.rods.values():
        start, end = np.asarray(r.start, float), np.asarray(r.end, float)
        assy.add(cq.Solid.makeCylinder(r.diameter / 2, float(np.linalg.norm(end - start)), _v(start), _v(end - start)), name=r.name)
    path = tmp_path_factory.mktemp("roundtrip") / "assembly.step"
    assy.export(str(path))
    return spec, frame, read_exoskeleton(path)


@pytest.mark.cad
def test_rods_are_the_frames(carbon_roundtrip):
    _spec, frame, exo = carbon_roundtrip
    assert sorted(r.name for r in exo.rods) == sorted(frame.rods)
    for r in exo.rods:
        assert r.length == pytest.approx(frame.rods[r.name].length, abs=0.01)
        assert r.diameter == pytest.approx(frame.rods[r.name].diameter, abs=1e-6)
    assert exo.loose_ends == () and exo.unplaced == ()


@pytest.mark.cad
def test_sockets_are_the_frames_ports_and_directions(carbon_roundtrip):
    spec, frame, exo = carbon_roundtrip
    assert len([s for s in exo.sockets if s.end is not None]) == 2 * len(frame.rods)
    for name, r in frame.rods.items():
        for end, point in ((r.a, r.start), (r.b, r.end)):
            s = next(s for s in exo.sockets if s.rod == name and s.joint == end.node)
            assert s.kind == "blind"
            assert np.allclose(s.rod_end, point, atol=1e-3)
            assert np.allclose(s.direction, r.socket_direction(end.node), atol=1e-6)
            assert s.depth == pytest.approx(end.depth, abs=1e-3)
            assert s.bore == pytest.approx(spec.bore, abs=1e-6)
            assert s.gap == pytest.approx(0.0, abs=1e-3)


@pytest.mark.cad
def test_toframe_gives_the_frames_rods_and_mouths(carbon_roundtrip):
    _spec, frame, exo = carbon_roundtrip
    rods = frame_rods(exo)
    assert set(rods) == set(frame.rods)
    for name, r in frame.rods.items():
        got = rods[name]
        assert got.length == pytest.approx(r.length, abs=1e-3)
        tags = ("a", "b") if got.a.node == r.a.node else ("b", "a")
        for mine, theirs in zip(tags, ("a", "b")):
            assert np.allclose(mouth(got, mine), mouth(r, theirs), atol=1e-3)
    nodes = frame_nodes(exo)
    assert set(nodes) == set(frame.nodes)
    for name, n in frame.nodes.items():
        assert sorted(nodes[name].rods) == sorted(n.rods)
        for ps in part_sockets(exo, name):  # stiffness._match_rod's port + direction key
            r = frame.rods[ps.rod]
            assert np.allclose(ps.direction, r.socket_direction(name), atol=1e-6)
            assert np.allclose(ps.bottom(), r.start if r.a.node == name else r.end, atol=1e-3)

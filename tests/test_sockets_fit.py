"""The printed sockets agree with the frame graph and the cut list.

Each rod (a cylinder of the rod diameter from `rod.start` to `rod.end`) and each printed part copy
(its STL moved by Placement.matrix() @ inv(print_from_local)) are put in world coordinates:
* every rod end sits at the bottom of a socket of some part copy (within 0.5 mm), pointing out of it;
* that socket's hole really ends there: a ray from outside the mouth down the socket axis hits the
  hole bottom at the socket depth (measured on the STL);
* no rod intersects any printed part (manifold3d boolean volume ~ 0), so rods only enter their
  own sockets, and the motor mounts' clips leave the arm rods free.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
import trimesh

from test_parts import PRESETS, built_preset

END_TOL = 0.5  # mm
VOLUME_TOL = 1.0  # mm^3, tessellation


def _world(d):
    """(instance name, part, world mesh, world-from-print) for every printed part copy."""
    from cogniframe.export.assembly import instance_name, world_from_print

    out = []
    for name, part in d.parts.items():
        b = d.built[name]
        for pl in part.placements:
            m = world_from_print(pl.matrix(), b.print_from_local)
            mesh = d.meshes[name].copy()
            mesh.apply_transform(m)
            out.append((instance_name(part, pl.instance), part, mesh, pl.matrix()))
    return out


def _rod_mesh(rod):
    start, end = np.asarray(rod.start), np.asarray(rod.end)
    return trimesh.creation.cylinder(radius=rod.diameter / 2, segment=np.vstack([start, end]), sections=64)


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_every_rod_end_sits_at_a_socket_bottom(preset):
    d = built_preset(preset)
    sockets = []  # (instance, world bottom, world out-direction)
    for name, part in d.parts.items():
        for pl in part.placements:
            m = pl.matrix()
            for s in part.sockets:
                sockets.append((pl.instance, (m @ np.r_[s.bottom(), 1.0])[:3], m[:3, :3] @ np.asarray(s.direction)))
    used = Counter()
    for rod in d.frame.rods.values():
        for end, node, out_dir in ((rod.start, rod.a.node, rod.axis), (rod.end, rod.b.node, -rod.axis)):
            dist = [np.linalg.norm(b - end) for _, b, _ in sockets]
            i = int(np.argmin(dist))
            inst, bottom, direction = sockets[i]
            assert dist[i] <= END_TOL, f"{rod.name} end at {node}: nearest socket bottom {dist[i]:.2f} mm away"
            assert inst == node
            assert direction @ out_dir > 0.999  # the rod leaves through the socket's mouth
            used[i] += 1
    assert len(used) == len(sockets) == 2 * len(d.frame.rods)  # every socket holds exactly one rod end
    assert max(used.values()) == 1


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_socket_holes_end_at_the_socket_bottom(preset):
    from cogniframe.export.mesh import ray_first_hit
    from cogniframe.parts.joint_plan import map_sockets

    d = built_preset(preset)
    for name, part in d.parts.items():
        for s in map_sockets(part, d.built[name].print_from_local) if part.sockets else []:
            start = s.mouth + s.direction * 2.0
            hit = ray_first_hit(d.meshes[name], [start], [-s.direction])[0]
            assert hit == pytest.approx(2.0 + s.depth, abs=0.05), f"{name} {s.rod}"


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_no_rod_intersects_a_printed_part(preset):
    from cogniframe.export.assembly import press_fits
    from cogniframe.export.mesh import intersection_volume

    d = built_preset(preset)
    parts = _world(d)
    # a rod pressed into its blind socket (joints.fit_clearance < 0) overlaps it by the designed
    # ring pi/4 (d^2 - bore^2) x depth, and by no more
    pressed = press_fits(d.spec, d.frame)
    checked = 0
    for rod in d.frame.rods.values():
        rm = _rod_mesh(rod)
        for inst, _, mesh, _ in parts:
            lo = np.maximum(rm.bounds[0], mesh.bounds[0])
            hi = np.minimum(rm.bounds[1], mesh.bounds[1])
            if np.any(lo > hi):
                continue
            v = intersection_volume(rm, mesh)
            assert v < VOLUME_TOL + pressed.get(frozenset((inst, rod.name)), 0.0), f"{rod.name} cuts {v:.2f} mm^3 into {inst}"
            checked += 1
    assert checked >= 2 * len(d.frame.rods)  # at least both joints of every rod were really tested


@pytest.mark.cad
def test_the_intersection_check_sees_a_rod_in_the_wrong_place():
    """Negative control: a rod shifted 1 mm sideways into its socket wall is caught."""
    from cogniframe.export.mesh import intersection_volume

    d = built_preset("carbon")
    rod = d.frame.rods["rod_cage_top_front"]
    bad = _rod_mesh(rod)
    bad.apply_translation([0, 0, 1.0])
    knee = [m for inst, _, m, _ in _world(d) if inst == "corner_top_fl"][0]
    assert intersection_volume(bad, knee) > 10


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.cad
def test_part_quantities_match_the_frame_graph(preset):
    d = built_preset(preset)
    kinds = Counter(n.kind for n in d.frame.nodes.values())
    for kind, count in kinds.items():
        of_kind = [p for p in d.parts.values() if dict(p.params).get("kind", p.name) == kind]  # core_link + its mirror image
        assert sum(p.qty for p in of_kind) == count
        assert {pl.instance for p in of_kind for pl in p.placements} == {n for n, x in d.frame.nodes.items() if x.kind == kind}
    assert d.parts["motor_mount"].qty == len(d.frame.motors)
    for core in ("core_plate", "battery_holder"):
        assert d.parts[core].qty == 1
    assert ("computer_mount" in d.parts) == (d.spec.core.computer is not None)
    assert sum(len(p.sockets) * p.qty for p in d.parts.values()) == 2 * len(d.frame.rods)


@pytest.mark.cad
def test_rod_diameter_drives_every_bore_and_the_cut_list(tmp_path):
    """3 -> 4 mm rods: every socket hole measured on the STL grows by 1 mm; the cut list follows."""
    from cogniframe import cutlist, frame as frame_mod, partlist, spec as spec_mod
    from cogniframe.export.part_files import build_parts
    from cogniframe.export.mesh import load_stl, ray_first_hit
    from cogniframe.parts.joint_plan import map_sockets

    def bores(spec, out):
        fr = frame_mod.frame_of(spec)
        parts = [p for p in partlist.part_list(spec, fr) if p.family == "joint"]
        built = build_parts(spec, fr, parts, out)
        found = []
        for p, b in zip(parts, built):
            mesh = load_stl(out / b.stl)
            for s in map_sockets(p, b.print_from_local):
                mid = s.at(s.seat + s.depth / 2)
                u = np.cross(s.direction, [0.3, 0.5, 0.8])
                u /= np.linalg.norm(u)
                dirs = np.array([u, -u, np.cross(s.direction, u), -np.cross(s.direction, u)])
                found.append(2 * ray_first_hit(mesh, np.tile(mid, (4, 1)), dirs).mean())
        return np.array(found), cutlist.cut_list(spec, fr), fr

    base = spec_mod.load(__import__("test_parts").ROOT / "params" / "carbon.yaml")
    data = base.model_dump(mode="json")
    data["rods"]["diameter"] = 4.0
    data["joints"]["wall"] = 1.6  # a 4 mm rod needs 40 % of its diameter in TPU (spec rule)
    thick = spec_mod.from_dict(data)
    b3, cut3, f3 = bores(base, tmp_path / "d3")
    b4, cut4, f4 = bores(thick, tmp_path / "d4")
    assert b3 == pytest.approx(3.0 + base.fit_clearance, abs=0.02)
    assert b4 == pytest.approx(4.0 + thick.fit_clearance, abs=0.02)
    for cut, fr, d in ((cut3, f3, 3.0), (cut4, f4, 4.0)):
        # the cut list is the frame's rods, each cut to the length between its two socket bottoms
        assert sum(row.qty for row in cut.rows) == len(fr.rods)
        for row in cut.rows:
            assert row.diameter_mm == d
            assert {fr.rods[n].cut_length for n in row.rods} == {row.length_mm}
    assert sorted(r.length_mm for r in cut3.rows) != sorted(r.length_mm for r in cut4.rows)

"""Frame graph: layout, names, symmetry, seats, cut lengths vs geometry, propeller clearance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cogniframe import frame as frame_mod
from cogniframe import spec as spec_mod
from cogniframe.errors import UserError


def test_counts_and_roles(preset):
    f = frame_mod.frame_of(preset)
    roles = [r.role for r in f.rods.values()]
    assert (roles.count("cage"), roles.count("leg"), roles.count("arm"), roles.count("strut")) == (8, 8, 8, 4)
    kinds = [n.kind for n in f.nodes.values()]
    assert {k: kinds.count(k) for k in set(kinds)} == {"corner_top": 4, "corner_bottom": 4, "knee": 4, "core_link": 4}
    assert len(f.motors) == 4


def test_readable_stable_names(carbon):
    f = frame_mod.frame_of(carbon)
    assert {"knee_fl", "corner_top_rr", "core_link_rl"} <= set(f.nodes)
    assert {"rod_cage_top_front", "rod_cage_bottom_left", "rod_leg_upper_fr", "rod_arm_fl_2", "rod_strut_rl"} <= set(f.rods)
    assert list(f.rods) == list(frame_mod.frame_of(carbon).rods)  # deterministic order


def test_box_extent_is_the_outside_size(carbon):
    f = frame_mod.frame_of(carbon)
    lo, hi = f.bbox()
    outer = carbon.bore / 2 + carbon.joints.wall  # joint wall beyond the node
    assert hi[0] - lo[0] + 2 * outer == pytest.approx(carbon.frame.width)
    assert hi[1] - lo[1] + 2 * outer == pytest.approx(carbon.frame.depth)
    assert hi[2] - lo[2] + 2 * outer == pytest.approx(carbon.frame.height)
    assert lo[2] - outer == pytest.approx(f.ground_z)


def test_incidence_is_consistent(preset):
    f = frame_mod.frame_of(preset)
    for r in f.rods.values():
        assert r.name in f.nodes[r.a.node].rods and r.name in f.nodes[r.b.node].rods
    assert sum(len(n.rods) for n in f.nodes.values()) == 2 * len(f.rods)


def test_fourfold_symmetry(preset):
    f = frame_mod.frame_of(preset)
    rot = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]])  # -90 deg about z: fl -> fr -> rr -> rl
    for a, b in (("fl", "fr"), ("fr", "rr"), ("rr", "rl"), ("rl", "fl")):
        for kind in ("corner_top", "corner_bottom", "knee", "core_link"):
            np.testing.assert_allclose(rot @ np.array(f.nodes[f"{kind}_{a}"].pos), f.nodes[f"{kind}_{b}"].pos, atol=1e-9)
        assert f.rods[f"rod_strut_{a}"].length == pytest.approx(f.rods[f"rod_strut_{b}"].length)
        assert f.rods[f"rod_arm_{a}_1"].length == pytest.approx(f.rods[f"rod_arm_{b}_2"].length)


def test_hourglass_knees_bow_inwards(carbon):
    f = frame_mod.frame_of(carbon)
    top, knee, bottom = (np.array(f.nodes[f"{k}_fl"].pos) for k in ("corner_top", "knee", "corner_bottom"))
    assert abs(knee[0]) == pytest.approx(abs(top[0]) - carbon.frame.knee_inset)
    assert knee[2] == pytest.approx(carbon.frame.height / 2, abs=0.5)  # level arms: the knee follows the plate to 1 mm
    assert abs(bottom[0]) == pytest.approx(abs(top[0]))


def test_level_arms_hang_the_plate_at_the_knees_on_whole_mm_standoffs(carbon):
    f = frame_mod.frame_of(carbon)
    for k in ("fl", "fr", "rr", "rl"):
        for i in (1, 2):
            r = f.rods[f"rod_arm_{k}_{i}"]
            assert r.a.port[2] == pytest.approx(r.b.port[2], abs=1e-9)  # a level arm
    assert all(m.arm_slope_deg == pytest.approx(0.0, abs=1e-9) for m in f.motors)
    c = f.core
    assert c.hang == round(c.hang) and c.hang > 0
    # the standoffs span the gap between the spacer's top and the plate's underside exactly
    assert c.plate.lo[2] - c.spacer.hi[2] == pytest.approx(c.hang)
    assert f.nodes["knee_fl"].pos[2] == pytest.approx(c.plate.centre[2] - frame_mod.peg_drop(carbon))  # the pegs' tubes under it
    sitting = carbon.model_copy(update={"frame": carbon.frame.model_copy(update={"level_arms": False})})
    g = frame_mod.frame_of(sitting)
    assert g.core.hang == 0 and g.core.plate.lo[2] == pytest.approx(g.core.spacer.hi[2])
    assert g.nodes["knee_fl"].pos[2] == pytest.approx(carbon.frame.height / 2)
    assert g.motors[0].arm_slope_deg > 10  # the knee above the plate: the arm climbs to it


def test_level_arms_below_the_battery_stack_name_the_key(carbon):
    from cogniframe.errors import UserError

    low = carbon.model_copy(update={"frame": carbon.frame.model_copy(update={"knee_height": 0.25})})
    with pytest.raises(UserError) as e:
        frame_mod.frame_of(low)
    assert "frame.knee_height" in str(e.value) and "level_arms: false" in str(e.value)


def test_cut_length_is_distance_minus_seats(carbon):
    f = frame_mod.frame_of(carbon)
    r = f.rods["rod_cage_top_front"]
    a, b = f.nodes["corner_top_fl"].pos, f.nodes["corner_top_fr"].pos
    assert r.length == pytest.approx(math.dist(a, b) - 2 * f.nodes["corner_top_fl"].seat)
    assert r.cut_length == round(r.length * 2) / 2
    assert np.linalg.norm(r.end - r.start) == pytest.approx(r.length)


def test_arm_rods_are_parallel_and_spaced(carbon):
    f = frame_mod.frame_of(carbon)
    r1, r2 = f.rods["rod_arm_fl_1"], f.rods["rod_arm_fl_2"]
    np.testing.assert_allclose(r1.axis, r2.axis, atol=1e-12)
    assert np.linalg.norm(np.subtract(r1.a.port, r2.a.port)) == pytest.approx(carbon.frame.arm_spacing)


# The seat rule at a node takes each rod's direction node to node; a pegged link's strut leaves its
# link from a port moved outboard onto the arch (frame.pegged_strut_port), so at the bottom corner
# it is 2 deg steeper than the rule assumes and the carbon foot's seat is 0.26 mm short of keeping
# the strut's bore off the leg's (4.71 against 4.97 mm). The fix (the rule on the rods' real ports)
# changes the bottom corners' geometry, so their surrogate family is retrained with it.
@pytest.mark.xfail(strict=True, reason="the seat rule takes the strut's direction from the link's node, not its port")
def test_seat_raised_where_rods_meet_at_sharp_angles(carbon):
    f = frame_mod.frame_of(carbon)
    # Strut and lower leg leave the foot in the same plane at a narrow angle: their bores must not meet.
    foot = f.nodes["corner_bottom_fl"]
    r = carbon.bore / 2 + carbon.joints.wall / 2
    needs = []
    for i, a in enumerate(foot.rods):
        for b in foot.rods[i + 1:]:
            ang = math.acos(np.dot(f.rods[a].socket_direction(foot.name), f.rods[b].socket_direction(foot.name)))
            needs.append(r / math.tan(ang / 2))
    leg, strut = f.rods["rod_leg_lower_fl"], f.rods["rod_strut_fl"]
    ang = math.acos(np.dot(leg.socket_direction(foot.name), strut.socket_direction(foot.name)))
    assert foot.seat >= r / math.tan(ang / 2) > carbon.joints.seat
    assert foot.seat == pytest.approx(max(needs), abs=0.01)  # the sharpest pair decides
    assert f.nodes["corner_top_fl"].seat == carbon.joints.seat  # 90 degree corners need no more


def test_parallel_sockets_side_by_side_keep_the_base_seat(carbon):
    # Arm rods reach the core link 6 mm beside the strut, more than bore + 2 walls: no clash.
    f = frame_mod.frame_of(carbon)
    assert carbon.frame.arm_spacing / 2 >= carbon.bore + 2 * carbon.joints.wall
    assert f.nodes["core_link_fl"].seat == carbon.joints.seat


def test_carbon_rods_resemble_the_papers(carbon):
    f = frame_mod.frame_of(carbon)
    cage = [r.cut_length for r in f.rods_of("cage")]
    assert len(cage) == 8 and all(abs(c - 195) <= 5 for c in cage)  # paper: 8 x 195
    arms = [r.cut_length for r in f.rods_of("arm")]
    assert len(arms) == 8 and all(abs(a - 97) <= 0.15 * 97 for a in arms)  # paper: 8 x 97


def test_bamboo_rods_resemble_the_build(bamboo):
    f = frame_mod.frame_of(bamboo)
    for role, target in (("cage", 230), ("leg", 50), ("arm", 110)):
        for r in f.rods_of(role):
            assert abs(r.cut_length - target) <= 0.06 * target, (r.name, r.cut_length, target)
    # The struts run from the bottom corners up to the core links at the knees' height. The
    # authors' connectors stand on a 64.5 mm plus-shaped base, cogniframe's links at the corners of
    # a 40 mm plate, about 11 mm further in along the strut: 130 mm is not the reference for their
    # length, only a floor (docs/authors-parts.md).
    for r in f.rods_of("strut"):
        assert 130 < r.cut_length < 130 + 12, (r.name, r.cut_length)


def test_clearance_from_geometry_is_the_holder_underside(preset):
    f = frame_mod.frame_of(preset)
    assert f.clearance_mm == pytest.approx(preset.core.battery_clearance)
    assert f.core.battery.lo[2] > f.core.holder.lo[2]


def test_rod_diameter_changes_bore_and_cut_lengths(carbon):
    data = carbon.model_dump()
    data["rods"]["diameter"] = 4.0
    data["joints"]["wall"] = 1.6  # a 4 mm rod needs 40 % of its diameter in TPU
    f3, f4 = frame_mod.frame_of(carbon), frame_mod.frame_of(spec_mod.from_dict(data))
    assert all(r.diameter == 4.0 for r in f4.rods.values())
    # the joint grows with the bore, so the ring nodes move in and the ring rods get shorter
    assert f4.rods["rod_cage_top_front"].length < f3.rods["rod_cage_top_front"].length


def test_prop_clearance_positive_and_reported(preset):
    f = frame_mod.frame_of(preset)
    assert len(f.prop_clearances) == 4
    assert f.min_prop_margin > 0


def test_prop_disc_distance_matches_hand_calculation():
    centre, radius = np.array([0.0, 0.0, 10.0]), 5.0
    pts = np.array([[3.0, 0.0, 12.0], [8.0, 0.0, 10.0], [9.0, 0.0, 13.0]])
    np.testing.assert_allclose(frame_mod._point_to_disc(pts, centre, radius), [2.0, 3.0, 5.0])
    box = frame_mod.Box("b", (20.0, 0.0, 10.0), (4.0, 4.0, 4.0))
    assert frame_mod._box_to_disc(box, centre, radius) == pytest.approx(13.0, abs=0.05)


def test_big_propellers_are_a_clear_error(carbon):
    data = carbon.model_dump()
    data["motors"]["prop_diameter"] = 180
    with pytest.raises(UserError, match=r"propeller of motor_.. hits the frame.*motors.prop_diameter"):
        frame_mod.frame_of(spec_mod.from_dict(data))


def test_motor_off_the_arm_is_a_clear_error(carbon):
    data = carbon.model_dump()
    data["motors"]["radius"] = 200
    with pytest.raises(UserError, match="motors.radius"):
        frame_mod.frame_of(spec_mod.from_dict(data))


def test_rod_axis_and_ends_computed_once_are_the_ports_geometry_and_read_only():
    # a 3-4-12 rod: |(3, 4, 12)| = 13, so axis = (3, 4, 12) / 13 and the ends sit `seat` along it
    a = frame_mod.RodEnd("n0", (1.0, 2.0, 3.0), 2.0, 5.0)
    b = frame_mod.RodEnd("n1", (4.0, 6.0, 15.0), 1.5, 5.0)
    r = frame_mod.Rod("rod_x", "cage", a, b, 6.0, "carbon")
    np.testing.assert_allclose(r.axis, np.array([3.0, 4.0, 12.0]) / 13, rtol=0, atol=1e-15)
    assert r.centre_distance == pytest.approx(13.0, rel=1e-15)
    assert r.length == pytest.approx(13.0 - 2.0 - 1.5, rel=1e-15)
    np.testing.assert_allclose(r.start, np.array([1.0, 2.0, 3.0]) + 2.0 * np.array([3.0, 4.0, 12.0]) / 13, atol=1e-14)
    np.testing.assert_allclose(r.end, np.array([4.0, 6.0, 15.0]) - 1.5 * np.array([3.0, 4.0, 12.0]) / 13, atol=1e-14)
    np.testing.assert_array_equal(r.socket_direction("n1"), -r.axis)
    # shared arrays: a caller cannot change the rod for the next one
    with pytest.raises(ValueError):
        r.axis[0] = 1.0
    with pytest.raises(ValueError):
        r.start += 1.0
    # not fields: equality and hashing are the dataclass's own
    assert r == frame_mod.Rod("rod_x", "cage", a, b, 6.0, "carbon")
    assert hash(r) == hash(frame_mod.Rod("rod_x", "cage", a, b, 6.0, "carbon"))

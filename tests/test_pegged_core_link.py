"""The pegged core link (`core.link: pegs`): the authors' connector as an option of the core link.
Per arm a TPU column round the socket and a solid peg beyond it, pressed into an ABS bore; an arch
joining the columns; the strut's own peg and column, its sleeve leaning out of that column. It must
be one watertight solid standing on its pegs' ends that prints with no support, its closed form
must follow its CAD, its mirrored part must be its mirror image, and its joint FE must hold the
arm pair as the authors' connector with a middle peg does (tools/pegged_link_fe.py) and the strut
at least as stiffly as the tab link."""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest

from conftest import ROOT
from presets import preset_spec

from cogniframe import design as design_mod
from cogniframe.families.joint import PEGS

_spec = importlib.util.spec_from_file_location("pegged_link_fe", ROOT / "tools" / "pegged_link_fe.py")
pl = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = pl  # its dataclass looks its module up there
_spec.loader.exec_module(pl)


def _links(spec):
    return {p.name: p for p in design_mod.design(spec).parts if dict(p.params).get("kind", p.name) == "core_link"}


def _pegs_spec(name="carbon", **changes):
    return preset_spec(name, core__link="pegs", **changes)


def test_the_default_is_the_tab_link_and_pegs_drop_its_screw():
    """The key defaults to the tab link (the presets do not set it); a pegged link has no screw,
    no bolt hole and no hardware line, and carries the authors' dimensions."""
    assert preset_spec("carbon").core.link == "tab"
    tab = _links(preset_spec("carbon"))["core_link"]
    assert dict(tab.params).get("bolt_hole") is not None and tab.hardware
    for p in _links(_pegs_spec()).values():
        params = dict(p.params)
        assert params["link"] == "pegs" and "bolt_hole" not in params and "screw" not in params
        assert p.hardware == ()
        assert (params["peg_d"], params["peg_len"], params["column_wall"], params["arch_depth"]) == (6.8, 9.0, 1.8, 6.7)
    assert dict(PEGS)["column_wall"] == pytest.approx((6.79 - 3.19) / 2, abs=0.01)  # the authors' connector


def test_the_closed_form_is_the_connectors_cylinders_arch_and_strut_by_hand():
    """Carbon (2.85 mm bores, 8 mm sockets, 25 mm pair): three pegs (r 3.4, 9 mm), two arm columns
    (r 1.425 + 1.8, 8.3 mm) and the strut's column (as wide as its peg, from the shoulder to under
    the strut's mouth), the arch 25 x 6.7 x 3 less the two half arm columns and the strut column's
    part in it (a disc less the segment past the arch's face), the strut's sleeve (r 3.225, 9.8 mm)
    less what is not its own, less three sockets: the hand sum with the sleeve's overlap taken
    from the plan."""
    from cogniframe.parts.peg_plan import pegged_plan

    p = _links(_pegs_spec())["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    rc, rp = 1.425 + 1.8, 3.4
    assert plan.col_r == pytest.approx(rc) and plan.peg_r == pytest.approx(rp) and plan.spacing == pytest.approx(25.0, abs=1e-6)
    assert len(plan.columns) == 3 and len(plan.struts) == 1
    mid = plan.columns[plan.struts[0].column]
    assert mid.col_r == rp and [c.col_r for c in plan.columns if c is not mid] == [rc, rc]
    overlap = plan.struts[0].overlap
    assert 0 < overlap < math.pi * rc**2 * 9.8  # most of the sleeve is in its column
    # the strut column in the arch: its disc less the segment beyond the arch's +y face
    d = plan.arch_n[1] - float(mid.axis[1])
    segment = rp**2 * math.acos(d / rp) - d * math.sqrt(rp**2 - d**2)
    in_arch = (math.pi * rp**2 - segment) * (mid.col1 - 14.3)
    by_hand = (3 * math.pi * rp**2 * 9 + math.pi * rc**2 * 2 * 8.3 + math.pi * rp**2 * (mid.col1 - 9.0)
               + (25 * 6.7 - math.pi * rc**2) * 3 - in_arch + math.pi * rc**2 * 9.8 - overlap - 3 * math.pi * 1.425**2 * 8)
    assert p.estimate.volume == pytest.approx(by_hand, rel=1e-3)


def _strut_bore_below_shoulder(p, plan):
    """Points of the strut's bore (print coordinates) at or below the pegs' shoulder: its wall
    and floor, sampled from the socket alone."""
    from cogniframe.parts.joint_plan import map_sockets, print_from_local

    s = next(s for s in map_sockets(p, print_from_local(p)) if "strut" in s.rod)
    d = np.asarray(s.direction, float)
    a = np.cross(d, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(d, a)
    ring = a[:, None] * np.cos(np.linspace(0, 2 * np.pi, 181)) + b[:, None] * np.sin(np.linspace(0, 2 * np.pi, 181))
    t = np.linspace(s.seat, s.seat + s.depth, 801)
    port = np.asarray(s.port, float)
    wall = port[:, None, None] + d[:, None, None] * t[None, :, None] + s.bore / 2 * ring[:, None, :]
    floor = (port + d * s.seat)[:, None, None] + np.linspace(0, s.bore / 2, 8)[None, :, None] * ring[:, None, :]
    pts = np.hstack([wall.reshape(3, -1), floor.reshape(3, -1)])
    return pts[:, pts[2] <= plan.columns[0].col0 + 1e-9]


@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
def test_the_strut_has_its_own_peg_parallel_to_the_arms_round_its_bore(preset):
    """The plan's columns are the core's pegs (the core plate's peg tubes are built from them): three,
    all standing on the bed (z 0..9, the shoulder where the arms' are), the same radius, axes all
    upright in print (parallel: the link presses in along one direction), the third holding the
    strut's socket. The strut's bore dips below the shoulder into that peg: sampled from the
    socket alone, it lies within the peg with at least the columns' 1.8 mm of TPU round it, and
    the peg's axis is where that TPU is thickest (a 0.05 mm move any way thins it)."""
    from cogniframe.parts.peg_plan import pegged_plan

    p = _links(_pegs_spec(preset))["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    assert [(c.peg0, c.col0) for c in plan.columns] == [pytest.approx((0.0, 9.0))] * 3
    strut = next(i for i, s in enumerate(p.sockets) if "strut" in s.rod)
    mid = plan.columns[plan.struts[0].column]
    assert mid.socket == strut and plan.struts[0].index == strut
    assert [c.socket for c in plan.columns if c is not mid] == [i for i, s in enumerate(p.sockets) if "arm" in s.rod]
    assert float(mid.axis[0]) == pytest.approx(0.0, abs=1e-6)  # the strut leaves the pair's middle
    pts = _strut_bore_below_shoulder(p, plan)
    assert pts.shape[1] > 100  # the bore does dip into the peg

    def reach(c):
        return float(np.max(np.hypot(pts[0] - c[0], pts[1] - c[1])))

    assert 3.4 - reach(mid.axis) >= 1.8
    assert 3.4 - reach(mid.axis) == pytest.approx(plan.struts[0].wall, abs=0.01)
    for ang in np.arange(8) * np.pi / 4:
        assert reach(mid.axis + 0.05 * np.array([np.cos(ang), np.sin(ang)])) > reach(mid.axis) - 1e-3
    # the pegs' bores in the core stay apart: 12.5 mm between axes less a peg, 5.7 mm of ABS
    gaps = [float(np.linalg.norm(mid.axis - c.axis)) - 6.8 for c in plan.columns if c is not mid]
    assert min(gaps) > 5.5


def test_pegs_too_close_for_the_cores_bores_are_refused_naming_the_key():
    """At 14 mm between the arms the strut's peg (6.8 mm) would stand 0.4 mm from an arm's: the
    core's bores would run together, so the params are refused naming core.link and the fix."""
    from cogniframe.errors import UserError

    with pytest.raises(UserError) as e:
        _links(_pegs_spec(frame__arm_spacing=14))
    msg = str(e.value)
    assert "core.link" in msg and "2.8 mm of ABS" in msg and "frame.arm_spacing" in msg
    # at 18 mm the bores keep 2.3 mm apart, but the plate's tubes round them (1.2 mm walls and a
    # line of gap: 2.8 mm) would run into each other
    with pytest.raises(UserError):
        _links(_pegs_spec(frame__arm_spacing=18))
    assert len(_links(_pegs_spec(frame__arm_spacing=20))) == 2


@pytest.mark.slow
def test_pegged_link_is_one_watertight_solid_standing_on_its_pegs(tmp_path):
    """Carbon with core.link: pegs, both parts: one watertight solid, its closed form within 2 % of
    the CAD (exact but for the mouths' chamfers; test_parts allows the joints 15 %) and its
    envelope within 0.1 mm of the CAD's box; in print the arms point up (+z), nothing is below
    the bed and what lies on it is the three pegs' ends (their discs, faceted); the mirrored part
    has the same volume and the mirrored box."""
    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry
    from cogniframe.parts.joint_plan import map_sockets, print_from_local
    from cogniframe.parts.peg_plan import pegged_plan

    spec = _pegs_spec()
    links = _links(spec)
    assert set(links) == {"core_link", "core_link_mirrored"}
    vols, boxes = {}, {}
    for name, p in links.items():
        built = registry.solid(p)
        mesh = write_stl(built.shape, tmp_path / f"{name}.stl", name=name)  # raises unless watertight
        assert mesh.body_count == 1
        vol = built.shape.Volume()
        assert p.estimate.volume == pytest.approx(vol, rel=0.02)
        bb = built.shape.BoundingBox()
        assert sorted(p.estimate.envelope) == pytest.approx(sorted([bb.xlen, bb.ylen, bb.zlen]), abs=0.1)
        assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
        arms = [s for s in map_sockets(p, print_from_local(p)) if "arm" in s.rod]
        assert len(arms) == 2 and all(s.direction == pytest.approx([0.0, 0.0, 1.0], abs=1e-6) for s in arms)
        # the faces on the bed: the pegs' three end discs, around the columns' axes
        plan = pegged_plan(p.sockets, dict(p.params))
        tri = mesh.vertices[mesh.faces]
        on_bed = np.all(np.abs(tri[:, :, 2]) < 1e-6, axis=1)
        area = 0.5 * np.linalg.norm(np.cross(tri[on_bed, 1] - tri[on_bed, 0], tri[on_bed, 2] - tri[on_bed, 0]), axis=1).sum()
        assert area == pytest.approx(3 * math.pi * 3.4**2, rel=0.03)
        centres = np.array([c.axis for c in plan.columns])
        dist = np.linalg.norm(tri[on_bed][:, :, :2].reshape(-1, 2)[:, None, :] - centres[None], axis=2).min(axis=1)
        assert dist.max() <= 3.4 + 1e-6
        vols[name], boxes[name] = vol, (bb.xmin, bb.xmax, bb.ymin, bb.ymax, bb.zmin, bb.zmax)
    assert vols["core_link_mirrored"] == pytest.approx(vols["core_link"], rel=1e-9)
    x0, x1, *rest = boxes["core_link"]
    assert boxes["core_link_mirrored"] == pytest.approx((-x1, -x0, *rest), abs=1e-6)


def test_mirrored_pegged_link_is_found_as_the_mirror_image():
    """The FE reflects the mirrored link's super-element from its original's (`mirror_original`):
    that needs the two print orientations to be mirror images on the bed."""
    from cogniframe.analysis.joints import mirror_original

    links = _links(_pegs_spec())
    found = mirror_original(links["core_link_mirrored"], list(links.values()))
    assert found is not None and found[0].name == "core_link"
    assert np.linalg.det(found[1]) == pytest.approx(-1.0)


@pytest.mark.slow
def test_pegged_link_hinge_matches_the_authors_connector_in_the_same_fe():
    """The arm pair's hinge (`load_cases.arm_pair_hinge` on the link's FE, the pegs' sides and ends
    tied to the core) against tools/pegged_link_fe.py's `connector_hinge` of a `Connector` with
    the same dimensions (the preset's bore and socket, 1.8 mm walls, the 6.8 x 9 mm pegs, the arch
    over the columns' outer 3 mm, the strut's peg and column where the plan puts them): the same
    physics, within 10 % (the strut's leaning sleeve and the arch's exact extent differ); above
    the authors' connector's without the strut's peg (which holds the arch's middle), and far above
    the tab link's (75 N mm/rad, test_pegged_link_fe.py)."""
    from dataclasses import replace

    from cogniframe.analysis.joints.fe import fe_joint
    from cogniframe.analysis.load_cases import arm_pair_hinge
    from cogniframe.parts.peg_plan import pegged_plan

    spec = _pegs_spec()
    link = _links(spec)["core_link"]
    hinge = arm_pair_hinge({link.name: fe_joint(spec, link)}, [link])
    plan = pegged_plan(link.sockets, dict(link.params))
    depth = spec.joints.socket_depth
    conn = pl.Connector(spacing=spec.frame.arm_spacing, peg_d=6.8, peg_len=9.0, column_d=spec.bore + 3.6, column_len=depth + 0.3,
                        bore=spec.bore, depth=depth, arch_z=(depth + 0.3 - 3.0, depth + 0.3),
                        mid_peg_y=float(plan.columns[plan.struts[0].column].axis[1]))
    ref, _ = pl.connector_hinge(spec, conn)
    assert hinge == pytest.approx(ref, rel=0.10)
    no_mid, _ = pl.connector_hinge(spec, replace(conn, mid_peg_y=None))
    assert hinge > no_mid
    flat, _ = pl.flat_link_hinge(preset_spec("carbon"))
    assert hinge > 3 * flat


@pytest.mark.slow
def test_the_core_holds_the_pegs_sides_and_ends_only():
    """The support body's tie in the joint FE is the pegs' cylindrical sides and inner ends, the
    faces the ABS bores hold: its meshed area is the three pegs' (the arms' and the strut's)
    3 (2 pi r L + pi r^2) (r 3.4, L 9: 686 mm^2), within the faceting of the mesh; the rods' ties
    are the sockets'."""
    from cogniframe.analysis.joints import solid_fe
    from cogniframe.analysis.joints.fe import joint_problem

    spec = _pegs_spec()
    link = _links(spec)["core_link"]
    pb = joint_problem(spec, link)
    assert pb.labels[-1] == "body"
    area = solid_fe.assemble(pb.points, pb.tets, pb.e, pb.nu, list(pb.ties)).tied_area
    assert area[-1] == pytest.approx(3 * (2 * math.pi * 3.4 * 9.0 + math.pi * 3.4**2), rel=0.03)
    # each rod's socket: its wall over the depth less the chamfer, and its floor
    bore, depth = spec.bore, spec.joints.socket_depth - 0.5
    for a in area[:-1]:
        assert a == pytest.approx(math.pi * bore * depth + math.pi * bore**2 / 4, rel=0.05)


def _strut_axial(js, part) -> float:
    """The strut socket's stiffness (N/mm) along its axis in a core link's super-element: the
    support body held, the arms and the strut's rotations free."""
    labs = list(js.labels)
    K = np.asarray(js.matrix, float)
    body, strut = labs.index("body"), next(i for i, lab in enumerate(labs) if "strut" in lab)
    keep = [6 * strut + k for k in range(6)]
    free = [6 * i + k for i in range(len(labs)) if i not in (strut, body) for k in range(6)]
    K_ss = K[np.ix_(keep, keep)] - K[np.ix_(keep, free)] @ np.linalg.solve(K[np.ix_(free, free)], K[np.ix_(free, keep)])
    d = np.asarray(next(s for s in part.sockets if "strut" in s.rod).direction, float)
    return 1.0 / float(d @ np.linalg.inv(K_ss)[:3, :3] @ d)


@pytest.mark.slow
def test_the_strut_pushes_on_its_own_peg_at_least_as_stiffly_as_on_the_tab():
    """The payload rests on the struts: their sockets' axial stiffness in the core link (the
    support held, `_strut_axial`) carries the frame's k. On its own peg the pegged link's strut is
    stiffer than the tab link's (9.85 N/mm on carbon; hung on the arch it was 0.56)."""
    from cogniframe.analysis.joints.fe import fe_joint

    tab_spec, peg_spec = preset_spec("carbon"), _pegs_spec()
    tab, peg = _links(tab_spec)["core_link"], _links(peg_spec)["core_link"]
    k_tab = _strut_axial(fe_joint(tab_spec, tab), tab)
    k_peg = _strut_axial(fe_joint(peg_spec, peg), peg)
    assert k_tab == pytest.approx(9.85, rel=0.05)
    assert k_peg > k_tab


def _layers(mesh, dz: float, px: float):
    """The print-oriented mesh's layers (every `dz` from dz / 4 up: off the parts' faces at whole
    and half millimetres) as boolean rasters of `px`
    pixels: each layer's outline (the mesh cut by its plane) filled by the even-odd rule along
    each row of pixel centres. Returns (rasters z, y, x; the layers' heights; x0, y0)."""
    import trimesh

    (x0, y0, _), (x1, y1, z1) = mesh.bounds
    xs = x0 - px + px * (np.arange(int((x1 - x0) / px) + 3) + 0.5)
    ys = y0 - px + px * (np.arange(int((y1 - y0) / px) + 3) + 0.5)
    zs = dz / 4 + dz * np.arange(int(z1 / dz))
    out = np.zeros((len(zs), len(ys), len(xs)), bool)
    for k, z in enumerate(zs):
        seg = trimesh.intersections.mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z])  # (n, 2, 3)
        (ax, ay), (bx, by) = seg[:, 0, :2].T, seg[:, 1, :2].T
        for j, y in enumerate(ys):
            hit = (ay <= y) != (by <= y)
            cx = np.sort(ax[hit] + (y - ay[hit]) * (bx[hit] - ax[hit]) / (by[hit] - ay[hit]))
            for u, v in zip(cx[0::2], cx[1::2]):
                out[k, j] |= (xs > u) & (xs < v)
    return out, zs, xs[0], ys[0]


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
def test_the_pegged_link_prints_with_no_support(preset, tmp_path):
    """Sliced every 0.2 mm (0.05 mm pixels), the standing link has no floating island: every piece
    of a layer touches the layer below. And nothing overhangs more than 45 deg (a layer grows at
    most one layer height, plus a pixel, past the one below) but the arch's underside, which
    bridges from column to column (the authors' connector prints it so): the strut sleeve's back
    end stands on its peg."""
    from scipy import ndimage

    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry
    from cogniframe.parts.peg_plan import pegged_plan

    p = _links(_pegs_spec(preset))["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    mesh = write_stl(registry.solid(p).shape, tmp_path / "link.stl", name=p.name)
    dz, px = 0.2, 0.05
    layers, zs, x0, y0 = _layers(mesh, dz, px)
    assert layers[0].sum() * px**2 == pytest.approx(3 * math.pi * 3.4**2, rel=0.02)  # the three pegs' ends
    bridge = []
    for k in range(1, len(zs)):
        below, here = layers[k - 1], layers[k]
        lab, n = ndimage.label(here)
        assert all((below & (lab == i)).any() for i in range(1, n + 1)), f"an island floats at z {zs[k]:.1f}"
        past = here & (ndimage.distance_transform_edt(~below) > dz / px + 1)
        if past.any():
            j, i = np.nonzero(past)
            bridge.append((zs[k], x0 + px * i, y0 + px * j, past.sum() * px**2))
    # the only overhang: the arch's first layer, between the columns, within the arch's footprint
    assert len(bridge) == 1
    z, x, y, area = bridge[0]
    assert plan.arch_lo < z < plan.arch_lo + dz
    assert plan.arch_x[0] < x.min() and x.max() < plan.arch_x[1]
    assert plan.arch_n[0] - px < y.min() and y.max() < plan.arch_n[1] + px
    assert area > 50.0


def test_surrogate_leaves_the_pegged_link_to_the_fe_and_says_so():
    """The pegged link is its own surrogate family (`family_of`), which the shipped fit does not
    hold yet: a pegged link (and its mirror, which follows its original) is solved by the FE, and
    `check` notes it."""
    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints import surrogate_notes

    spec = _pegs_spec()
    parts = [p for p in design_mod.design(spec).parts if p.family == "joint"]
    why = sg.outside_reasons(spec, parts)
    assert why["core_link"] == "no surrogate for core_link_pegs joints"
    assert why["core_link_mirrored"] == "its original core_link is outside"
    link = next(p for p in parts if p.name == "core_link")
    assert sg.family_of(link) == "core_link_pegs"
    assert sg.predict(spec, link) == (None, why["core_link"])
    notes = surrogate_notes(spec, parts)
    assert any(n.startswith("joint core_link:") and "core_link_pegs" in n and "solid FE" in n for n in notes)
    # the tab link stays inside (the presets' joints are in the training box)
    tab = [p for p in design_mod.design(preset_spec("carbon")).parts if p.family == "joint"]
    assert not [n for n in sg.outside_reasons(preset_spec("carbon"), tab) if "core_link" in n]
    assert {sg.family_of(p) for p in tab} == {"corner_top", "corner_bottom", "knee", "core_link"}


def test_analytic_model_refuses_the_pegged_link_naming_the_key():
    """No closed form models the pegs: the params are refused (the key and the fix named), and the
    closed-form joint itself refuses rather than use the tab link's formulas."""
    from cogniframe.analysis.joints import analytic_joint
    from cogniframe.errors import UserError
    from presets import preset_doc
    from cogniframe import spec as spec_mod

    doc = preset_doc("carbon", core__link="pegs", model__stiffness_model="analytic")
    with pytest.raises(UserError) as e:
        spec_mod.from_dict(doc, "carbon.yaml")
    assert "model.stiffness_model" in str(e.value) and "core.link: pegs" in str(e.value)
    link = _links(_pegs_spec())["core_link"]
    with pytest.raises(ValueError, match="core.link: pegs"):
        analytic_joint(_pegs_spec(), link)


def test_the_studios_fast_model_of_a_pegged_design_is_the_design_itself():
    """The studio shows the closed forms while a joint's FE solves (`with_fast_model`); with no
    closed form for the pegs, a pegged design is shown by its own model rather than refused."""
    import yaml

    from cogniframe import api
    from presets import preset_doc

    d = api.from_text(yaml.safe_dump(preset_doc("carbon", core__link="pegs")), "carbon.yaml")
    assert d.with_fast_model() is d
    tab = api.from_text(yaml.safe_dump(preset_doc("carbon")), "carbon.yaml")
    assert tab.with_fast_model()._spec.model.stiffness_model == "analytic"


def test_a_strut_far_off_the_arms_refuses_the_pegs_naming_the_key():
    """A tall, narrow box (150 x 150 x 180) brings the strut in at 51 deg to the arms: standing on
    its pegs (the arms upright) the link's strut sleeve would overhang past 45 deg, so the params
    are refused, naming core.link and the fix; the tab link still builds that box."""
    from cogniframe.errors import UserError

    box = dict(frame__width=150, frame__depth=150, frame__height=180, motors__radius=82 * 150 / 210,
               motors__prop_diameter=76.2 * 150 / 210)
    assert _links(preset_spec("carbon", **box))
    with pytest.raises(UserError) as e:
        _links(_pegs_spec(**box))
    msg = str(e.value)
    assert "core.link" in msg and "51 deg" in msg and "core.link: tab" in msg


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3))
def test_random_designs_with_pegs_build_one_watertight_link_each(seed, tmp_path):
    """tests/design_space.py's random edits of a preset (other boxes, rectangles, struts or not,
    other motors) with core.link: pegs and level arms: the first design the params accept gives
    each core link one watertight solid whose closed form follows its CAD within 2 %, and the
    mirrored link the same volume."""
    import random

    import design_space
    from cogniframe import spec as spec_mod
    from cogniframe.errors import UserError
    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry

    rnd = random.Random(500 + seed)
    for _ in range(50):
        doc = design_space.random_design(rnd, "edit")
        doc["core"]["link"] = "pegs"
        doc["frame"]["level_arms"] = True  # the plate's peg tubes lie level with the arms (climbing arms are refused)
        try:
            links = _links(spec_mod.from_dict(doc, "random.yaml"))
            break
        except UserError:
            continue
    else:
        pytest.fail("no accepted design in 50 draws")
    vols = {}
    for name, p in links.items():
        built = registry.solid(p)
        mesh = write_stl(built.shape, tmp_path / f"{name}.stl", name=name)  # raises unless watertight
        assert mesh.body_count == 1 and mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
        vols[name] = built.shape.Volume()
        assert p.estimate.volume == pytest.approx(vols[name], rel=0.02)
    assert vols["core_link_mirrored"] == pytest.approx(vols["core_link"], rel=1e-6)


def test_a_strut_peg_whose_tube_would_miss_the_plate_is_refused_naming_the_key():
    """The strut's peg stands under its bore; a deep seat moves that crossing away from the arms'
    plane. Bamboo at joints.seat 8: the peg 3.1 mm below the arms' (their tubes flush with the
    3 mm plate's top), so its tube would reach the slab by less than PEG_TUBE_EMBED: refused,
    naming core.link and the fix, not an internal error in the plate's tubes."""
    from cogniframe.errors import UserError
    from cogniframe.families.joint import PEG_TUBE_EMBED

    assert PEG_TUBE_EMBED == 1.0
    with pytest.raises(UserError) as e:
        _links(preset_spec("bamboo", core__link="pegs", joints__seat=8))
    msg = str(e.value)
    assert "core.link" in msg and "3.1 mm below" in msg and "at most 2 mm below" in msg and "joints.seat" in msg
    assert len(_links(preset_spec("bamboo", core__link="pegs"))) == 2  # the preset's 3 mm seat: 1.4 mm below

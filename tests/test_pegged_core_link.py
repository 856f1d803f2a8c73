"""The pegged core link (`core.link: pegs`, the presets'): the authors' connector. Per arm a TPU
column round the socket and a solid peg beyond it, pressed into an ABS bore; an arch joining the
columns down to the pegs' shoulder round an opening; the strut's sleeve standing on the arch's
crown, as the authors' third column does. It must be one watertight solid standing on its pegs'
ends that prints with no support, its closed form must follow its CAD, its mirrored part must be
its mirror image, and its joint FE must hold the arm pair between the authors' connector with a
shallow arch and with a full one (tools/pegged_link_fe.py)."""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest

from conftest import ROOT
from presets import preset_doc, preset_spec

from cogniframe import numfmt
from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.families.joint_kinds.core_link_pegs import PEGS

_spec = importlib.util.spec_from_file_location("pegged_link_fe", ROOT / "tools" / "pegged_link_fe.py")
pl = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = pl  # its dataclass looks its module up there
_spec.loader.exec_module(pl)


def _links(spec):
    return {p.name: p for p in design_mod.design(spec).parts if dict(p.params).get("kind", p.name) == "core_link"}


def _pegs_spec(name="carbon", **changes):
    return preset_spec(name, core__link="pegs", **changes)


def test_the_presets_press_pegs_in_and_the_tab_keeps_its_screw():
    """The presets set core.link: pegs (a params file without the key keeps the bolted tab); a
    pegged link has no screw, no bolt hole and no hardware line, and carries the authors'
    dimensions."""
    assert preset_spec("carbon").core.link == "pegs" and preset_spec("bamboo").core.link == "pegs"
    doc = preset_doc("carbon")
    del doc["core"]["link"]
    assert spec_mod.from_dict(doc, "carbon.yaml").core.link == "tab"
    tab = _links(preset_spec("carbon", core__link="tab"))["core_link"]
    assert dict(tab.params).get("bolt_hole") is not None and tab.hardware
    for p in _links(_pegs_spec()).values():
        params = dict(p.params)
        assert params["link"] == "pegs" and "bolt_hole" not in params and "screw" not in params
        assert p.hardware == ()
        assert (params["peg_d"], params["peg_len"], params["column_wall"], params["arch_depth"]) == (6.8, 9.0, 1.8, 6.7)
    assert dict(PEGS)["column_wall"] == pytest.approx((6.79 - 3.19) / 2, abs=0.01)  # the authors' connector


def test_the_closed_form_is_the_connectors_cylinders_arch_and_strut_by_hand():
    """Carbon at 2.85 mm bores (-0.15; the preset's own are 2.70), 8 mm sockets, 25 mm pair: two pegs (r 3.4, 9 mm) and two arm columns
    (r 1.425 + 1.8, 8.3 mm); the arch 25 x 6.7 (the authors' depth) from 0.5 mm above
    the shoulder to the mouths (7.8 mm), less the two half columns in it and the opening (its 45 deg
    sides from 0.5 mm inside each column, 8.775 mm each side, up to the crown 3 mm under the mouths:
    4.8 mm; its roof 3.975 each side); the strut's sleeve (r 3.225, 9.8 mm) less its part in the
    arch, taken from the plan; the crown's block under the sleeve; less three sockets."""
    from cogniframe.parts.peg_plan import pegged_plan, sleeve_in_arch

    p = _links(_pegs_spec(joints__fit_clearance={"tpu_95a": -0.15}))["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    rc, rp = 1.425 + 1.8, 3.4
    assert plan.col_r == pytest.approx(rc) and plan.peg_r == pytest.approx(rp) and plan.spacing == pytest.approx(25.0, abs=1e-6)
    assert len(plan.columns) == 2 and len(plan.struts) == 1
    assert plan.arch_n[1] - plan.arch_n[0] == pytest.approx(6.7)
    assert (plan.arch_lo, plan.arch_hi) == pytest.approx((9.5, 17.3))
    o = plan.opening
    assert (o.half, o.top_half, o.z0, o.z1) == pytest.approx((8.775, 3.975, 9.5, 14.3))
    overlap = sleeve_in_arch(plan, plan.struts[0])
    assert 0 < overlap < math.pi * rc**2 * 9.8
    depth = 6.7
    # the crown's block: the sleeve's width and ARCH_CLEAR, the arch's depth, from the mouths to 0.5
    # over the back-end disc's top (its lowest point 0.5 over the crown, 14.3: 2 rc sin up)
    sin = math.sqrt(1 - plan.struts[0].lean_cos**2)
    block = (2 * rc + 0.2) * depth * (14.3 + 0.5 + 2 * rc * sin + 0.5 - 17.3)
    by_hand = (2 * math.pi * rp**2 * 9 + 2 * math.pi * rc**2 * 8.3 + (25 * depth - math.pi * rc**2) * 7.8
               - (8.775 + 3.975) * 4.8 * depth + block + math.pi * rc**2 * 9.8 - overlap - 3 * math.pi * 1.425**2 * 8)
    assert p.estimate.volume == pytest.approx(by_hand, rel=1e-3)


@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
def test_the_strut_stands_on_the_arch_crown_between_the_arm_pegs(preset):
    """The plan's columns are the core's pegs (the plate's tubes are built from them): the two arms',
    standing on the bed (z 0..9), upright in print. The strut has no peg: its sleeve's back end is
    centred on the pair's mid-line (print x 0, y of the arms' axes) with its lowest point
    PEG_SLEEVE_FLOOR above the crown (frame.pegged_strut_port), over the opening's roof, and the
    sleeve keeps PEG_SLEEVE_GAP clear of both columns."""
    from cogniframe.families.joint_kinds.core_link_pegs import PEG_SLEEVE_GAP, _sleeve_clear
    from cogniframe.frame import PEG_ARCH_LEN, PEG_SLEEVE_FLOOR
    from cogniframe.parts.peg_plan import pegged_plan

    p = _links(_pegs_spec(preset))["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    assert [(c.peg0, c.col0) for c in plan.columns] == [pytest.approx((0.0, 9.0))] * 2
    assert [c.socket for c in plan.columns] == [i for i, s in enumerate(p.sockets) if "arm" in s.rod]
    st = plan.struts[0]
    assert "strut" in p.sockets[st.index].rod
    back = np.asarray(st.back)
    assert back[0] == pytest.approx(0.0, abs=1e-6) and back[1] == pytest.approx(float(plan.columns[0].axis[1]), abs=1e-6)
    crown = plan.arch_hi - PEG_ARCH_LEN
    assert plan.opening.z1 == pytest.approx(crown)
    sin = math.sqrt(1 - st.lean_cos**2)
    assert back[2] - plan.col_r * sin == pytest.approx(crown + PEG_SLEEVE_FLOOR, abs=1e-5)
    assert _sleeve_clear(plan, st) > PEG_SLEEVE_GAP


def test_arms_too_close_for_the_strut_sleeve_are_refused_naming_the_key():
    """At 12 mm between the arms the strut's sleeve (6.45 mm) would pass 0.2 mm from each arm's
    column: refused, naming core.link and the fix. At 14 mm it clears by 0.55 mm and builds."""
    from cogniframe.errors import UserError

    with pytest.raises(UserError) as e:
        _links(_pegs_spec(frame__arm_spacing=12))
    msg = str(e.value)
    assert "core.link" in msg and "from an arm's column" in msg and "frame.arm_spacing" in msg
    assert len(_links(_pegs_spec(frame__arm_spacing=14))) == 2


@pytest.mark.cad
def test_pegged_link_is_one_watertight_solid_standing_on_its_pegs(tmp_path):
    """Carbon with core.link: pegs, both parts: one watertight solid, its closed form within 2 % of
    the CAD (exact but for the mouths' chamfers; test_parts allows the joints 15 %) and its
    envelope within 0.1 mm of the CAD's box; in print the arms point up (+z), nothing is below
    the bed and what lies on it is the two pegs' ends (their discs, faceted); the mirrored part
    has the same volume and the mirrored box."""
    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry
    from cogniframe.families.joint_kinds.kinds import print_from_local
    from cogniframe.parts.joint_plan import map_sockets
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
        # the faces on the bed: the pegs' two end discs, around the columns' axes
        plan = pegged_plan(p.sockets, dict(p.params))
        tri = mesh.vertices[mesh.faces]
        on_bed = np.all(np.abs(tri[:, :, 2]) < 1e-6, axis=1)
        area = 0.5 * np.linalg.norm(np.cross(tri[on_bed, 1] - tri[on_bed, 0], tri[on_bed, 2] - tri[on_bed, 0]), axis=1).sum()
        assert area == pytest.approx(2 * math.pi * 3.4**2, rel=0.03)
        centres = np.array([c.axis for c in plan.columns])
        dist = np.linalg.norm(tri[on_bed][:, :, :2].reshape(-1, 2)[:, None, :] - centres[None], axis=2).min(axis=1)
        # the STL's vertices lie on the grid the outputs are written at: up to half its diagonal out
        assert dist.max() <= 3.4 + numfmt.GRID_MM * math.sqrt(2) / 2
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


@pytest.mark.cad
def test_pegged_link_hinge_lies_between_the_authors_connector_with_a_shallow_and_a_full_arch():
    """The arm pair's hinge (`load_cases.arm_pair_hinge` on the link's FE, the pegs' sides and ends
    tied to the core) against tools/pegged_link_fe.py's `connector_hinge` of the authors'
    connector at the preset's dimensions (bore, socket, 1.8 mm walls, 6.8 x 9 mm pegs, 6.7 mm deep
    arch): above it with the arch only over the columns' outer 3 mm (its crown), below it with the
    arch solid from 0.5 mm over the shoulder to the mouths (the opening taken out of that), and
    far above the tab link's (test_pegged_link_fe.py)."""
    from dataclasses import replace

    from cogniframe.analysis.joints.fe import fe_joint
    from cogniframe.analysis.load_cases import arm_pair_hinge

    spec = _pegs_spec()
    link = _links(spec)["core_link"]
    hinge = arm_pair_hinge({link.name: fe_joint(spec, link)}, [link])
    depth = spec.joints.socket_depth
    col = depth + 0.3
    shallow = pl.Connector(spacing=spec.frame.arm_spacing, peg_d=6.8, peg_len=9.0, column_d=spec.bore + 3.6, column_len=col,
                           bore=spec.bore, depth=depth, arch_z=(col - 3.0, col))
    lo, _ = pl.connector_hinge(spec, shallow)
    hi, _ = pl.connector_hinge(spec, replace(shallow, arch_z=(0.5, col)))
    assert lo < hinge < hi
    flat, _ = pl.flat_link_hinge(preset_spec("carbon", core__link="tab"))
    assert hinge > 3 * flat


@pytest.mark.cad
def test_the_core_holds_the_pegs_sides_and_ends_only():
    """The support body's tie in the joint FE is the pegs' cylindrical sides and inner ends, the
    faces the ABS bores hold: its meshed area is the two pegs'
    2 (2 pi r L + pi r^2) (r 3.4, L 9: 457 mm^2), within the faceting of the mesh; the rods' ties
    are the sockets'."""
    from cogniframe.analysis.joints import solid_fe
    from cogniframe.analysis.joints.fe import joint_problem

    spec = _pegs_spec()
    link = _links(spec)["core_link"]
    pb = joint_problem(spec, link)
    assert pb.labels[-1] == "body"
    area = solid_fe.assemble(pb.points, pb.tets, pb.e, pb.nu, list(pb.ties)).tied_area
    assert area[-1] == pytest.approx(2 * (2 * math.pi * 3.4 * 9.0 + math.pi * 3.4**2), rel=0.03)
    # each rod's socket: its wall over the depth less the chamfer, and its floor
    bore, depth = spec.bore, spec.joints.socket_depth - 0.5
    for a in area[:-1]:
        assert a == pytest.approx(math.pi * bore * depth + math.pi * bore**2 / 4, rel=0.05)


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


@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
@pytest.mark.cad
def test_the_pegged_link_prints_with_no_support(preset, tmp_path):
    """Sliced every 0.2 mm (0.05 mm pixels), the standing link has no floating island: every piece
    of a layer touches the layer below. And nothing overhangs more than 45 deg (a layer grows at
    most one layer height, plus a pixel, past the one below) but the arch's first layer beside the
    columns and the opening's roof, a bridge under the crown (the authors' connector prints its
    arch so): the opening's sides rise at 45 deg and the strut's sleeve stands on the crown."""
    from scipy import ndimage

    from cogniframe.export.mesh import write_stl
    from cogniframe.families import registry
    from cogniframe.parts.peg_plan import pegged_plan

    p = _links(_pegs_spec(preset))["core_link"]
    plan = pegged_plan(p.sockets, dict(p.params))
    mesh = write_stl(registry.solid(p).shape, tmp_path / "link.stl", name=p.name)
    dz, px = 0.2, 0.05
    layers, zs, x0, y0 = _layers(mesh, dz, px)
    assert layers[0].sum() * px**2 == pytest.approx(2 * math.pi * 3.4**2, rel=0.02)  # the two pegs' ends
    bridge = []
    for k in range(1, len(zs)):
        below, here = layers[k - 1], layers[k]
        lab, n = ndimage.label(here)
        assert all((below & (lab == i)).any() for i in range(1, n + 1)), f"an island floats at z {zs[k]:.1f}"
        past = here & (ndimage.distance_transform_edt(~below) > dz / px + 1)
        if past.any():
            j, i = np.nonzero(past)
            bridge.append((zs[k], x0 + px * i, y0 + px * j, past.sum() * px**2))
    # the overhangs: the arch's first layer (beside the columns, within the arch's footprint) and
    # the opening's roof (within it)
    assert len(bridge) == 2
    (z, x, y, area), (z_r, x_r, y_r, area_r) = bridge
    assert plan.arch_lo < z < plan.arch_lo + dz
    assert plan.arch_x[0] < x.min() and x.max() < plan.arch_x[1]
    assert plan.arch_n[0] - px < y.min() and y.max() < plan.arch_n[1] + px
    o = plan.opening
    assert o.z1 < z_r < o.z1 + dz
    assert o.x - o.top_half - px < x_r.min() and x_r.max() < o.x + o.top_half + px
    assert plan.arch_n[0] - px < y_r.min() and y_r.max() < plan.arch_n[1] + px
    assert area_r == pytest.approx(2 * o.top_half * (plan.arch_n[1] - plan.arch_n[0]), rel=0.1)


def test_surrogate_holds_the_pegged_link_in_its_own_family():
    """The pegged link is its own surrogate family (`family_of`), trained on the pegged carbon
    preset (tools/train_joint_surrogate.py --family core_link_pegs --core-link pegs): both pegged
    presets' joints are inside the shipped fit's box and predicted by it, the mirror reflected from
    its original; the tab link keeps its own family."""
    import json

    from cogniframe.analysis.joints import surrogate as sg
    from cogniframe.analysis.joints import surrogate_models

    meta = json.loads(sg.DATA_FILE.read_text())["meta"]["families"]
    assert meta["core_link_pegs"]["core_link"] == "pegs" and meta["core_link"]["core_link"] == "tab"
    for name in ("carbon", "bamboo"):
        spec = preset_spec(name)
        parts = [p for p in design_mod.design(spec).parts if p.family == "joint"]
        assert sg.outside_reasons(spec, parts) == {}
        link = next(p for p in parts if p.name == "core_link")
        assert sg.family_of(link) == "core_link_pegs"
        assert {u.method for u in surrogate_models(spec, parts).values()} == {"surrogate"}
    tab = [p for p in design_mod.design(preset_spec("carbon", core__link="tab")).parts if p.family == "joint"]
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


def test_the_studios_fast_model_of_a_pegged_design_is_the_surrogate():
    """The studio shows a fast model while a joint's FE solves (`with_fast_model`): the closed forms
    for the tab link; with no closed form for the pegs, the FE's surrogate for a pegged design."""
    import yaml

    from cogniframe import api
    from presets import preset_doc

    d = api.from_text(yaml.safe_dump(preset_doc("carbon")), "carbon.yaml")
    assert d.with_fast_model()._spec.model.stiffness_model == "surrogate"
    tab = api.from_text(yaml.safe_dump(preset_doc("carbon", core__link="tab")), "carbon.yaml")
    assert tab.with_fast_model()._spec.model.stiffness_model == "analytic"


def test_a_strut_far_off_the_arms_refuses_the_pegs_naming_the_key():
    """A tall, narrow box (150 x 150 x 180) brings the strut in at 56 deg to the arms: standing on
    its pegs (the arms upright) the link's strut sleeve would overhang past 45 deg, so the params
    are refused, naming core.link and the fix; the tab link still builds that box."""
    from cogniframe.errors import UserError

    box = dict(frame__width=150, frame__depth=150, frame__height=180, frame__knee_inset=12, motors__radius=82 * 150 / 210,
               motors__prop_diameter=76.2 * 150 / 210)
    assert _links(preset_spec("carbon", core__link="tab", **box))
    with pytest.raises(UserError) as e:
        _links(_pegs_spec(**box))
    msg = str(e.value)
    assert "core.link" in msg and "56 deg" in msg and "core.link: tab" in msg


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.cad
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

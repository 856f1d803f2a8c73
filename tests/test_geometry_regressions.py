"""Joint geometry that used to fall apart or not build at all (parts/joint.py), each case as reported.

* frame.knee_inset 0 (straight sides): the knee's upper and lower legs are one vertical line, their
  cross product is zero, and the print orientation was NaN ("no parallel arm sockets", exit 3).
* 2.3 mm rods in a 91-92 mm tall frame: the knee's rigid lower leg leans back from the arms
  (107 deg) and its sleeve, 2.4 mm in radius, no longer reached the arm block ("joint geometry
  produced 2 solids instead of 1", exit 3); behind it, the core link's tab top sat exactly on the
  strut sleeve's top (bore 2.4 mm = M2 clearance) and its STL was not watertight.
* rectangles: rounding of the stored sockets left the two arm sleeves ~1e-5 mm apart (zero-area
  faces the FE mesher rejected), and OCC's many-piece fuse left a 0 mm^3 solid on a bottom corner.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod

ROOT = Path(__file__).resolve().parents[1]


def _variant(base: str, **changes) -> spec_mod.Spec:
    data = yaml.safe_load((ROOT / "params" / f"{base}.yaml").read_text(encoding="utf-8"))
    for key, value in changes.items():
        section, field = key.split("__")
        data[section][field] = value
    data["name"] = f"{base}-variant"
    return spec_mod.from_dict(data)


def _joints(spec, names=None):
    return [p for p in design_mod.design(spec).parts if p.family == "joint" and (names is None or p.name in names)]


# -- straight sides ----------------------------------------------------------------------------

def test_straight_sides_have_a_finite_print_orientation():
    """Pure numpy: the knee's lateral axis is the legs' and arms' plane normal, not 0/0."""
    from cogniframe.parts.joint import _groups, map_sockets, print_from_local

    (knee,) = _joints(_variant("carbon", frame__knee_inset=0), ["knee"])
    m = print_from_local(knee)
    assert np.isfinite(m).all() and np.allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3))
    socks = map_sockets(knee, m)
    arms, legs = _groups(socks)
    assert len(arms) == 2 and len(legs) == 2
    assert max(abs(s.direction[2]) for s in socks) < 1e-9  # every socket parallel to the bed


def test_straight_sides_check_with_closed_form_joints(run_cli, tmp_path):
    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text(encoding="utf-8"))
    data["frame"]["knee_inset"] = 0
    data["model"]["stiffness_model"] = "analytic"
    data["name"] = "straight"
    path = tmp_path / "straight.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    code, _, err = run_cli("check", path, "--json")
    assert code in (0, 1), err


@pytest.mark.slow
@pytest.mark.parametrize("base", ["carbon", "bamboo"])
def test_straight_sides_build_every_joint_as_one_solid(base):
    from cogniframe.parts import registry

    for part in _joints(_variant(base, frame__knee_inset=0)):
        built = registry.build(part)  # finish() raises unless it is one solid
        assert built.shape.isValid() and built.shape.Volume() > 100, part.name


# -- thin rods, short frame ----------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("base", ["carbon", "bamboo"])
@pytest.mark.parametrize("height", [91, 92])
def test_thin_rods_in_a_short_frame_keep_the_knee_in_one_piece(base, height):
    from cogniframe.parts import registry

    (knee,) = _joints(_variant(base, rods__diameter=2.3, frame__height=height), ["knee"])
    built = registry.build(knee)
    assert built.shape.isValid() and built.shape.Volume() > 100


@pytest.mark.slow
@pytest.mark.parametrize("base, height", [("carbon", 91), ("bamboo", 91.5)])
def test_thin_rods_core_links_mesh_watertight(base, height):
    """With 2.3 mm rods the bore (2.4 mm) equals the M2 clearance, so the core link's tab top met the
    strut sleeve's top exactly and the STL of one of the two links had open edges (build: MeshError)."""
    from cogniframe.export.mesh import tessellate
    from cogniframe.parts import registry

    links = _joints(_variant(base, rods__diameter=2.3, frame__height=height), ["core_link", "core_link_mirrored"])
    assert len(links) == 2
    for part in links:
        mesh = tessellate(registry.build(part).shape)
        assert mesh.is_watertight and mesh.volume > 0, part.name


def test_rigid_leg_reaches_into_the_arm_block():
    """Pure numpy: the rigid leg's sleeve starts far enough back that its inner back corner lies at
    least JOIN inside the arm block's footprint; the presets' knees already do (start unchanged)."""
    from cogniframe.parts.joint import (
        JOIN,
        _groups,
        _rigid_leg_start,
        horizontal,
        map_sockets,
        print_from_local,
    )

    for spec, moved in ((_variant("carbon", rods__diameter=2.3, frame__height=91), True),
                        (spec_mod.load(ROOT / "params" / "carbon.yaml"), False),
                        (spec_mod.load(ROOT / "params" / "bamboo.yaml"), False)):
        (knee,) = _joints(spec, ["knee"])
        socks = map_sockets(knee, print_from_local(knee))
        arms, legs = _groups(socks)
        a = arms[0]
        r = a.bore / 2 + knee.wall
        s_back = a.seat - knee.wall
        rigid = max(legs, key=lambda s: float(s.direction @ a.direction))
        t = _rigid_leg_start(a, rigid, r, s_back, knee.wall)
        assert (t < rigid.seat - knee.wall) == moved
        dx, u = horizontal(a.direction), horizontal(rigid.direction)
        lat = np.array([-dx[1], dx[0], 0.0])
        n = np.array([-u[1], u[0], 0.0])
        n = n if n @ dx >= 0 else -n
        corner = (rigid.port - a.port) * [1, 1, 0] + u * t + n * r
        assert corner @ dx - s_back >= JOIN - 1e-9
        assert r - abs(corner @ lat) >= JOIN - 1e-9


# -- rectangles ---------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("box", [(212, 210), (240, 180)])
def test_rectangle_joints_have_no_sliver_faces(box):
    """Every joint of a near-square and of a clearly rectangular box is one valid solid with no
    face under 1e-4 mm^2 (the arm sleeves 1e-5 mm apart gave faces of 1e-8 mm^2 and 0 mm^2, and
    gmsh: 'Invalid boundary mesh (overlapping facets)')."""
    from cogniframe.parts import registry

    width, depth = box
    for part in _joints(_variant("carbon", frame__width=width, frame__depth=depth)):
        shape = registry.build(part).shape
        assert shape.isValid(), part.name
        assert min(f.Area() for f in shape.Faces()) > 1e-4, part.name

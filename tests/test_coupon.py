"""The socket-fit coupon: one socket per clearance, measured on the mesh; closed, on the bed, stable."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

import tiers

from cogniframe import spec as spec_mod

ROOT = Path(__file__).resolve().parents[1]


def _loops_at(mesh, z):
    """Closed section loops of `mesh` at height z: (equivalent diameter, centre xy) each."""
    sec = mesh.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1])
    flat, to_3d = sec.to_2D()
    out = []
    for v in flat.discrete:
        x, y = v[:, 0], v[:, 1]
        area = abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2
        c = (to_3d @ np.r_[v.mean(axis=0), 0.0, 1.0])[:2]
        out.append((2 * np.sqrt(area / np.pi), c))
    return out


@pytest.fixture(scope="module", params=("carbon", "bamboo"))
@tiers.needs('cad')
def coupon(request, tmp_path_factory):
    from cogniframe.export.coupon import write_coupon
    from cogniframe.export.mesh import load_stl

    spec = spec_mod.load(ROOT / "params" / f"{request.param}.yaml")
    path, clearances = write_coupon(spec, tmp_path_factory.mktemp("coupon") / "coupon.stl")
    return spec, path, clearances, load_stl(path)


@pytest.mark.cad
def test_clearances_span_the_authors_fits_and_beyond(coupon):
    """The authors' parts (docs/authors-parts.md, each socket read across its own axis): blind
    sockets 2.69-2.70 mm and through-sleeves 3.19-3.20 mm for 3 mm rods, i.e. -0.30 and +0.20 mm;
    the coupon runs 0.10 mm past both, and the preset's own fit is one of its sockets."""
    spec, _, clearances, _ = coupon
    assert clearances == pytest.approx([round(-0.40 + 0.05 * i, 2) for i in range(15)])
    assert min(clearances) < 2.70 - 3.0 and max(clearances) > 3.20 - 3.0
    assert -0.30 in clearances and spec.joints.fit_clearance[spec.joints.material] in clearances


@pytest.mark.cad
def test_one_hole_per_clearance_with_the_right_diameter(coupon):
    spec, _, clearances, mesh = coupon
    z = spec.joints.wall + spec.joints.socket_depth / 2  # mid-depth of the sockets
    loops = _loops_at(mesh, z)
    od = spec.rods.diameter + max(clearances) + 2 * spec.joints.wall
    holes = sorted(d for d, _ in loops if d < od - 1.0)
    bosses = [d for d, _ in loops if d >= od - 1.0]
    assert len(holes) == len(clearances) == len(bosses)
    assert holes == pytest.approx([spec.rods.diameter + c for c in clearances], abs=0.02)
    # neighbouring sockets differ by the 0.05 mm step, measurably
    assert np.diff(holes) == pytest.approx([0.05] * (len(holes) - 1), abs=0.01)


@pytest.mark.cad
def test_coupon_is_closed_flat_and_fits_the_bed(coupon):
    from cogniframe.export.mesh import flat_contact_ratio, overhangs

    spec, _, _, mesh = coupon
    assert mesh.is_watertight and mesh.is_volume and mesh.body_count == 1
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-9)
    assert np.all(mesh.extents <= np.asarray(spec.printer.bed))
    assert flat_contact_ratio(mesh) > 0.5
    assert overhangs(mesh)["fraction"] < 0.01


@pytest.mark.cad
def test_labels_are_engraved(coupon):
    """Every label cuts a floor 0.6 mm into the base: up-facing area at that depth, under each socket."""
    from cogniframe.parts import coupon_solid as cp

    spec, _, clearances, mesh = coupon
    z_floor = cp.BASE - cp.ENGRAVE
    n = mesh.face_normals
    c = mesh.triangles_center
    floor = (np.abs(c[:, 2] - z_floor) < 1e-3) & (n[:, 2] > 0.99)
    g = cp.layout(spec, clearances)
    for x, y in zip(g["xs"], g["ys"]):
        near = floor & (np.abs(c[:, 0] - x) < g["pitch"] / 2) & (np.abs(c[:, 1] - y - g["label_dy"]) < 3.0)
        assert mesh.area_faces[near].sum() > 1.0


@pytest.mark.cad
def test_coupon_bytes_are_stable(tmp_path):
    from cogniframe.export.coupon import write_coupon

    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    a, _ = write_coupon(spec, tmp_path / "a.stl")
    b, _ = write_coupon(spec, tmp_path / "b.stl")
    assert hashlib.sha256(a.read_bytes()).digest() == hashlib.sha256(b.read_bytes()).digest()


def test_font_is_available_headless():
    from cogniframe.parts.coupon_solid import font_path

    assert font_path() is not None, "install fonts-dejavu-core: the coupon labels need a TrueType font"

"""The authors' options on the core (issue 45 item 3), each off by default: `core.support_holes`,
the four 3.0 mm mounting holes of the authors' MainBase on a 25.4 mm radius (their Pi support's
pattern), each in a boss on a bar out from the pegged plate's centre. The closed form must be
the pegged plate's plus the bars and the bosses by hand, the CAD its volume, the mass budget's
core-plate line the only one to grow, the holes clear of the pegs' bores, and nothing may clash.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from presets import preset_spec

from cogniframe import design as design_mod
from cogniframe.errors import UserError

R_HOLE, R_PATTERN = 1.5, 25.4  # the authors' MainBase: 2.98 mm through holes at (+-25.41, 0), (0, +-25.41)
R_BOSS = 3.5  # a stem's width (7 mm): 2.0 mm of ABS round the hole
DEPTH = 9.2  # the pegs' tubes (6.8 + 2 x 1.2) and the authors' block


def _made(name: str, on: bool):
    from cogniframe.analysis.mass import budget

    spec = preset_spec(name, core__support_holes=on)
    d = design_mod.design(spec)
    plate = next(p for p in d.parts if p.name == "core_plate")
    return spec, d, plate, budget(spec, d.frame, d.cut, d.parts)


@pytest.mark.parametrize("preset", ("carbon", "bamboo"))
def test_support_holes_add_four_bars_and_bosses_by_hand_and_only_the_plates_mass(preset):
    """Off -> on: the holes lie on the authors' pattern; the outline gains four bars 7 mm wide from
    the centre to each hole (manifold3d's union of the outline grows by their area outside the X);
    each boss adds pi 3.5^2 (9.2 - t/2) (its half past the bar's end full depth, its half over the
    bar below the slab) less the hole pi 1.5^2 9.2; the budget's core-plate line is the only one
    that moves."""
    import manifold3d as m3

    spec, _, off, mass_off = _made(preset, False)
    _, _, on, mass_on = _made(preset, True)
    t = spec.core.plate_thickness
    holes = on.param("support_holes")
    assert sorted(holes) == sorted([(R_PATTERN, 0.0), (-R_PATTERN, 0.0), (0.0, R_PATTERN), (0.0, -R_PATTERN)])
    assert on.param("support_hole_d") == 2 * R_HOLE and on.param("boss_depth") == pytest.approx(DEPTH)

    def area(outline):
        return m3.CrossSection.batch_boolean([m3.CrossSection([[tuple(map(float, q)) for q in p]]) for p in outline],
                                             m3.OpType.Add).area()

    bars = on.param("outline")[len(off.param("outline")):]
    assert len(bars) == 4
    for (x, y), bar in zip(holes, bars):
        assert m3.CrossSection([[tuple(map(float, q)) for q in bar]]).area() == pytest.approx(R_PATTERN * 2 * R_BOSS, rel=1e-9)
    by_hand = (area(on.param("outline")) - area(off.param("outline"))) * t \
        + 4 * (math.pi * R_BOSS**2 * (DEPTH - t / 2) - math.pi * R_HOLE**2 * DEPTH)
    assert on.estimate.volume - off.estimate.volume == pytest.approx(by_hand, rel=1e-8)
    assert 2000 < on.estimate.volume - off.estimate.volume < 3500  # mm^3: about 2.7-3.2 cm^3 of core material
    lines_off = {i.name: i.mass_g for i in mass_off.items}
    lines_on = {i.name: i.mass_g for i in mass_on.items}
    moved = {k for k in lines_on if abs(lines_on[k] - lines_off.get(k, 0.0)) > 1e-9}
    assert moved == {"core_plate"}
    grown = lines_on["core_plate"] - lines_off["core_plate"]
    assert mass_on.total_g - mass_off.total_g == pytest.approx(grown, abs=1e-9)
    from cogniframe.materials import MATERIALS

    solid_g = (on.estimate.volume - off.estimate.volume) * MATERIALS[on.material].density_g_mm3
    assert 0.3 * solid_g < grown <= solid_g * 1.001  # infill and walls: the slicer's share of solid


def test_support_holes_keep_a_line_of_abs_from_every_peg_bore():
    """Each hole keeps at least 0.4 mm (a nozzle line) from every tube's bore in plan, on both presets."""
    for name in ("carbon", "bamboo"):
        _, _, on, _ = _made(name, True)
        r_b = on.param("tube_bore") / 2
        for q in on.param("support_holes"):
            for e, s in on.param("tubes"):
                a, b, x = np.asarray(e[:2]), np.asarray(s[:2]), np.asarray(q)
                f = np.clip((x - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
                assert np.linalg.norm(x - (a + f * (b - a))) - r_b - R_HOLE >= 0.4


def test_support_holes_refuse_the_tab_plate_and_tubes_on_the_axes_naming_the_key():
    with pytest.raises(UserError, match="core.support_holes"):
        preset_spec("carbon", core__support_holes=True, core__link="tab")
    # a small core brings the pegs' tubes onto the axes, over the holes
    with pytest.raises(UserError, match="core.support_holes"):
        design_mod.design(preset_spec("carbon", core__support_holes=True, core__plate_size=30.0))


def test_defaults_leave_the_plate_as_it_was():
    spec, _, off, _ = _made("carbon", False)
    assert spec.core.support_holes is False and "support_holes" not in dict(off.params)


@pytest.mark.cad
def test_plate_with_support_holes_is_one_flat_solid_on_the_bed_its_holes_open(tmp_path):
    """The CAD of carbon's plate with the holes: one watertight solid, its volume the closed form's
    within 0.5 %, on the bed, inside the printer's bed; a probe down each hole's axis is outside
    the solid, a ring 0.3 mm outside the hole's wall inside it, the boss's full depth."""
    from cogniframe.export.mesh import contains, overhangs, write_stl
    from cogniframe.families import registry

    spec, _, on, _ = _made("carbon", True)
    built = registry.solid(on)
    mesh = write_stl(built.shape, tmp_path / "core_plate.stl", name="core_plate")
    assert mesh.is_watertight and mesh.body_count == 1
    assert built.shape.Volume() == pytest.approx(on.estimate.volume, rel=0.005)
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    ext = mesh.bounds[1] - mesh.bounds[0]
    assert ext[0] <= spec.printer.bed[0] and ext[1] <= spec.printer.bed[1]
    oh = overhangs(mesh)
    assert oh["area"] < 1.0 and oh["fraction"] < 0.01, oh
    m = built.print_from_local
    for x, y in on.param("support_holes"):
        q = m[:2, :2] @ np.array([x, y])
        for z in (0.5, DEPTH / 2, DEPTH - 0.5):
            assert not contains(mesh, [[q[0], q[1], z]]).any()
            ring = [[q[0] + (R_HOLE + 0.3) * math.cos(a), q[1] + (R_HOLE + 0.3) * math.sin(a), z]
                    for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)]
            assert contains(mesh, ring).all()


@pytest.mark.cad
def test_carbon_with_support_holes_has_no_clash(tmp_path):
    """The clash check over carbon's parts with the holes (no analysis): 0 clashes. The other
    parts are the preset's, read from the run's part cache when a build made them before."""
    import os

    from cogniframe.export.assembly import check_clashes
    from cogniframe.export.part_files import build_parts

    spec, d, _, _ = _made("carbon", True)
    parts = list(d.parts)
    built = build_parts(spec, d.frame, parts, tmp_path, cache_dir=os.environ.get("COGNIFRAME_CACHE"))
    res = check_clashes(spec, d.frame, parts, built, tmp_path)
    assert res.ok and res.clashes == (), res.messages()

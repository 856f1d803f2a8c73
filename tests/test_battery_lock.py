"""The authors' magnetic battery holder as an option (`core.battery_lock: magnetic`, issue 45
item 3): the strap holder without its strap slots and strap, two bosses at its mouth with a
pocket each for a 6 x 2 mm disc magnet, and a lid (`battery_lid`) across the mouth with two more.
The closed forms by hand, the CAD their volumes, the magnets as bought parts in the budget, the
pockets where the magnets go, the lid exempt from the battery's slide path (it goes on after the
pack), and nothing clashing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from presets import preset_spec

from cogniframe import design as design_mod

POCKET_D, POCKET_DEPTH, WALL = 6.2, 2.1, 1.2  # a 6 x 2 mm disc + 0.2 across, + 0.1 deep; three 0.4 mm lines
MAGNET_G = 0.42  # pi 3^2 2 mm^3 at 7.5 g/cm^3


def _made(name: str, lock: str):
    from cogniframe.analysis.mass import budget

    spec = preset_spec(name, core__battery_lock=lock)
    d = design_mod.design(spec)
    return spec, d, {p.name: p for p in d.parts}, budget(spec, d.frame, d.cut, d.parts)


@pytest.mark.parametrize("preset", ("carbon", "bamboo"))
def test_the_holder_gains_two_bosses_and_loses_its_strap_slots_by_hand(preset):
    """Each boss: a pocket centred 1.2 + 3.1 mm outside the cavity, 1.2 mm of plastic beyond it,
    so it reaches `out` past the side wall; 2.1 + 1.2 mm long at full reach, then 45 deg back to
    the wall; 6.2 + 2.4 mm high; less the pocket. The strap slots (2 x (strap + 1) x 2 mm through
    the wall) are gone."""
    spec, d, strap, _ = _made(preset, "strap")
    _, _, mag, _ = _made(preset, "magnetic")
    c, b = spec.core, spec.core.battery
    w = d.frame.core.holder.size[0]
    out = b.width / 2 + WALL + POCKET_D + WALL - w / 2
    back, height = POCKET_DEPTH + WALL, POCKET_D + 2 * WALL
    boss = (out * back + out**2 / 2) * height - math.pi / 4 * POCKET_D**2 * POCKET_DEPTH
    slots = 2 * (c.strap_width + 1.0) * 2.0 * c.holder_wall
    assert mag["battery_holder"].estimate.volume - strap["battery_holder"].estimate.volume == pytest.approx(2 * boss + slots, rel=1e-9)
    assert mag["battery_holder"].param("strap_slot") is None and strap["battery_holder"].param("strap_slot") is not None
    # the lid: the mouth and both bosses, 2.1 + 1.2 mm thick, less two pockets
    a, h = w + 2 * out, d.frame.core.holder.size[2]
    lid = a * h * (POCKET_DEPTH + WALL) - 2 * math.pi / 4 * POCKET_D**2 * POCKET_DEPTH
    assert mag["battery_lid"].estimate.volume == pytest.approx(lid, rel=1e-9)
    assert "battery_lid" not in strap


@pytest.mark.parametrize("preset", ("carbon", "bamboo"))
def test_the_budget_trades_the_strap_for_the_lid_and_four_magnets(preset):
    from cogniframe.materials import MATERIALS

    _, _, _, off = _made(preset, "strap")
    _, _, parts, on = _made(preset, "magnetic")
    l0 = {i.name: i for i in off.items}
    l1 = {i.name: i for i in on.items}
    magnets = [i for n, i in l1.items() if "disc magnet" in n]
    assert sum(i.qty for i in magnets) == 4 and all(i.mass_g == pytest.approx(i.qty * MAGNET_G) for i in magnets)
    straps = [n for n in l0 if "strap" in n]
    assert len(straps) == 1 and not any("strap" in n for n in l1)
    moved = {n for n in set(l0) | set(l1) if abs((l1[n].mass_g if n in l1 else 0) - (l0[n].mass_g if n in l0 else 0)) > 1e-9}
    assert moved == {"battery_holder", "battery_lid", straps[0], *(i.name for i in magnets)}
    assert on.total_g - off.total_g == pytest.approx(sum((l1[n].mass_g if n in l1 else 0) - (l0[n].mass_g if n in l0 else 0)
                                                         for n in moved), abs=1e-9)
    lid = parts["battery_lid"]
    solid = lid.estimate.volume * MATERIALS[lid.material].density_g_mm3
    assert 0.3 * solid < l1["battery_lid"].mass_g <= solid * 1.001


def test_each_pocket_holds_its_magnet_clear_of_the_cavity_and_faces_the_lids():
    """The holder's pockets keep 1.2 mm from the cavity; the lid's face them, the same x and z."""
    spec, d, parts, _ = _made("carbon", "magnetic")
    m = dict(parts["battery_holder"].param("magnet_bosses"))
    assert m["x"] - POCKET_D / 2 - spec.core.battery.width / 2 == pytest.approx(WALL)
    assert tuple(parts["battery_lid"].param("pockets")) == ((-m["x"], m["zc"]), (m["x"], m["zc"]))
    (pl,) = parts["battery_lid"].placements
    holder = d.frame.core.holder
    assert pl.origin[1] - (POCKET_DEPTH + WALL) / 2 == pytest.approx(holder.hi[1])  # on the mouth's face


def test_the_lid_is_exempt_from_the_slide_path_only_with_the_magnetic_lock():
    from cogniframe.analysis.fit_check import keepouts

    for lock, exempt in (("strap", {"battery"}), ("magnetic", {"battery", "battery_lid"})):
        spec, d, _, _ = _made("carbon", lock)
        (path,) = [k for k in keepouts(spec, d.frame, ()) if k.rule == "battery_path"]
        assert set(path.exempt) == exempt


@pytest.mark.cad
def test_holder_and_lid_are_single_flat_solids_with_open_pockets(tmp_path):
    from cogniframe.export.mesh import contains, overhangs, write_stl
    from cogniframe.families import registry

    _, _, parts, _ = _made("carbon", "magnetic")
    for name in ("battery_holder", "battery_lid"):
        p = parts[name]
        built = registry.solid(p)
        mesh = write_stl(built.shape, tmp_path / f"{name}.stl", name=name)
        assert mesh.is_watertight and mesh.body_count == 1
        assert built.shape.Volume() == pytest.approx(p.estimate.volume, rel=0.005)
        assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
        oh = overhangs(mesh)
        assert oh["area"] < 1.0 and oh["fraction"] < 0.01, (name, oh)
        m = built.print_from_local
        if name == "battery_holder":
            b = dict(p.param("magnet_bosses"))
            centres = [(sx * b["x"], b["mouth"] - POCKET_DEPTH / 2, b["zc"]) for sx in (-1, 1)]
        else:
            t = p.param("size")[1]
            centres = [(x, -t / 2 + POCKET_DEPTH / 2, z) for x, z in p.param("pockets")]
        for c in centres:
            q = m[:3, :3] @ np.asarray(c) + m[:3, 3]
            assert not contains(mesh, [q]).any()  # the pocket is open
            ring = [q + (POCKET_D / 2 + 0.5) * np.array([math.cos(a), math.sin(a), 0.0]) for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)]
            assert contains(mesh, ring).all()  # with plastic round it (the pockets' axes are vertical as printed)


@pytest.mark.cad
def test_carbon_with_the_magnetic_lock_has_no_clash(tmp_path):
    """The clash check and its fit rules over carbon's parts with the magnetic lock (no analysis):
    0 clashes, the battery's slide path included (the lid exempt). Other parts come from the run's
    part cache when a build made them before."""
    import os

    from cogniframe.export.assembly import check_clashes
    from cogniframe.export.part_files import build_parts

    spec, d, _, _ = _made("carbon", "magnetic")
    parts = list(d.parts)
    built = build_parts(spec, d.frame, parts, tmp_path, cache_dir=os.environ.get("COGNIFRAME_CACHE"))
    res = check_clashes(spec, d.frame, parts, built, tmp_path)
    assert res.ok and res.clashes == (), res.messages()

"""BOM: every budget item listed once, masses add up to the mass budget, hardware sizes, CSV/MD."""

from __future__ import annotations

import csv
import io
import math
from dataclasses import replace
from pathlib import Path

import pytest

import tiers

from cogniframe.analysis import verdict
from cogniframe.analysis.mass import MassItem
from cogniframe.export.slicer import MaterialCheck, PlateSlice, SliceReport
from cogniframe.report import bom as bom_mod


@pytest.fixture(scope="module", params=("carbon", "bamboo"))
@tiers.needs('fe')
def checked(request):
    from cogniframe import spec as spec_mod

    root = Path(__file__).resolve().parents[1]
    return verdict.check(spec_mod.load(root / "params" / f"{request.param}.yaml"))


def test_total_equals_the_mass_budget(checked):
    lines = bom_mod.build_bom(checked.design.spec, checked.design, checked.mass)
    assert math.isclose(bom_mod.total_g(lines), checked.mass.total_g, rel_tol=1e-12)
    assert sum(ln.qty for ln in lines) == sum(i.qty for i in checked.mass.items)
    assert not [ln for ln in lines if ln.category == "other"], "every budget item is classified"
    for ln in lines:
        assert ln.mass_g == pytest.approx(ln.qty * ln.mass_g_each)


def test_lines_cover_the_design(checked):
    d, spec = checked.design, checked.design.spec
    lines = bom_mod.build_bom(spec, d, checked.mass)
    cats = [ln.category for ln in lines]
    assert cats == sorted(cats, key=bom_mod.CATEGORIES.index), "shopping order"
    printed = {ln.item: ln for ln in lines if ln.category == "printed"}
    assert set(printed) == {p.name for p in d.parts}
    for p in d.parts:
        assert printed[p.name].qty == p.qty and printed[p.name].material == p.material
    rods = [ln for ln in lines if ln.category == "rod"]
    assert sum(ln.qty for ln in rods) == len(d.frame.rods)
    assert {ln.size.split(" mm")[0] for ln in rods} == {f"{r.length_mm:g}" for r in d.cut.rows}
    hw = {ln.item: ln for ln in lines if ln.category == "hardware"}
    motor_screws = next(ln for ln in hw.values() if "motor to mount" in ln.item)
    # every hole of every motor mount, at the length the plan chose through its seat into the motor's thread
    mount = next(p for p in d.parts if p.family == "motor_mount")
    assert motor_screws.qty == 4 * len(mount.param("holes")) >= 8
    assert motor_screws.size == f"M2 x {mount.param('screw_length'):g}"
    threaded = [ln for ln in hw.values() if any(w in ln.item for w in ("screw", "standoff", "spacer"))]
    assert all(ln.size.startswith("M") for ln in threaded)
    assert all(ln.size.endswith(" mm") for ln in hw.values() if ln not in threaded)  # strap, zip ties
    # level arms: the plate stands on four standoffs as long as the gap the frame leaves for them,
    # with pegs the rear two on the spacer's bar and the front two on the holder, the spacer longer
    stand = sorted((ln for ln in hw.values() if "standoff, female-female" in ln.item), key=lambda ln: ln.size)
    assert [ln.qty for ln in stand] == [2, 2]
    assert [ln.size for ln in stand] == [f"M2 x {d.frame.core.hang:g}", f"M2 x {d.frame.core.hang + spec.core.spacer_thickness:g}"]
    (motor,) = [ln for ln in lines if ln.category == "motor"]
    assert motor.qty == 4 and motor.mass_g_each == spec.motor.mass_g
    (prop,) = [ln for ln in lines if ln.category == "propeller"]
    assert prop.qty == 4 and f"{spec.motors.prop_diameter:g} mm" in prop.size
    assert [ln.item for ln in lines if ln.category == "electronics"] == [c.name for c in spec.components]
    (bat,) = [ln for ln in lines if ln.category == "battery"]
    assert bat.mass_g == spec.core.battery.mass


def test_unknown_budget_items_are_kept(checked):
    extra = replace(checked.mass, items=checked.mass.items + (MassItem("gps puck", "electronics", 1, 9.5),))
    lines = bom_mod.build_bom(checked.design.spec, checked.design, extra)
    assert [ln.item for ln in lines if ln.category == "other"] == ["gps puck"]
    assert bom_mod.total_g(lines) == pytest.approx(extra.total_g)


def test_sliced_grams_and_time_per_part(checked, tmp_path):
    d = checked.design
    knee = next(p for p in d.parts if p.name == "knee")
    objs = tuple((f"knee_{k}", 100.0) for k in range(1, knee.qty + 1)) + (("corner_top_1", 200.0),)
    plate = PlateSlice("tpu_95a_1", "tpu_95a", tmp_path / "a.3mf", tmp_path / "a.gcode", 12.0, 6000.0, objs, 0.5)
    report = SliceReport("PrusaSlicer-test", (plate,), (MaterialCheck("tpu_95a", 12.0, 11.0, 6000.0),))
    lines = bom_mod.build_bom(d.spec, d, checked.mass, report)
    by = {ln.item: ln for ln in lines}
    share = 100.0 * knee.qty / (100.0 * knee.qty + 200.0)
    assert by["knee"].sliced_g == pytest.approx(12.0 * share)
    assert by["knee"].print_time_s == pytest.approx(6000.0 * share)
    assert by["core_plate"].sliced_g is None
    assert bom_mod.total_g(lines) == pytest.approx(checked.mass.total_g)  # sliced grams never change the budget


def test_csv_and_markdown(checked, tmp_path):
    lines = bom_mod.build_bom(checked.design.spec, checked.design, checked.mass)
    c, m = bom_mod.write_bom(lines, tmp_path)
    rows = list(csv.DictReader(io.StringIO(c.read_text())))
    assert rows[-1]["category"] == "total"
    assert float(rows[-1]["mass_g"]) == pytest.approx(round(checked.mass.total_g, 2))
    assert sum(float(r["mass_g"]) for r in rows[:-1]) == pytest.approx(checked.mass.total_g, abs=0.01 * len(rows))
    assert len(rows) - 1 == len(lines)
    md = m.read_text()
    assert f"Total: {checked.mass.total_g:.2f} g" in md
    assert md.count("\n| ") == len(lines) + 1  # header + one row per line

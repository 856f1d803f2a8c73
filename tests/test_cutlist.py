"""Cut list rows vs the frame, and the stock plan (a real 1-D cutting-stock packing)."""

from __future__ import annotations

import csv
import io
import math

import pytest

from cogniframe import cutlist, frame as frame_mod
from cogniframe.errors import UserError


def test_rows_cover_every_rod_once(preset):
    f = frame_mod.frame_of(preset)
    cut = cutlist.cut_list(preset, f)
    names = [n for r in cut.rows for n in r.rods]
    assert sorted(names) == sorted(f.rods) and cut.count == len(f.rods) == 28
    for r in cut.rows:
        assert all(f.rods[n].cut_length == r.length_mm and f.rods[n].role == r.role for n in r.rods)


def test_rod_mass_is_length_section_density(carbon):
    cut = cutlist.cut_list(carbon, frame_mod.frame_of(carbon))
    row = cut.rows[0]
    assert row.mass_g == pytest.approx(row.length_mm * math.pi / 4 * 3.0**2 * 1.55e-3)
    assert cut.total_mass_g == pytest.approx(sum(r.mass_g * r.qty for r in cut.rows))


def test_stock_plan_never_exceeds_stock(preset):
    cut = cutlist.cut_list(preset, frame_mod.frame_of(preset))
    plan = cut.stock
    for s in plan.rods:
        assert s.used_mm == pytest.approx(sum(c + plan.kerf_mm for _, c in s.cuts))
        assert s.used_mm <= plan.stock_length_mm + 1e-9 and s.offcut_mm >= -1e-9
    placed = sorted(c for s in plan.rods for _, c in s.cuts)
    assert placed == sorted(r.length_mm for r in cut.rows for _ in range(r.qty))
    assert plan.count >= plan.lower_bound


def test_stock_plan_shares_stock_rods(carbon):
    plan = cutlist.cut_list(carbon, frame_mod.frame_of(carbon)).stock
    assert plan.count == plan.lower_bound == 4  # 28 cuts, ~3.1 m, into 1 m rods: optimal
    assert max(len(s.cuts) for s in plan.rods) > 5


def test_best_fit_decreasing_on_a_known_instance():
    rows = (cutlist.CutRow("a", 60, 2, 3, "m", ("x", "y"), 0), cutlist.CutRow("b", 40, 3, 3, "m", ("p", "q", "r"), 0))
    plan = cutlist.plan_stock(rows, 100, 0)
    assert plan.count == 3 and plan.lower_bound == 3
    assert sorted(sorted(c for _, c in s.cuts) for s in plan.rods) == [[40], [40, 60], [40, 60]]


def test_kerf_is_counted(carbon):
    rows = (cutlist.CutRow("a", 50, 2, 3, "m", ("x", "y"), 0),)
    assert cutlist.plan_stock(rows, 100, 0).count == 1
    assert cutlist.plan_stock(rows, 100, 1).count == 2


def test_piece_longer_than_stock_is_a_clear_error():
    rows = (cutlist.CutRow("cage", 230, 1, 3, "bamboo", ("x",), 0),)
    with pytest.raises(UserError, match=r"rods.stock_length to at least 231"):
        cutlist.plan_stock(rows, 200, 0.5)


def test_csv_and_markdown(carbon):
    cut = cutlist.cut_list(carbon, frame_mod.frame_of(carbon))
    rows = list(csv.DictReader(io.StringIO(cutlist.to_csv(cut))))
    assert len(rows) == len(cut.rows) and float(rows[0]["length_mm"]) == cut.rows[0].length_mm
    md = cutlist.to_markdown(cut)
    top = cut.rows[0]
    assert f"| cage | {top.length_mm:g} | {top.qty} | 3 | carbon_rod |" in md
    assert "Stock plan: 4 stock rods of 1000 mm" in md

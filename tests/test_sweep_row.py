"""A sweep row's recorded values against the full `check` of the same params, and what a sweep's
check leaves out (evaluate.CHECK_OPTIONS): no recorded column changes, no cache entry is shared."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from cogniframe import spec as spec_mod
from cogniframe.analysis import verdict
from cogniframe.sweep import evaluate as ev
from cogniframe.sweep.run import batch_sizes

ROOT = Path(__file__).resolve().parents[1]
RUN_COLUMNS = {"design_id", "worker", "seconds", "cpu_seconds"}  # the run's, not the design's


def _base() -> dict:
    base = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    base["model"]["stiffness_model"] = "surrogate"  # the sweeps' default
    return base


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return a == pytest.approx(b, rel=1e-12, abs=1e-12) or (math.isnan(a) and math.isnan(b))
    return a == b


@pytest.mark.parametrize("over", [
    {"rods.material": "carbon_rod", "rods.diameter": 2.8, "joints.wall": 1.7, "frame.height": 112.0},
    {"rods.material": "bamboo", "rods.diameter": 3.6, "joints.wall": 1.9, "joints.socket_depth": 12.0, "frame.height": 133.0},
])
def test_sweep_row_records_the_full_checks_values(over, tmp_path, monkeypatch):
    """Every column of a sweep row (the check with CHECK_OPTIONS) equals the full check's value for
    the same params, evaluated after it into the same cache: the sweep's cases entry is not read
    by the full check (its modes are listed), and the only columns the row lacks are the peaks'."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    base = _base()
    row = ev.evaluate_one(base, over, 120)
    assert row["verdict"] in ("PASS", "FAIL") and row["error"] == ""
    full = verdict.check_dict(verdict.check(spec_mod.from_dict(ev.apply_overrides(base, over))))
    assert len(full["stiffness"]["modes_hz"]) == 8 and full["stiffness"]["modes_hz"][0] > 1.0
    want = ev.outputs(full)
    recorded = set(row) - RUN_COLUMNS - set(over)
    assert recorded <= set(want)
    assert {k for k in set(want) - recorded} <= {k for k in want if k.startswith("peak_g")}
    diff = {k: (row[k], want[k]) for k in recorded if not _same(row[k], want[k])}
    assert not diff
    # the columns the skipped computations could have touched, with real values
    assert row["stiffness.mode_near_rotor"] is None and full["stiffness"]["mode_near_rotor"] is None
    assert max(full["stiffness"]["modes_hz"]) < 0.85 * row["stiffness.hover_rotor_hz"]
    assert 0.05 < row["stiffness.thrust.motor_deflection_mm_per_n"] < 5.0
    assert 100.0 < row["survival.max_undamaged_drop_cm"] <= 600.0
    assert row["k_n_per_m"] == pytest.approx(full["drop"]["k_n_per_m"], rel=1e-12)


def test_sweep_row_after_a_full_check_in_the_same_cache(tmp_path, monkeypatch):
    """The other order: the full check's cases entry first; the sweep row's values are the same."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    base, over = _base(), {"rods.diameter": 2.9, "frame.height": 125.0}
    full = ev.outputs(verdict.check_dict(verdict.check(spec_mod.from_dict(ev.apply_overrides(base, over)))))
    row = ev.evaluate_one(base, over, 120)
    assert all(_same(row[k], full[k]) for k in set(row) - RUN_COLUMNS - set(over))
    assert row["max_safe_drop_cm"] == pytest.approx(full["max_safe_drop_cm"], rel=1e-12)


def test_mode_count_rules_out_the_band_exactly_where_the_modes_do(tmp_path, monkeypatch):
    """`_no_mode_near_rotor` against the solved modes of the same model: True only when the 8th
    elastic mode sits below the band's lower edge (less the rounding), False when a mode is in
    the band or at its edge."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    from cogniframe.analysis import drop, load_cases as lc
    from cogniframe.design import design

    spec = spec_mod.from_dict(_base())
    d = design(spec)
    session = drop.Session(spec, d.frame, d.parts)
    play = session.solve().play or None
    masses = lc.masses_g(spec, d.frame, d.parts, 240.0)
    args = (spec, d.frame, d.parts, session.joints, masses)
    modes = lc._modes(*args, play=play)
    assert len(modes) == 8 and 5.0 < modes[0] < modes[-1] < 200.0
    top = modes[-1]
    band = 1 - lc.MODE_WARN_BAND
    assert lc._no_mode_near_rotor(*args, (top + 0.5) / band, play=play)  # every mode 0.5 Hz below the band
    assert not lc._no_mode_near_rotor(*args, (top + 0.005) / band, play=play)  # the 8th's rounding reaches it
    assert not lc._no_mode_near_rotor(*args, modes[3] / 0.95, play=play)  # the 4th mode inside the band
    assert not lc._no_mode_near_rotor(*args, modes[0], play=play)


def test_batch_sizes_shrink_towards_the_end_and_cover_every_design():
    sizes = batch_sizes(300, 2, None)
    assert sum(sizes) == 300 and sizes[0] == 64 and sizes[1] == 59
    assert sizes == sorted(sizes, reverse=True) and sizes[-1] <= 4
    assert len(sizes) <= 16  # one parquet file per batch on the client
    big = batch_sizes(100_000, 64, None)
    assert sum(big) == 100_000 and big[0] == 64 and min(big) >= 1
    assert batch_sizes(10, 2, 3) == [3, 3, 3, 3]  # the sweep file's `batch`: as given (the last one short)
    assert batch_sizes(1, 4, None) == [1]


@pytest.mark.parametrize("over, short", [
    ({"core.plate_thickness": 4.5}, False),  # a thicker core plate: it breaks past 400 cm (~490)
    ({}, True),  # the carbon preset: the core plate, a stem bent at a link, at ~383 cm
    ({"rods.diameter": 2.6}, False),  # thin carbon rods: a soft frame, the core plate past 400 cm (~486)
    ({"core.plate_thickness": 2.0}, True),  # a thinner core plate breaks lower still (~139 cm)
    ({"rods.material": "bamboo", "rods.diameter": 2.6, "joints.wall": 1.6, "frame.height": 110.0}, True),
])
def test_survival_cut_at_the_first_failure_gives_the_whole_sweeps_answer(over, short, tmp_path, monkeypatch):
    """`survival_margins=False` (a sweep's check): the same first failure and max undamaged drop
    as the whole sweep, from the heights up to 400 cm when a part fails there, else the whole sweep."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    spec = spec_mod.from_dict(ev.apply_overrides(_base(), over))
    whole = verdict.check(spec).survival
    cut = verdict.check(spec, survival_margins=False).survival
    assert cut.first_failure == whole.first_failure and cut.max_undamaged_drop_cm == whole.max_undamaged_drop_cm
    assert whole.first_failure is not None and 10.0 < whole.max_undamaged_drop_cm < 600.0
    assert (whole.max_undamaged_drop_cm <= 400.0) == short
    assert len(cut.heights_cm) == (40 if short else 60) and len(whole.heights_cm) == 60

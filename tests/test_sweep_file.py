"""Sweep files, samplers and the per-design evaluation: no Dask cluster needed here."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from cogniframe.analysis import verdict
from cogniframe import spec as spec_mod
from cogniframe.errors import UserError
from cogniframe.sweep import evaluate as ev
from cogniframe.sweep import run as run_mod
from cogniframe.sweep import sample
from cogniframe.sweep import sweepfile

ROOT = Path(__file__).resolve().parents[1]
CARBON = ROOT / "params" / "carbon.yaml"


def sweep_file(tmp_path: Path, text: str, name: str = "s.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text.replace("BASE", str(CARBON)))
    return p


GOOD = """base: BASE
samples: 8
sampler: lhs
seed: 3
vary:
  rods.diameter: [2.5, 4.0]
  frame.height: [105, 140]
  rods.material: {choices: [carbon_rod, bamboo]}
"""


def error_of(path: Path) -> str:
    with pytest.raises(UserError) as e:
        sweepfile.load(path)
    return str(e.value)


def test_example_sweep_file_loads_with_its_five_keys():
    sw = sweepfile.load(ROOT / "examples" / "sweeps" / "carbon.yaml")
    assert [k.name for k in sw.keys] == ["rods.diameter", "joints.wall", "joints.socket_depth", "frame.height", "rods.material"]
    assert (sw.keys[0].lo, sw.keys[0].hi) == (2.6, 4.0) and sw.keys[4].choices == ("carbon_rod", "bamboo")
    assert sw.settings.samples == 300 and sw.settings.sampler == "lhs" and sw.base_data["name"] == "carbon"


def test_unknown_sweep_key_names_file_line_and_fix(tmp_path):
    msg = error_of(sweep_file(tmp_path, GOOD.replace("seed: 3", "seeds: 3")))
    assert "s.yaml" in msg and "seeds (line 4)" in msg and "unknown key" in msg and "did you mean 'seed'" in msg


def test_vary_key_that_is_not_a_params_key(tmp_path):
    msg = error_of(sweep_file(tmp_path, GOOD.replace("rods.diameter:", "rods.diamter:")))
    assert "vary.rods.diamter (line 6)" in msg and "not a params key" in msg and "did you mean 'rods.diameter'" in msg


def test_vary_key_that_is_a_section_is_refused(tmp_path):
    msg = error_of(sweep_file(tmp_path, GOOD.replace("rods.diameter:", "rods:")))
    assert "vary.rods (line 6)" in msg and "section" in msg


def test_range_outside_the_params_schema_names_the_bounds(tmp_path):
    # RodsSection.diameter: ge=1.0, le=8.0
    msg = error_of(sweep_file(tmp_path, GOOD.replace("[2.5, 4.0]", "[2.5, 9.0]")))
    assert "vary.rods.diameter (line 6)" in msg and "9.0 is outside" in msg and ">= 1.0 and <= 8.0" in msg


def test_unknown_material_choice(tmp_path):
    msg = error_of(sweep_file(tmp_path, GOOD.replace("bamboo]", "balsa]")))
    assert "vary.rods.material (line 8)" in msg and "unknown material 'balsa'" in msg and "carbon_rod" in msg


def test_empty_range_and_malformed_range(tmp_path):
    assert "is empty" in error_of(sweep_file(tmp_path, GOOD.replace("[105, 140]", "[140, 105]")))
    msg = error_of(sweep_file(tmp_path, GOOD.replace("[105, 140]", "[105]")))
    assert "vary.frame.height (line 7)" in msg and "[lo, hi]" in msg


def test_base_that_does_not_load(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("rods:\n  diametr: 3\n")
    msg = error_of(sweep_file(tmp_path, GOOD.replace("BASE", str(bad))))
    assert "s.yaml: base (line 1)" in msg and "bad.yaml" in msg and "rods.diametr" in msg
    msg = error_of(sweep_file(tmp_path, GOOD.replace("BASE", "nowhere.yaml")))
    assert "base (line 1)" in msg and "no params file 'nowhere.yaml'" in msg


def test_cli_sweep_file_error_exits_2_and_writes_nothing(tmp_path, run_cli):
    out = tmp_path / "out"
    code, stdout, err = run_cli("sweep", sweep_file(tmp_path, GOOD.replace("seed: 3", "sed: 3")), "-o", out)
    assert code == 2 and "unknown key" in err and not out.exists()


def test_foreign_non_empty_folder_is_refused(tmp_path, run_cli):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    code, _, err = run_cli("sweep", sweep_file(tmp_path, GOOD), "-o", out)
    assert code == 2 and "was not made by `cogniframe sweep`" in err
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]


# -- samplers --------------------------------------------------------------------------------

def test_lhs_puts_one_design_in_each_stratum_of_every_range_key(tmp_path):
    sw = sweepfile.load(sweep_file(tmp_path, GOOD))
    d = sample.designs(sw)
    assert len(d) == 8 and d == sample.designs(sw)  # seeded: same file, same designs
    for key, lo, hi in (("rods.diameter", 2.5, 4.0), ("frame.height", 105, 140)):
        u = (np.array([x[key] for x in d]) - lo) / (hi - lo)
        assert sorted(np.floor(u * 8).astype(int).clip(0, 7)) == list(range(8))  # Latin hypercube property
    assert {x["rods.material"] for x in d} == {"carbon_rod", "bamboo"}


def test_grid_is_the_full_product_with_ends(tmp_path):
    sw = sweepfile.load(sweep_file(tmp_path, GOOD.replace("sampler: lhs", "sampler: grid\nlevels: 3")))
    d = sample.designs(sw)
    assert len(d) == 3 * 3 * 2
    assert sorted({x["rods.diameter"] for x in d}) == [2.5, 3.25, 4.0]
    assert sorted({x["frame.height"] for x in d}) == [105, 122.5, 140]


def test_sobol_is_saltelli_n_times_keys_plus_two(tmp_path):
    sw = sweepfile.load(sweep_file(tmp_path, GOOD.replace("sampler: lhs", "sampler: sobol")))
    assert len(sample.designs(sw)) == 8 * (3 + 2)


def test_random_sampler_is_seeded(tmp_path):
    a = sample.designs(sweepfile.load(sweep_file(tmp_path, GOOD.replace("sampler: lhs", "sampler: random"))))
    b = sample.designs(sweepfile.load(sweep_file(tmp_path, GOOD.replace("sampler: lhs", "sampler: random").replace("seed: 3", "seed: 4"))))
    assert len(a) == 8 and a != b


# -- one design ------------------------------------------------------------------------------

@pytest.mark.fe
def test_row_matches_check_json_of_the_same_params(tmp_path):
    base = yaml.safe_load(CARBON.read_text())
    row = ev.evaluate_one(base, {"frame.height": 130.0}, 60, "here")
    data = yaml.safe_load(CARBON.read_text())
    data["frame"]["height"] = 130.0
    d = verdict.check_dict(verdict.check(spec_mod.from_dict(data)))
    assert row["verdict"] == d["verdict"] and row["frame.height"] == 130.0
    assert row["mass_g"] == d["mass"]["total_g"] and row["k_n_per_m"] == d["drop"]["k_n_per_m"]
    assert row["max_safe_drop_cm"] == d["drop"]["max_safe_height_cm"]
    assert row["prop_margin_mm"] == min(min(p["to_cage_mm"], p["to_core_mm"], p["to_neighbour_mm"]) for p in d["frame"]["prop_margin_mm"])
    assert row["design_id"] == ev.design_id(data) and row["worker"] == "here" and row["seconds"] > 0


def test_new_sections_of_check_json_flow_into_the_row():
    row = ev.outputs({"verdict": "PASS", "problems": [], "mass": {"total_g": 200.0},
                      "stiffness": {"k_lateral_n_per_m": 1234.5, "modes": [1, 2]}, "flight": {"hover_time_min": 7.5},
                      "peak_g": 88.5, "note": "text"})
    assert row["stiffness.k_lateral_n_per_m"] == 1234.5 and row["flight.hover_time_min"] == 7.5 and row["peak_g"] == 88.5
    assert "note" not in row
    assert "stiffness.modes" not in row and row["mass_g"] == 200.0


def _line_of(text: str, start: str) -> int:
    return next(i for i, ln in enumerate(text.splitlines(), 1) if ln.startswith(start))


def test_invalid_design_is_a_row_with_its_error():
    text = CARBON.read_text()
    base = yaml.safe_load(text)
    row = ev.evaluate_one(base, {"rods.diameter": 5.0}, 60, text=text, base_name="carbon.yaml")  # socket_depth 8 < 2 x 5
    assert row["verdict"] == "INVALID" and row["mass_g"] is None
    line = _line_of(text, "  socket_depth:")
    assert row["error"].startswith(f"design {row['design_id']} of carbon.yaml: joints.socket_depth (line {line})")


def test_a_stage_error_names_the_key_by_its_line_in_the_base():
    """A propeller that hits the cage (found by the frame stage, after validation): the key is set in
    the base file, so the message gives its line there, not "default applies"."""
    text = CARBON.read_text()
    row = ev.evaluate_one(yaml.safe_load(text), {"motors.prop_diameter": 120.0}, 60, text=text, base_name="carbon.yaml")
    assert row["verdict"] == "INVALID" and f"motors.prop_diameter (line {_line_of(text, '  prop_diameter:')})" in row["error"], row["error"]


def test_timeout_cuts_a_running_design_off():
    def spin():  # a design that would run for a minute: only the watchdog's exception ends it sooner
        t = time.perf_counter()
        while time.perf_counter() - t < 60:
            pass
        return "finished"

    with pytest.raises(ev.DesignTimeout):
        ev.run_with_timeout(spin, 0.2)
    assert ev.run_with_timeout(lambda: 42, 5.0) == 42
    time.sleep(0.05)  # a cancelled watchdog never fires later
    assert threading.active_count() >= 1


def test_timed_out_design_is_recorded_not_raised():
    base = yaml.safe_load(CARBON.read_text())
    row = ev.evaluate_one(base, {"frame.height": 131.0}, 1e-6)
    assert row["verdict"] == "TIMEOUT" and "cut off after" in row["error"] and row["mass_g"] is None


def test_plan_ids_are_hashes_of_the_full_params(tmp_path):
    sw = sweepfile.load(sweep_file(tmp_path, GOOD))
    ids = [i for i, _ in run_mod.plan(sw)]
    assert len(set(ids)) == 8 and all(len(i) == 16 for i in ids)


# -- sensitivity (closed forms) ------------------------------------------------------------

LINEAR = """base: BASE
samples: SAMPLES
sampler: SAMPLER
seed: 1
vary:
  core.battery.mass: [40, 70]
  motors.prop_mass: [0.5, 3.0]
"""


def _linear_table(sweep):
    """mass = 100 + battery + 4 prop (the budget is additive): a table with a known answer."""
    import pandas as pd

    rows = []
    for _, o in run_mod.plan(sweep):
        rows.append({"design_id": ev.design_id(ev.apply_overrides(sweep.base_data, o)), **o, "verdict": "PASS",
                     "mass_g": 100 + o["core.battery.mass"] + 4 * o["motors.prop_mass"]})
    return pd.DataFrame(rows)


def test_sobol_total_indices_match_the_variance_shares_of_a_linear_model(tmp_path):
    from cogniframe.sweep import report

    sw = sweepfile.load(sweep_file(tmp_path, LINEAR.replace("SAMPLES", "256").replace("SAMPLER", "sobol")))
    method, inputs, outputs, m, _ = report.sensitivity(sw, _linear_table(sw))
    assert method.startswith("Sobol") and outputs == ["mass_g"]
    # Var(battery) = 30^2/12 = 75, Var(4 prop) = 16 * 2.5^2 / 12 = 8.33: ST = 0.9 and 0.1
    assert m[:, 0] == pytest.approx([0.9, 0.1], abs=0.03)


def test_src_of_a_linear_model_is_slope_times_sigma_ratio(tmp_path):
    from cogniframe.sweep import report

    sw = sweepfile.load(sweep_file(tmp_path, LINEAR.replace("SAMPLES", "200").replace("SAMPLER", "lhs")))
    table = _linear_table(sw)
    method, inputs, outputs, m, r2 = report.sensitivity(sw, table)
    sb, sp = table["core.battery.mass"].std(ddof=0), table["motors.prop_mass"].std(ddof=0)
    sy = table["mass_g"].std(ddof=0)
    assert method.startswith("standardized") and r2["mass_g"] == pytest.approx(1.0, abs=1e-9)
    assert m[:, 0] == pytest.approx([sb / sy, 4 * sp / sy], rel=1e-6)


def test_pareto_front_is_the_passing_non_dominated_set():
    import pandas as pd

    from cogniframe.sweep import report

    t = pd.DataFrame({"design_id": list("abcde"), "verdict": ["PASS", "PASS", "PASS", "FAIL", "PASS"],
                      "mass_g": [200.0, 210.0, 205.0, 150.0, 220.0], "max_safe_drop_cm": [100.0, 150.0, 90.0, 300.0, 150.0]})
    assert list(report.pareto_front(t)["design_id"]) == ["a", "b"]


def test_set_values_apply_to_every_design_and_are_checked(tmp_path):
    sw = sweepfile.load(sweep_file(tmp_path, GOOD + "set:\n  core.battery.mass: 40\n  requirements.drop_heights_cm: [50, 120]\n"))
    assert sw.base_data["core"]["battery"]["mass"] == 40
    # the sweep's default joint model comes after the file's set: values
    assert sw.fixed == ("core.battery.mass", "requirements.drop_heights_cm", "model.stiffness_model")
    assert sw.defaults == ("model.stiffness_model",) and sw.base_data["model"]["stiffness_model"] == "surrogate"
    row = ev.evaluate_one(sw.base_data, sample.designs(sw)[0], 60)
    data = ev.apply_overrides(yaml.safe_load(CARBON.read_text()), {"core.battery.mass": 40, "requirements.drop_heights_cm": [50, 120],
                                                                  "model.stiffness_model": "surrogate", **sample.designs(sw)[0]})
    data["name"] = "carbon"
    assert row["design_id"] == ev.design_id(data)
    msg = error_of(sweep_file(tmp_path, GOOD + "set:\n  core.battery.mass: 900\n"))
    assert "set.core.battery.mass (line 10)" in msg and "<= 500" in msg
    msg = error_of(sweep_file(tmp_path, GOOD + "set:\n  core.batery.mass: 40\n"))
    assert "set.core.batery.mass (line 10)" in msg and "did you mean 'core.battery'" in msg


def test_sweep_schema_lists_the_sweep_keys(run_cli):
    import json

    code, out, _ = run_cli("sweep-schema")
    props = json.loads(out)["properties"]
    assert code == 0 and {"base", "vary", "sampler", "samples", "seed", "set", "timeout_s"} <= set(props)


def test_why_no_design_is_feasible_is_told_from_the_trials():
    from cogniframe.sweep import optimize as opt

    c = opt.parse_constraint("max_safe_drop_cm >= 500")
    rows = [{"design_id": "a", "verdict": "PASS", "max_safe_drop_cm": 180.0}, {"design_id": "b", "verdict": "PASS", "max_safe_drop_cm": 210.5},
            {"design_id": "c", "verdict": "INVALID", "max_safe_drop_cm": None}]
    ranked, pareto = opt.ranked(rows, opt.parse_objectives(["mass_g"], []), [c])
    assert ranked == [] and pareto == []
    note = opt.why_none(rows, [opt.Objective("mass_g", "minimize")], [c])
    assert "2 violates max_safe_drop_cm >= 500" in note and "1 verdict INVALID" in note and "b with max_safe_drop_cm = 210.5" in note


def test_second_sweep_into_a_folder_being_written_is_refused(tmp_path, run_cli):
    from cogniframe.outdir import lock

    out = tmp_path / "out"
    with lock(out):  # as a running sweep holds it
        code, _, err = run_cli("sweep", sweep_file(tmp_path, GOOD), "-o", out)
    assert code == 2 and "is writing" in err and not out.exists()


def test_best_yaml_edits_only_the_changed_values_and_keeps_comments(tmp_path):
    from cogniframe.sweep import optimize as opt

    sw = sweepfile.load(sweep_file(tmp_path, GOOD + "set:\n  requirements.drop_heights_cm: [50, 120]\n"))
    row = {"rods.diameter": np.float64(2.75), "frame.height": 111.8, "rods.material": "bamboo"}  # height unchanged
    changed = opt.write_best_yaml(sw, row, tmp_path / "best.yaml")
    assert changed == ["requirements.drop_heights_cm", "rods.diameter", "rods.material"]
    before, after = CARBON.read_text().splitlines(), (tmp_path / "best.yaml").read_text().splitlines()
    diff = [(a, b) for a, b in zip(before, after) if a != b]
    assert len(before) == len(after) and len(diff) == 3
    assert "  diameter: 2.75         # mm" in after
    assert any(b.startswith("  drop_heights_cm: [50, 120]") and "# heights in the crash table" in b for _, b in diff)
    assert any(b.startswith("  material: bamboo") and "# pultruded" in b for _, b in diff)
    best = spec_mod.load(tmp_path / "best.yaml")
    assert best.rods.diameter == 2.75 and best.frame.height == 111.8 and best.requirements.drop_heights_cm == (50, 120)


def test_sobol_example_is_a_full_saltelli_design():
    sw = sweepfile.load(ROOT / "examples" / "sweeps" / "carbon-sobol.yaml")
    assert sw.settings.sampler == "sobol" and len(sw.keys) == 6
    assert len(sample.designs(sw)) == 64 * (6 + 2)

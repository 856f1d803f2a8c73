"""Docs tables of figures are generated, and fail here when stale: docs/stiffness-model.md's
"Results" (tools/stiffness_results.py) from `check --json` of the presets."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("stiffness_results", ROOT / "tools" / "stiffness_results.py")
results = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = results
_spec.loader.exec_module(results)


def test_the_table_is_the_checks_figures_row_by_row():
    """The table's cells are read from the check's JSON (a made-up pair of checks, cheap)."""
    def fake(k, mass):
        thrust = {"max_thrust_g": 175.0, "motor_deflection_mm_per_n": 0.2, "motor_tilt_deg_per_n": 0.25,
                  "motor_deflection_mm": 0.34, "motor_tilt_deg": 0.43, "arms_only_motor_deflection_mm": 5.0,
                  "arms_only_motor_tilt_deg": 6.0, "arms_only_core_link_hinge_n_mm_per_rad": 800.0,
                  "exoskeleton_stiffening": 13.2}
        return {"mass": {"total_g": mass}, "drop": {"max_safe_height_cm": 170.04},
                "stiffness": {"k_n_per_m": k, "k_lateral_n_per_m": 9000.0, "thrust": thrust, "modes_hz": [15.71, 16.0],
                              "wall": {"max_wall_speed_m_s": 3.5, "limited_by": "propeller of motor_fr"},
                              "min_buckling_margin": 11.79, "critical_rod": "rod_strut_fl"},
                "survival": {"max_undamaged_drop_cm": 382.7, "first_failure": None}}
    t = results.table({"carbon": fake(8448.0, 238.29), "bamboo": fake(7040.0, 242.0)})
    lines = t.splitlines()
    assert lines[0] == "| | carbon | bamboo |" and len(lines) == 2 + len(results.rows({"a": fake(1.0, 1.0)}))
    assert "| k (N/m), secant: a prediction | 8448 | 7040 |" in lines
    assert "| k against the paper's 7040 (the authors' carbon frame) | +20.0% | +0.0% |" in lines
    assert "| first modes (Hz) | 15.7, 16.0 | 15.7, 16.0 |" in lines
    assert "| all-up mass (g) | 238.3 | 242.0 |" in lines


@pytest.mark.fe
def test_the_stiffness_results_table_is_what_check_says_today():
    """Run `python tools/stiffness_results.py --write` after a change that moves a preset's figures."""
    doc = results.in_doc((ROOT / "docs" / "stiffness-model.md").read_text(encoding="utf-8"))
    assert doc == results.table(results.preset_checks())

"""tools/strut_path_fe.py: the pegged carbon preset with the strut on its own peg and with the
strut hanging on the arch (the authors' load path), each with the one TPU factor fitted to the
paper's 7040 N/m (docs/stiffness-model.md, "Where the strut meets the core decides the
calibration")."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from conftest import ROOT
from test_thrust_survival import ARM_LENGTH_MM

_spec = importlib.util.spec_from_file_location("strut_path_fe", ROOT / "tools" / "strut_path_fe.py")
sp = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = sp
_spec.loader.exec_module(sp)


@pytest.fixture(scope="module")
def rows():
    return {r["strut"]: r for r in sp.measure(("carbon",))}


@pytest.mark.slow
def test_both_paths_reach_the_papers_7040_n_per_m_with_their_own_factor(rows):
    for r in rows.values():
        assert r["k_n_per_m"] == pytest.approx(7040.0, rel=1e-3)


@pytest.mark.slow
def test_strut_on_its_own_peg_needs_printed_tpu_under_a_tenth_of_its_datasheet(rows):
    """A stiff strut path the paper's frame lacks: the fit can only soften the TPU. Printed TPU at
    full infill keeps most of its moulded modulus, so a factor under 0.1 is the model, not the
    material; on the arch the factor is a material's (between 0.1 and 1)."""
    assert rows["own peg"]["factor"] < 0.1
    assert 0.1 < rows["on the arch"]["factor"] <= 1.0


@pytest.mark.slow
def test_on_the_arch_the_bare_arms_bend_and_the_wall_case_passes(rows):
    """The paper photographs its bare x-frame bent, not folded, and flew its frame into walls at
    up to 7 m/s; the presets require 2.5 m/s side-on."""
    arch, own = rows["on the arch"], rows["own peg"]
    assert arch["bare_mm"] < 0.5 * ARM_LENGTH_MM["carbon"] and arch["bare_deg"] < 45
    assert arch["ratio"] < own["ratio"]
    assert arch["wall_m_s"] >= 2.5 > own["wall_m_s"]

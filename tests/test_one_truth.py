"""One value per quantity: the maximum thrust, g, infill, and the payload mass the dynamic cases use."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cogniframe import design as design_mod
from cogniframe.analysis import verdict
from cogniframe import spec as spec_mod

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.cad
@pytest.mark.fe
def test_the_thrust_load_case_and_the_flight_model_use_the_same_maximum_thrust(carbon):
    d = verdict.check_dict(verdict.check(carbon))
    assert d["stiffness"]["thrust"]["max_thrust_g"] == d["flight"]["max_thrust_g_per_motor"] == 175.0


@pytest.mark.fe
def test_a_given_maximum_thrust_is_what_both_use(carbon):
    data = carbon.model_dump(mode="json")
    data["motors"]["max_thrust_g"] = 150.0
    d = verdict.check_dict(verdict.check(spec_mod.from_dict(data)))
    assert d["stiffness"]["thrust"]["max_thrust_g"] == d["flight"]["max_thrust_g_per_motor"] == 150.0
    assert d["flight"]["thrust_to_weight"] == pytest.approx(4 * 150.0 / d["mass"]["total_g"], abs=0.01)


def test_g_has_one_value_in_the_code():
    literal = re.compile(r"(?<![\d.])9\.8(1|0665)\b")
    found = [f"{p.relative_to(ROOT)}:{i}" for p in (ROOT / "cogniframe").rglob("*.py")
             for i, line in enumerate(p.read_text().splitlines(), 1) if literal.search(line)]
    assert found == ["cogniframe/analysis/constants.py:3"]


def test_the_dynamic_cases_count_each_joint_copy_once(carbon):
    """The payload is the total less the frame's own parts: each printed joint as many times as it
    has copies (the presets' five joint parts have 20 copies, not 4 each)."""
    from cogniframe.analysis.stiffness import joint_parts, masses_g

    d = design_mod.design(carbon)
    m = masses_g(carbon, d.frame, d.parts, 240.0)
    joints = sum(p.qty * m["joints"][p.name] for p in joint_parts(d.parts))
    assert sum(p.qty for p in joint_parts(d.parts)) == 16
    assert m["payload"] == pytest.approx(240.0 - m["rods"] - joints - 4 * m["motor_each"])


def test_infill_per_material_has_one_source(carbon):
    from cogniframe.export import slicer
    from cogniframe.partlist import infill_by_material

    d = design_mod.design(carbon)
    assert infill_by_material(d.parts) == slicer.default_infill(carbon) == {"abs": 0.1, "tpu_95a": 1.0}

"""Assembly steps: fold-as-you-assemble order; every rod and every part copy in exactly one step."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.report.assembly_steps import assembly_steps, copy_labels, to_markdown

ROOT = Path(__file__).resolve().parents[1]


def _design(name: str, **overrides):
    data = spec_mod.load(ROOT / "params" / f"{name}.yaml").model_dump(mode="json")
    for dotted, value in overrides.items():
        cur = data
        *path, key = dotted.split(".")
        for k in path:
            cur = cur[k]
        cur[key] = value
    return design_mod.design(spec_mod.from_dict(data))


@pytest.mark.parametrize("name,overrides", [
    ("carbon", {}), ("bamboo", {}), ("carbon", {"core.computer": None}), ("carbon", {"frame.struts": False}),
])
def test_every_rod_and_part_copy_exactly_once(name, overrides):
    d = _design(name, **overrides)
    steps = assembly_steps(d)
    rods = Counter(r for s in steps for r, _ in s.rods)
    assert set(rods) == set(d.frame.rods) and set(rods.values()) == {1}
    copies = Counter(c for s in steps for c in s.parts)
    expected = [c for p in d.parts for c in copy_labels(p)]
    assert len(expected) == sum(p.qty for p in d.parts) == len(set(expected))
    assert set(copies) == set(expected) and set(copies.values()) == {1}
    assert [s.number for s in steps] == list(range(1, len(steps) + 1))
    assert "Remaining rods" not in [s.title for s in steps]


def test_fold_as_you_assemble_order_and_lengths():
    d = _design("carbon")
    steps = assembly_steps(d)
    titles = [s.title for s in steps]
    assert titles == ["Top ring", "Bottom ring", "Knees and upper legs", "Fold the sides", "Arms, motor mounts and motors",
                      "Struts", "Core", "Hang the core", "Camera and sensors", "Electronics"]
    cut = {n: r.length_mm for r in d.cut.rows for n in r.rods}
    for s in steps:
        for rod, length in s.rods:
            assert length == cut[rod] == d.frame.rods[rod].cut_length
    by = {s.title: s for s in steps}
    assert by["Top ring"].parts == ("corner_top_fl", "corner_top_fr", "corner_top_rr", "corner_top_rl")
    assert {d.frame.rods[r].role for r, _ in by["Top ring"].rods} == {"cage"}
    assert all("_top_" in r for r, _ in by["Top ring"].rods)
    arms = by["Arms, motor mounts and motors"]
    assert {d.frame.rods[r].role for r, _ in arms.rods} == {"arm"}
    assert arms.parts == ("motor_mount_fl", "motor_mount_fr", "motor_mount_rr", "motor_mount_rl")
    assert set(by["Core"].parts) >= {"core_plate", "battery_holder", "core_link_fl", "core_link_mirrored_fr", "sensor_mount"}
    assert by["Camera and sensors"].parts == ("front_camera_mount",)
    assert any("hook-and-loop battery strap" in h for h in by["Core"].hardware)
    # glue: CA on the ring, never on the core links (the core stays removable)
    assert "CA" in by["Top ring"].glue and "CA" in by["Fold the sides"].glue
    assert by["Core"].glue.startswith("none") and by["Hang the core"].glue.startswith("none")
    assert not any("core link to plate" in h for h in by["Core"].hardware)  # the pegs press in: no link screw
    # the motors go on while the mounts are threaded on the free arm rods, before the arms go in
    assert any("motor to mount" in h for h in arms.hardware) and "before the arm goes in" in arms.text
    assert not any("motor to mount" in h for h in by["Electronics"].hardware)


def test_markdown():
    d = _design("carbon")
    md = to_markdown(assembly_steps(d))
    assert md.startswith("# Assembly")
    top = d.frame.rods["rod_cage_top_front"].cut_length
    assert "## 1. Top ring" in md and f"rod_cage_top_front ({top:g} mm)" in md
    assert md.count("- Glue:") == len(assembly_steps(d))


@pytest.mark.parametrize("name, over", [("carbon", {}), ("bamboo", {}), ("carbon", {"core__link": "tab"}),
                                        ("carbon", {"core__link": "tab", "frame__level_arms": False})])
def test_no_step_names_what_the_build_lacks(name, over):
    """Issue 45: the steps named a strut peg and a middle tube the pegged link does not have, clipped
    on motor mounts whose sleeves are closed and put ABS tubes on bamboo's PLA core. Every step now
    names only parts, features and materials the build has; a step naming one it lacks is caught."""
    from dataclasses import replace as _replace

    from cogniframe.design import design
    from cogniframe.report.assembly_steps import unbuilt
    from presets import preset_spec

    d = design(preset_spec(name, **over))
    steps = assembly_steps(d)
    for s in steps:
        assert unbuilt(s, d) == [], (s.number, s.title)
    text = " ".join(s.text for s in steps)
    assert "clip" not in text.lower() and "strut's peg" not in text
    core = next(s for s in steps if s.title == "Core")
    assert unbuilt(_replace(core, text=core.text + " Clip the motor mounts on."), d) == ["clip"]
    wrong = "PLA" if d.spec.core.material == "abs" else "ABS"
    assert unbuilt(_replace(core, text=f"Press the pegs into the {wrong} tubes of core_link_xx."), d) == \
        [wrong] + (["tube", "peg"] if over else []) + ["core_link_xx"]

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
    assert titles == ["Top ring", "Bottom ring", "Knees and upper legs", "Fold the sides", "Arms and motor mounts",
                      "Struts", "Core", "Hang the core", "Camera and sensors", "Electronics"]
    cut = {n: r.length_mm for r in d.cut.rows for n in r.rods}
    for s in steps:
        for rod, length in s.rods:
            assert length == cut[rod] == d.frame.rods[rod].cut_length
    by = {s.title: s for s in steps}
    assert by["Top ring"].parts == ("corner_top_fl", "corner_top_fr", "corner_top_rr", "corner_top_rl")
    assert {d.frame.rods[r].role for r, _ in by["Top ring"].rods} == {"cage"}
    assert all("_top_" in r for r, _ in by["Top ring"].rods)
    assert {d.frame.rods[r].role for r, _ in by["Arms and motor mounts"].rods} == {"arm"}
    assert by["Arms and motor mounts"].parts == ("motor_mount_fl", "motor_mount_fr", "motor_mount_rr", "motor_mount_rl")
    assert set(by["Core"].parts) >= {"core_plate", "battery_holder", "core_link_fl", "core_link_mirrored_fr", "sensor_mount"}
    assert by["Camera and sensors"].parts == ("front_camera_mount",)
    assert any("hook-and-loop battery strap" in h for h in by["Core"].hardware)
    # glue: CA on the ring, never on the core links (the core stays removable)
    assert "CA" in by["Top ring"].glue and "CA" in by["Fold the sides"].glue
    assert by["Core"].glue.startswith("none") and by["Hang the core"].glue.startswith("none")
    assert not any("core link to plate" in h for h in by["Core"].hardware)  # the pegs press in: no link screw
    assert any("motor to mount" in h for h in by["Electronics"].hardware)


def test_markdown():
    d = _design("carbon")
    md = to_markdown(assembly_steps(d))
    assert md.startswith("# Assembly")
    top = d.frame.rods["rod_cage_top_front"].cut_length
    assert "## 1. Top ring" in md and f"rod_cage_top_front ({top:g} mm)" in md
    assert md.count("- Glue:") == len(assembly_steps(d))

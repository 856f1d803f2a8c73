"""At the bench (issue 45): every screw, nut and standoff the BOM lists is a solid of the assembly,
each screw head and nut can be turned by its driver, and nothing sits in the battery's slide path.

The keep-out rules (analysis/fit_check.keepouts, tested by analysis/clash.check) run here on the
bought parts' own solids (vitamins: primitives, no CAD); the preset builds' clash.json shows them
on every solid."""

from __future__ import annotations

import json
import re
import struct
from dataclasses import replace

import numpy as np
import pytest

from cogniframe import fasteners as fasteners_mod
from cogniframe.analysis import clash, fit_check
from cogniframe.design import design
from cogniframe.materials import COUNTERSUNK, MIN_THREAD_TURNS, SCREWS
from presets import preset_spec


def _design(name, **over):
    spec = preset_spec(name, **over)
    d = design(spec)
    return spec, d, fasteners_mod.fasteners(spec, d.frame, d.parts)


def _buys(item: str) -> str | None:
    """What a hardware line buys: "screw" (and its nut), "standoff" (a standoff or spacer), or None (a strap, a zip tie)."""
    if re.search(r"\bscrew\b", item):
        return "screw"
    if re.match(r"M[\d.]+ x [\d.]+ mm nylon (standoff|spacer)\b", item):
        return "standoff"
    return None


def _bom_counts(parts) -> dict[str, int]:
    """Hardware line -> how many the BOM buys, for the screw, standoff and spacer lines."""
    out: dict[str, int] = {}
    for p in parts:
        for h in p.hardware:
            if _buys(h.item):
                out[h.item] = out.get(h.item, 0) + h.qty * p.qty
    return out


@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_every_bom_screw_and_standoff_is_a_solid(name):
    """Carbon: 16 motor screws, 4 + 4 stack screws (holder and stack), 4 camera, 4 computer: the
    32 the BOM buys; bamboo 24. Each hardware line's quantity is the number of solids that name it,
    of the kind it buys."""
    from cogniframe.vitamins import vitamins

    spec, d, _ = _design(name)
    vits = vitamins(spec, d.frame, d.parts)
    bom = _bom_counts(d.parts)
    drawn: dict[str, int] = {}
    for v in vits:
        if v.family in ("screw", "standoff") and _buys(v.budget_line) == v.family:
            drawn[v.budget_line] = drawn.get(v.budget_line, 0) + 1
    assert drawn == bom
    screws = sum(q for item, q in bom.items() if _buys(item) == "screw")
    assert screws == sum(v.family == "screw" for v in vits) == {"carbon": 32, "bamboo": 24}[name]
    assert sum(v.family == "standoff" for v in vits) == {"carbon": 16, "bamboo": 8}[name]  # carbon: 4 standoffs, 4 + 4 stack spacers, 4 under the Pi


@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_holder_screws_sit_flush_in_countersinks_and_hold(name):
    """The holder's countersunk screws (ISO 7046 M2: 3.8 x 1.2 mm head) have their heads in the
    holder's top wall, flush with the cavity's ceiling, 1 mm over the pack; they engage their
    standoff 4 turns and stop short of its middle (the stack screw comes in from the top)."""
    spec, d, fs = _design(name)
    holder = next(p for p in d.parts if p.name == "battery_holder")
    ceiling = float(d.frame.core.holder.hi[2]) - spec.core.holder_wall
    dk, k = COUNTERSUNK["M2"]
    assert holder.param("countersink_d") == pytest.approx(dk + 0.2)
    assert k <= spec.core.holder_wall  # the head fits in the wall
    assert ceiling - float(d.frame.core.battery.hi[2]) == pytest.approx(1.0)
    held = [f for f in fs if f.name.startswith("screw_holder_")]
    assert len(held) == 4
    for f in held:
        assert f.head == "countersunk" and f.base[2] == pytest.approx(ceiling) and f.axis == (0.0, 0.0, 1.0)
        assert MIN_THREAD_TURNS * SCREWS["M2"].pitch <= f.engagement <= f.thread_depth
        assert f.thread.startswith("standoff_")


def _vitamin_bodies(spec, d):
    """The bought parts as clash bodies, each at its stage (as export/assembly.bodies makes them)."""
    from cogniframe.fasteners import VITAMIN_STAGES
    from cogniframe.vitamins import to_trimesh, vitamins

    return [clash.Body(v.name, "vitamin", to_trimesh(v), stage=v.stage or VITAMIN_STAGES[v.family])
            for v in vitamins(spec, d.frame, d.parts)]


def _keepout_clashes(bodies, keepouts) -> tuple:
    """The keep-outs' clashes only: no pair of bodies is tested against each other."""
    none = frozenset(frozenset((a.name, b.name)) for a in bodies for b in bodies)
    return clash.check(bodies, keepouts=keepouts, ignore=none).clashes


def test_old_holder_screws_block_the_battery_path():
    """The arrangement before issue 45: socket-head M2 screws from inside the holder, their 2 mm heads
    under the ceiling, 1 mm over the pack: the battery's slide path hits every one of them (a 3.8 mm
    head 1 mm deep: 11.3 mm^3 each). The countersunk heads clear it."""
    from cogniframe.vitamins import fastener_vitamin, to_trimesh

    spec, d, fs = _design("carbon")
    battery = next(b for b in _vitamin_bodies(spec, d) if b.name == "battery")
    path = [k for k in fit_check.keepouts(spec, d.frame, fs) if k.rule == "battery_path"]

    def clashes(screws):
        return _keepout_clashes([battery] + [clash.Body(f.name, "vitamin", to_trimesh(fastener_vitamin(f)), stage=f.stage)
                                             for f in screws], path)

    now = [f for f in fs if f.name.startswith("screw_holder_")]
    assert clashes(now) == ()
    old = [replace(f, head="socket") for f in now]
    found = clashes(old)
    assert sorted(c.b for c in found) == sorted(f.name for f in old)
    for c in found:
        assert c.kind == "battery_path" and c.a == "battery_path"
        assert c.volume_mm3 == pytest.approx(np.pi * 1.9**2 * 1.0, rel=0.02)
        assert "slide path" in c.message(5.0)


def test_a_driver_sees_only_what_is_fitted_by_its_stage():
    """Carbon's stack screws go in from the computer mount's top before the Pi Zero is fitted: their
    drivers clear everything fitted by then. Were they driven after the computer (stage "computer"),
    each driver would hit its board 1 mm above the head."""
    spec, d, fs = _design("carbon")
    bodies = _vitamin_bodies(spec, d)
    stack = [f for f in fs if f.name.startswith("screw_stack_")]
    ko = [k for k in fit_check.keepouts(spec, d.frame, stack) if k.rule == "driver"]
    assert _keepout_clashes(bodies, ko) == ()
    late = [k for k in fit_check.keepouts(spec, d.frame, [replace(f, stage="computer") for f in stack]) if k.rule == "driver"]
    found = _keepout_clashes(bodies, late)
    assert sorted(c.a for c in found) == sorted(f"driver_{f.name}" for f in stack)
    assert {c.b for c in found} == {"computer"} and all(c.kind == "driver" for c in found)
    assert "cannot be turned" in found[0].message(5.0)


def _glb_names(path) -> list[str]:
    data = path.read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    return [node["name"] for node in json.loads(data[20:20 + n])["nodes"]]


@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_build_glb_holds_every_bom_screw_and_clash_json_the_keepouts(name, preset_build):
    import csv

    out = preset_build(name)
    rows = list(csv.DictReader((out / "bom.csv").open()))
    hardware = [r for r in rows if r["category"] == "hardware"]
    bom_screws = sum(int(r["qty"]) for r in hardware if _buys(r["item"]) == "screw")
    bom_standoffs = sum(int(r["qty"]) for r in hardware if _buys(r["item"]) == "standoff")
    names = _glb_names(out / "assembly.glb")
    assert sum(n.startswith("screw_") for n in names) == bom_screws == {"carbon": 32, "bamboo": 24}[name]
    assert sum(n.startswith(("standoff_", "spacer_")) for n in names) == bom_standoffs
    c = json.loads((out / "clash.json").read_text())
    assert c["ok"] and c["clashes"] == []
    screws_and_nuts = sum(n.startswith(("screw_", "nut_")) for n in names)
    assert c["keepouts"] == screws_and_nuts + 1  # a driver each, and the battery's slide path

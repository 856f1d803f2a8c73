"""The assembly guide's pictures (report/step_views.py): one per step, the step's new parts
highlighted, an exploded view where parts go in along a line.

The render inputs are checked against the steps (what each picture highlights is exactly what its
step fits; every thing of the assembly is fitted in one step), the pictures' pixels against the
highlight colour (drawn from stand-in meshes, so no CAD is needed), and the built report of the
carbon preset (one picture per step in report.html, in Chromium too).
"""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cogniframe import design as design_mod
from cogniframe import spec as spec_mod
from cogniframe.fasteners import VITAMIN_STAGES, fasteners
from cogniframe.report import step_views as sv
from cogniframe.report.assembly_steps import assembly_steps, copy_labels
from cogniframe.vitamins import vitamins

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module", params=["carbon", "bamboo"])
def guide(request):
    d = design_mod.design(spec_mod.load(ROOT / "params" / f"{request.param}.yaml"))
    steps = assembly_steps(d)
    return request.param, d, steps, sv.step_views(d, steps)


def _items(d) -> set[str]:
    """Everything the assembly (GLB, clash check) holds: part copies, rods, bought parts and fasteners."""
    return ({label for p in d.parts for label in copy_labels(p)} | set(d.frame.rods)
            | {v.name for v in vitamins(d.spec, d.frame, d.parts)})


def test_each_picture_highlights_exactly_its_steps_new_parts(guide):
    _, d, steps, views = guide
    assert [v.number for v in views] == [s.number for s in steps]
    stage = {v.name: v.stage or VITAMIN_STAGES.get(v.family, "frame") for v in vitamins(d.spec, d.frame, d.parts)}
    own = {s.number: set(s.parts) | {r for r, _ in s.rods} | {n for n, st in stage.items() if st in s.stages}
           for s in steps}
    for s, v in zip(steps, views):
        expected = own[s.number].union(*(own[k] for k in s.places))
        assert set(v.new) == expected, s.title
        assert set(v.new) <= set(v.shown), s.title
    # every thing of the assembly is fitted in exactly one step
    fitted = [n for s in steps for n in own[s.number]]
    assert len(fitted) == len(set(fitted))
    assert set(fitted) == _items(d)


def test_what_each_step_highlights(guide):
    name, d, steps, views = guide
    by_title = {v.title: v for v in views}
    arms = set(by_title["Arms, motor mounts and motors"].new)
    assert {f"motor_{c}" for c in ("fl", "fr", "rr", "rl")} <= arms
    assert sum(n.startswith("screw_motor_") for n in arms) == 16  # four M2 screws per motor
    core = by_title["Core"]
    assert "core_plate" in core.new and "battery_holder" in core.new
    assert set(core.shown) == set(core.new)  # built off the frame: drawn alone
    assert not any(n.startswith("rod_") for n in core.shown)
    hang = by_title["Hang the core"]
    assert set(hang.new) == set(core.new) and set(d.frame.rods) <= set(hang.shown)
    last = views[-1]
    assert {"battery", "propeller_fl"} <= set(last.new)
    assert set(last.shown) == _items(d)  # the last picture is the whole aircraft
    # the core is not drawn in the frame before it is hung
    before = by_title["Struts"] if "Struts" in by_title else by_title["Arms, motor mounts and motors"]
    assert "core_plate" not in before.shown


def test_exploded_views_draw_parts_back_along_their_line(guide):
    _, d, steps, views = guide
    by_title = {v.title: v for v in views}
    for title in ("Top ring", "Bottom ring", "Knees and upper legs", "Fold the sides", "Hang the core"):
        assert not by_title[title].explode, title  # rods pushed in along many lines: no exploded view
        assert len(by_title[title].files()) == 1
    arms = dict(by_title["Arms, motor mounts and motors"].explode)
    screw = next(f for f in fasteners(d.spec, d.frame, d.parts) if f.name == "screw_motor_fl_1")
    # a motor screw goes up into the motor: drawn back down by its length and a gap
    assert arms["screw_motor_fl_1"] == pytest.approx(tuple(-np.asarray(screw.axis) * (screw.length + sv.GAP)))
    assert arms["motor_fl"] == (0.0, 0.0, sv.LIFT)
    assert not any(n.startswith(("rod_", "motor_mount")) for n in arms)  # the mounts stay on their rods
    last = dict(views[-1].explode)
    core = d.frame.core
    # the battery out of the holder's open front end, clear of it by a gap
    assert last["battery"] == pytest.approx((0.0, core.holder.hi[1] - core.battery.lo[1] + sv.GAP, 0.0))
    stack = dict(by_title["Core"].explode)
    assert "battery_holder" not in stack  # the stack's lowest level stays
    assert stack["core_plate"][2] > 0 and stack["core_plate"][2] % sv.GAP == pytest.approx(0.0)
    assert views[-1].files() == (f"renders/steps/step_{views[-1].number:02d}.png",
                                 f"renders/steps/step_{views[-1].number:02d}_exploded.png")


# -- pixels -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """The carbon guide's pictures drawn from stand-in meshes (cylinders for the joints and mounts,
    boxes for the core's parts) with the real rods and bought parts."""
    d = design_mod.design(spec_mod.load(ROOT / "params" / "carbon.yaml"))
    meshes = {p.name: (trimesh.creation.cylinder(radius=7, height=8, sections=24) if p.family in ("joint", "motor_mount")
                       else trimesh.creation.box(p.estimate.envelope)) for p in d.parts}
    views = sv.step_views(d, assembly_steps(d))
    items = sv.scene_items(d, meshes, {p.name: np.eye(4) for p in d.parts})
    out = tmp_path_factory.mktemp("steps")
    return d, views, items, sv.render_step_views(views, items, out), out


def test_every_picture_shows_the_highlight_and_only_those_do(drawn, tmp_path):
    from PIL import Image

    d, views, items, written, _ = drawn
    assert sorted(written) == [v.number for v in views]
    for v in views:
        assert len(written[v.number]) == len(v.files())
        for path in written[v.number]:
            assert Image.open(path).size == sv.SIZE
            assert sv.highlight_fraction(path) > 5e-4, path  # the new parts show, in orange
    # the whole aircraft with nothing highlighted: a few orange pixels at most, where the edges of red
    # and yellow parts blend (2 of its 172800 when written): the colour marks the new parts
    plain = sv.StepView(99, "whole", views[-1].shown, ())
    (path,) = sv.render_step_views([plain], items, tmp_path)[99]
    assert sv.highlight_fraction(path) < 1e-4


def test_same_views_same_bytes(drawn, tmp_path):
    _, views, items, written, _ = drawn
    again = sv.render_step_views(views[6:8], items, tmp_path)  # another plotter, fewer pictures before
    for n, paths in again.items():
        assert [p.read_bytes() for p in paths] == [p.read_bytes() for p in written[n]]


class _Store:
    """A dict as `render_step_views`' store of pictures drawn before, counting what it is given."""

    def __init__(self):
        self.pngs: dict[str, bytes] = {}
        self.puts = 0

    def get(self, key):
        return self.pngs.get(key)

    def put(self, key, data):
        self.puts += 1
        self.pngs[key] = data


def test_an_edit_draws_only_the_pictures_that_show_what_it_changed(drawn, tmp_path):
    """After one part's mesh changes, the pictures that do not show it come from the store, the
    others are drawn again, and every picture is the bytes of drawing the edited scene afresh."""
    _, views, items, written, _ = drawn
    store = _Store()
    sv.render_step_views(views, items, tmp_path / "first", known=store)
    pictures = sum(len(v.files()) for v in views)
    assert store.puts == pictures
    for n, paths in written.items():  # the store changes no byte of a first drawing
        assert [(tmp_path / "first" / p.relative_to(drawn[4])).read_bytes() for p in paths] == [p.read_bytes() for p in paths]

    edited_part = next(i.name for i in items if i.name.startswith("motor_mount"))
    part = edited_part.rsplit("_", 1)[0]
    edited = [sv.Item(i.name, i.vertices * np.array([1.0, 1.0, 1.5]) if i.name.startswith(part) else i.vertices,
                      i.faces, i.colour, i.opacity) for i in items]
    showing = sum(len(v.files()) for v in views if any(n.startswith(part) for n in v.shown))
    assert 0 < showing < pictures
    store.puts = 0
    again = sv.render_step_views(views, edited, tmp_path / "again", known=store)
    assert store.puts == showing  # only those are drawn
    fresh = sv.render_step_views(views, edited, tmp_path / "fresh")
    for n, paths in fresh.items():
        assert [p.read_bytes() for p in again[n]] == [p.read_bytes() for p in paths]


# -- the built report ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def carbon_build(preset_build):
    return preset_build("carbon")


def _pictures(html: str, css_class: str) -> list[bytes]:
    return [base64.b64decode(src) for src in re.findall(rf'<img class="{css_class}" src="data:image/png;base64,([^"]+)"', html)]


def test_report_has_one_picture_per_step_each_with_its_new_parts(carbon_build, tmp_path):
    d = design_mod.design(spec_mod.load(ROOT / "params" / "carbon.yaml"))
    views = sv.step_views(d, assembly_steps(d))
    html = (carbon_build / "report.html").read_text(encoding="utf-8")
    main, exploded = _pictures(html, "step-view"), _pictures(html, "step-exploded")
    assert len(main) == len(views) == len(assembly_steps(d))
    assert len(exploded) == sum(1 for v in views if v.explode)
    for i, data in enumerate(main + exploded):
        (tmp_path / f"{i}.png").write_bytes(data)
        assert sv.highlight_fraction(tmp_path / f"{i}.png") > 5e-4, i
    md = (carbon_build / "assembly.md").read_text(encoding="utf-8")
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    assert links == [f for v in views for f in v.files()]
    assert all((carbon_build / link).is_file() for link in links)


@pytest.mark.browser
def test_chromium_shows_one_picture_per_step(carbon_build):
    from browser import CHROMIUM, FLAGS, browser_or_skip

    browser_or_skip()
    from playwright.sync_api import sync_playwright

    d = design_mod.design(spec_mod.load(ROOT / "params" / "carbon.yaml"))
    n = len(assembly_steps(d))
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1100, "height": 900})
            page.goto((carbon_build / "report.html").as_uri())
            sizes = page.eval_on_selector_all(
                "#assembly img.step-view", "imgs => imgs.map(i => [i.complete, i.naturalWidth, i.naturalHeight])")
            rows = page.eval_on_selector_all("#assembly tbody tr", "rows => rows.length")
        finally:
            browser.close()
    assert rows == n
    assert sizes == [[True, sv.SIZE[0], sv.SIZE[1]]] * n  # every picture decoded at its size

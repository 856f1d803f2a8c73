"""The report's interactive 3D view in a real headless Chromium (Debian's /usr/bin/chromium via Playwright).

The report is written from the carbon preset's real part meshes (CAD) with the viewer items the
build uses. In the browser: no request leaves the file (only file: and blob: URLs), the canvas
draws the model (pixels that are not the background: TPU red and rod black), hiding the rods
removes the black, and a real mouse click on a part shows its name, material, mass, quantity and
plate. Outside CI the browser tests are skipped when Chromium or Playwright is missing; under
CI (`CI` set) they fail instead, so the check cannot silently vanish.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pytest

import tiers

from browser import CHROMIUM, FLAGS, browser_or_skip
import trimesh

import cogniframe as cf
from cogniframe import design as design_mod
from cogniframe.analysis import verdict
from cogniframe import spec as spec_mod
from cogniframe.analysis.mass import PartGeometry
from cogniframe.export.plates import PlateItem, pack_plates, write_plates
from cogniframe.report import html as report
from cogniframe.report.viewer import BACKGROUND, ViewerItem, design_items

ROOT = Path(__file__).resolve().parents[1]




@pytest.fixture(scope="module")
@tiers.needs('cad', 'fe')
def carbon_report(tmp_path_factory):
    """report.html for the carbon preset with the real meshes; returns (path, items, check result)."""
    from cogniframe.cache import cache_dir
    from cogniframe.export.part_files import build_parts

    out = tmp_path_factory.mktemp("viewer") / "carbon"
    out.mkdir()
    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    d = design_mod.design(spec)
    built = build_parts(spec, d.frame, d.parts, out, cache_dir=cache_dir())
    meshes = {b.name: trimesh.load(out / b.stl, force="mesh") for b in built}
    result = verdict.check(spec, {b.name: PartGeometry(b.volume_mm3, b.area_h_mm2, b.area_v_mm2, "cad") for b in built})
    plates = write_plates(pack_plates([PlateItem(b.name, b.material, b.qty, meshes[b.name]) for b in built],
                                      spec.printer.bed, spec.printer.margin), out / "plates")
    items = design_items(d, meshes, {b.name: b.print_from_local for b in built}, result.mass, plates)
    html_path, _ = report.write_report(result, out, plates=plates, viewer_items=items)
    return html_path, items, result


def test_report_size_and_bytes_stable(carbon_report, tmp_path):
    html_path, items, result = carbon_report
    size = html_path.stat().st_size
    assert size < 5_000_000, f"report.html is {size / 1e6:.2f} MB"
    again, _ = report.write_report(result, tmp_path, plates=(), viewer_items=items)
    first = html_path.read_text(encoding="utf-8")
    section = re.search(r'<section id="viewer-section">.*?</section>', first, re.S).group(0)
    assert section in again.read_text(encoding="utf-8")  # the same items give the same viewer bytes
    # the viewer sits right under the verdicts, before the first report section
    assert first.index('id="verdicts"') < first.index('id="viewer-section"') < first.index('<section id="mass"')
    # parts: every copy of every printed part; rods: every frame rod
    d = result.design
    assert sum(1 for i in items if i.kind == "part") == sum(p.qty for p in d.parts)
    assert sum(1 for i in items if i.kind == "rod") == len(d.frame.rods)


def test_html_loads_nothing_from_the_network(carbon_report):
    text = carbon_report[0].read_text(encoding="utf-8")
    assert not re.findall(r"""(?:src|href)\s*=\s*["']?\s*(?:https?:)?//""", text, re.I)
    assert "@import" not in text and not re.search(r"url\(\s*['\"]?(?:https?:)?//", text)


# -- in the browser -------------------------------------------------------------------------

@pytest.fixture(scope="module")
@tiers.needs('browser')
def page_factory():
    browser_or_skip()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)

        def open_page(path: Path):
            page = browser.new_page(viewport={"width": 1100, "height": 900})
            seen, errors = [], []
            page.on("request", lambda r: seen.append(r.url))
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(path.as_uri())
            page.wait_for_selector("#cf-viewer[data-ready='1'], #cf-viewer[data-error]", timeout=60_000)
            err = page.get_attribute("#cf-viewer", "data-error")
            assert err is None and not errors, (err, errors)
            page.locator("#cf-viewer").scroll_into_view_if_needed()
            return page, seen

        yield open_page
        browser.close()


def _pixels(page) -> np.ndarray:
    from PIL import Image

    # the toolbar and info panel float over the canvas: hide them so only WebGL's pixels count
    page.evaluate("document.querySelectorAll('.cf-bar, .cf-info').forEach(e => e.style.visibility = 'hidden')")
    png = page.locator("#cf-canvas").screenshot()
    page.evaluate("document.querySelectorAll('.cf-bar, .cf-info').forEach(e => e.style.visibility = '')")
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def _rendered(page) -> None:
    """Once the view has drawn what the page asked for before: the viewer renders in the next
    animation frame, and a frame asked for now comes after it (events, not a wait of some ms)."""
    page.evaluate("new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))")


def _counts(img: np.ndarray) -> dict[str, int]:
    bg = np.array([int(BACKGROUND[i:i + 2], 16) for i in (1, 3, 5)])
    img = img[2:-2, 2:-2]  # the element box can take in a pixel row of the frame's border
    drawn = np.abs(img - bg).sum(axis=2) > 30
    red = (img[..., 0] > 110) & (img[..., 1] < 80) & (img[..., 2] < 80)  # TPU parts (#d62728, shaded)
    black = img.max(axis=2) < 60  # rods (#1a1a1a) and the shaded side of the ABS core (#404040)
    return {"drawn": int(drawn.sum()), "red": int(red.sum()), "black": int(black.sum()), "all": int(drawn.size)}


def test_canvas_draws_the_model_and_rods_toggle(carbon_report, page_factory):
    page, seen = page_factory(carbon_report[0])
    assert {u.split(":", 1)[0] for u in seen} <= {"file", "blob"}, seen
    renderer = page.evaluate("(() => { const gl = document.createElement('canvas').getContext('webgl2')"
                             " || document.createElement('canvas').getContext('webgl'); return gl ? 'ok' : 'none'; })()")
    assert renderer == "ok", "no WebGL in this Chromium (software GL flags?)"
    d = carbon_report[2].design
    assert page.evaluate("window.cogniframeViewer.kinds") == {"part": sum(p.qty for p in d.parts), "rod": len(d.frame.rods)}
    full = _counts(_pixels(page))
    assert full["drawn"] > 0.04 * full["all"], full
    assert full["red"] > 2000 and full["black"] > 2000, full
    page.locator("input[data-kind='rod']").uncheck()
    _rendered(page)
    no_rods = _counts(_pixels(page))
    # the rods are most of the near-black pixels (the rest is the dark ABS core in shadow)
    assert no_rods["black"] < 0.5 * full["black"] and no_rods["drawn"] < 0.75 * full["drawn"], (full, no_rods)
    assert no_rods["red"] > 0.8 * full["red"], (full, no_rods)
    assert page.locator("input[data-kind='vitamin']").is_disabled()  # none in this design yet
    page.close()


@pytest.mark.parametrize("name", ["knee_fl", "core_plate", "rod_cage_top_front"])
def test_click_on_a_part_shows_its_data(carbon_report, page_factory, name):
    html_path, items, result = carbon_report
    item = next(i for i in items if i.name == name)
    page, _ = page_factory(html_path)
    pt = page.evaluate(f"window.cogniframeViewer.screenPointOf({name!r})")
    assert pt is not None, f"{name} is not visible in the default view"
    box = page.locator("#cf-canvas").bounding_box()
    px, py = int(pt["x"] - box["x"]), int(pt["y"] - box["y"])
    bg = np.array([int(BACKGROUND[i:i + 2], 16) for i in (1, 3, 5)])
    before = _pixels(page)[py - 1:py + 2, px - 1:px + 2].reshape(-1, 3).mean(axis=0)
    assert np.abs(before - bg).sum() > 60, f"nothing drawn where {name} should be: {before}"
    page.mouse.click(pt["x"], pt["y"])
    field = lambda f: page.locator(f".cf-info dd[data-field='{f}']").inner_text()  # noqa: E731
    assert field("name") == name
    assert page.get_attribute("#cf-viewer", "data-selected") == name
    assert field("material") == item.material and field("quantity") == str(item.qty)
    assert field("mass") == f"{item.mass_g:.2f} g each"
    if item.kind == "part":
        budget = {i.name: i.mass_g_each for i in result.mass.items}
        part = item.note.split()[-1]
        assert item.mass_g == pytest.approx(budget[part])
        assert field("plate") == item.plate and re.fullmatch(r"(tpu_95a|abs)_\d+", item.plate)
    else:
        assert field("plate") == "not printed" and field("note").startswith("cut to ")
    after = _pixels(page)[py - 1:py + 2, px - 1:px + 2].reshape(-1, 3).mean(axis=0)
    assert after[2] > before[2] + 30, f"{name} not highlighted: {before} -> {after}"  # the blue selection glow
    # a click on the empty background clears the selection
    page.mouse.click(box["x"] + 8, box["y"] + box["height"] - 8)
    assert page.get_attribute("#cf-viewer", "data-selected") == ""
    page.close()


def test_vitamins_from_the_item_list_show_and_toggle(page_factory, tmp_path):
    """Data-driven: a `vitamin` item appears, is clickable, and hides."""
    # the figures are not what is looked at: the fast model's (no joint FE, so no tier of its own)
    spec = cf.load(ROOT / "params" / "carbon.yaml").with_fast_model().spec
    result = verdict.check(spec)
    battery = trimesh.creation.box((70, 35, 15))
    items = [ViewerItem("battery", "vitamin", "LiPo 2S", 58.0, 1, "", "#2060c0", battery, np.eye(4), note="vitamin"),
             ViewerItem("motor_fl", "vitamin", "motor 1104", 6.0, 4, "", "#8a8a8a",
                        trimesh.creation.cylinder(radius=7, height=10), np.eye(4) @ trimesh.transformations.translation_matrix([60, 0, 0]))]
    html_path, _ = report.write_report(result, tmp_path, viewer_items=items)
    page, _ = page_factory(html_path)
    assert page.evaluate("window.cogniframeViewer.kinds") == {"vitamin": 2}
    toggle = page.locator("input[data-kind='vitamin']")
    assert toggle.is_enabled()
    pt = page.evaluate("window.cogniframeViewer.screenPointOf('battery')")
    page.mouse.click(pt["x"], pt["y"])
    assert page.locator(".cf-info dd[data-field='name']").inner_text() == "battery"
    assert page.locator(".cf-info dd[data-field='mass']").inner_text() == "58.00 g each"
    drawn = _counts(_pixels(page))["drawn"]
    toggle.uncheck()
    _rendered(page)
    assert _counts(_pixels(page))["drawn"] < 0.01 * drawn
    assert page.get_attribute("#cf-viewer", "data-selected") == ""  # a hidden object is deselected
    page.close()

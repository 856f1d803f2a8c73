"""report.html / report.md: numbers equal `check --json`, every image is an embedded PNG,
every expected table is there, and the Markdown's images exist beside it."""

from __future__ import annotations

import base64
import io
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import tiers
import trimesh

from cogniframe.analysis import verdict
from cogniframe import spec as spec_mod
from cogniframe.export.plates import PlateItem, pack_plates, write_plates
from cogniframe.export.slicer import MaterialCheck, PlateSlice, SliceReport
from cogniframe.report import assembly_steps, bom, html as report
from meshes import box as _box

ROOT = Path(__file__).resolve().parents[1]


class _Page(HTMLParser):
    """Collects tables (by id, with their cell texts), images and data-key values."""

    def __init__(self):
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self.images: list[str] = []
        self.keys: dict[str, list[str]] = {}
        self._table: str | None = None
        self._cell: list[str] | None = None
        self._key_stack: list[str | None] = []
        self._key_text: dict[int, list[str]] = {}

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self._table = a.get("id", f"table{len(self.tables)}")
            self.tables[self._table] = []
        elif tag == "tr" and self._table:
            self.tables[self._table].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "img":
            self.images.append(a.get("src", ""))
        if tag not in ("img", "meta", "br"):
            self._key_stack.append(a.get("data-key"))
            if a.get("data-key"):
                self._key_text[len(self._key_stack)] = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None and self._table and self.tables[self._table]:
            self.tables[self._table][-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag == "table":
            self._table = None
        if tag not in ("img", "meta", "br") and self._key_stack:
            depth = len(self._key_stack)
            key = self._key_stack.pop()
            if key:
                self.keys.setdefault(key, []).append("".join(self._key_text.pop(depth)).strip())

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
        for buf in self._key_text.values():
            buf.append(data)


def _png(path: Path, colour=(200, 30, 30)) -> Path:
    from PIL import Image

    img = np.full((60, 80, 3), 255, np.uint8)
    img[10:50, 10:70] = colour
    Image.fromarray(img).save(path)
    return path


@pytest.fixture(scope="module", params=("carbon", "bamboo"))
@tiers.needs('fe')
def written(request, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / request.param
    spec = spec_mod.load(ROOT / "params" / f"{request.param}.yaml")
    result = verdict.check(spec)
    d = result.design
    items = [PlateItem(p.name, p.material, p.qty, _box(*(min(v, 60.0) for v in p.estimate.envelope))) for p in d.parts]
    plates = write_plates(pack_plates(items, spec.printer.bed, spec.printer.margin), out / "plates")
    sliced = tuple(PlateSlice(f.name, f.material, f.threemf, f.threemf.with_suffix(".gcode"), 10.0 + i, 3600.0 * (i + 1),
                              tuple((c, 100.0) for c in f.copies), 0.5) for i, f in enumerate(plates))
    mats = {}
    for s in sliced:
        mats.setdefault(s.material, [0.0, 0.0])
        mats[s.material][0] += s.grams
        mats[s.material][1] += s.time_s
    est = result.mass.by_material
    slice_report = SliceReport("PrusaSlicer-test", sliced, tuple(MaterialCheck(m, g, est[m], t) for m, (g, t) in sorted(mats.items())),
                               ("tpu_95a: made-up warning for the test",))
    lines = bom.build_bom(spec, d, result.mass, slice_report)
    steps = assembly_steps.assembly_steps(d)
    renders_dir = out / "renders"
    renders_dir.mkdir(parents=True)
    images = {"assembly iso": _png(renders_dir / "assembly_iso.png"), "part knee": _png(renders_dir / "knee.png", (60, 60, 60))}
    html_path, md_path = report.write_report(result, out, images, lines, steps, plates, slice_report)
    page = _Page()
    page.feed(html_path.read_text(encoding="utf-8"))
    return result, out, html_path, md_path, page, plates, lines, steps


def test_numbers_equal_check_json(written):
    result, _, _, _, page, *_ = written
    cd = verdict.check_dict(result)
    for key in ("mass.total_g", "mass.limit_g", "mass.margin_g", "drop.k_n_per_m", "drop.max_safe_height_cm",
                "drop.clearance_mm"):
        assert key in page.keys, key
        assert set(page.keys[key]) == {report.fmt_key(cd, key)}, key
    # and the formats really are the JSON's values rounded
    assert page.keys["mass.total_g"][0] == f"{cd['mass']['total_g']:.2f}"
    assert float(page.keys["drop.k_n_per_m"][0]) == pytest.approx(round(cd["drop"]["k_n_per_m"]))
    assert float(page.keys["drop.max_safe_height_cm"][0]) == pytest.approx(round(cd["drop"]["max_safe_height_cm"], 1))
    assert page.keys["verdict"] == [cd["verdict"]]
    # the mass-budget table repeats the JSON's items and total
    rows = page.tables["mass-budget"]
    body = rows[1:-1]
    assert [r[0] for r in body] == [i["name"] for i in cd["mass"]["items"]]
    assert [r[4] for r in body] == [f"{i['mass_g']:.2f}" for i in cd["mass"]["items"]]
    assert rows[-1][4] == f"{cd['mass']['total_g']:.2f}"
    drop_rows = page.tables["drop"][1:]
    assert [r[2] for r in drop_rows] == [f"{h['x_max_mm']:.2f}" for h in cd["drop"]["heights"]]
    assert [r[1] for r in page.tables["cutlist"][1:]] == [f"{r['length_mm']:g}" for r in cd["cutlist"]]
    # one drop's peak deceleration, median and 90th percentile per height, beside the mean pulse's
    one_drop = next(r for r in page.tables["load-cases"] if r[0].startswith("peak |a| of one drop"))
    assert one_drop[1] == ", ".join(f"{h['height_cm']:g} cm: {h['peak_g_drop_median']:.0f} G ({h['peak_g_drop_p90']:.0f} G)"
                                    for h in cd["peak_g"]["heights"])


def test_verdicts_on_top(written):
    result, _, html_path, _, page, *_ = written
    text = html_path.read_text(encoding="utf-8")
    assert text.index('id="verdicts"') < text.index('id="mass-budget"')
    rows = {r[0]: r for r in page.tables["verdicts"][1:]}
    assert set(rows) == {"Mass", "Crash margin", "What breaks first", "Printability", "Vibration against the motors",
                         "Design verdict"}
    # the presets' frame modes sit in the attitude loop's band: WARN, the design verdict unchanged
    assert rows["Vibration against the motors"][1] == ("WARN" if result.warnings else "PASS")
    f = result.survival.first_failure
    assert rows["What breaks first"][2].startswith("first to fail" if f else "nothing fails in flat drops up to")
    assert rows["Mass"][1] == ("PASS" if result.mass.total_g <= result.mass.limit_g else "FAIL")
    assert rows["Printability"][1] == "WARN"  # the slice report carries a warning
    assert rows["Design verdict"][1] == result.verdict


def test_every_image_is_an_embedded_png(written):
    from PIL import Image

    _, _, _, _, page, plates, *_ = written
    # mass chart + stiffness + drop response + energy split + survival margins + 2 renders + one preview per plate
    assert len(page.images) == 5 + 2 + len(plates)
    for src in page.images:
        assert src.startswith("data:image/png;base64,")
        data = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        with Image.open(io.BytesIO(data)) as im:
            im.verify()


def test_every_table_is_present(written):
    _, _, _, _, page, plates, lines, steps = written
    for tid in ("verdicts", "mass-budget", "mass-groups", "drop-model", "drop", "props", "cutlist", "stock", "bom",
                "plates", "slicer", "assembly"):
        assert tid in page.tables and len(page.tables[tid]) > 1, tid
    assert len(page.tables["bom"]) == 1 + len(lines) + 1  # header, lines, total
    assert len(page.tables["assembly"]) == 1 + len(steps)
    assert [r[0] for r in page.tables["plates"][1:]] == [p.name for p in plates]
    assert page.tables["plates"][1][4] == "10.0"  # sliced grams shown per plate


def test_markdown_twin(written):
    result, out, _, md_path, *_ = written
    md = md_path.read_text(encoding="utf-8")
    cd = verdict.check_dict(result)
    assert md.startswith(f"# cogniframe report: {cd['name']}")
    assert f"all-up weight {cd['mass']['total_g']:.2f} g" in md
    assert f"max safe drop {cd['drop']['max_safe_height_cm']:.1f} cm" in md
    for title in ("## Mass budget", "## Stiffness and drop model", "## Cut list and stock plan", "## Bill of materials",
                  "## Print plates", "## Assembly", "## Renders"):
        assert title in md
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    assert links and all((out / link).is_file() for link in links)
    assert "warning: tpu_95a: made-up warning for the test" in md


def test_same_input_same_report(written, tmp_path):
    result, out, html_path, md_path, page, plates, lines, steps = written
    images = {"assembly iso": out / "renders" / "assembly_iso.png", "part knee": out / "renders" / "knee.png"}
    h2, m2 = report.write_report(result, tmp_path, images, lines, steps, plates, None)
    h3, _ = report.write_report(result, tmp_path / "again", images, lines, steps, plates, None)
    assert h2.read_bytes() == h3.read_bytes()
    assert "not sliced" in h2.read_text(encoding="utf-8")


@pytest.mark.skipif(shutil.which("chromium") is None, reason="chromium is not installed (optional check)")
@pytest.mark.browser
def test_opens_in_headless_chromium(written, tmp_path):
    import subprocess

    _, _, html_path, *_ = written
    shot = tmp_path / "shot.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                    "--window-size=1200,2000", html_path.resolve().as_uri()], check=True, capture_output=True, timeout=120)
    assert shot.is_file() and shot.stat().st_size > 10_000


def _text_outside(fig) -> list[str]:
    """Titles, axis labels, legend and annotation texts of a drawn figure that reach past its edges
    (clipped in the PNG). Tick labels are left out: matplotlib skips those outside the view."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    w, h = fig.bbox.width, fig.bbox.height
    texts = [fig._suptitle] if fig._suptitle is not None else []
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label, *ax.texts]
        if ax.get_legend() is not None:
            texts += ax.get_legend().get_texts()
    out = []
    for t in texts:
        if not t.get_visible() or not t.get_text().strip():
            continue
        bb = t.get_window_extent(renderer)
        if bb.x0 < -0.5 or bb.y0 < -0.5 or bb.x1 > w + 0.5 or bb.y1 > h + 0.5:
            out.append(f"{t.get_text()!r} spans x {bb.x0:.0f}..{bb.x1:.0f}, y {bb.y0:.0f}..{bb.y1:.0f} of {w:.0f} x {h:.0f}")
    return out


@pytest.mark.parametrize("preset", ["carbon", "bamboo"])
@pytest.mark.cad
@pytest.mark.fe
def test_no_figure_clips_its_title(preset, monkeypatch, tmp_path):
    from cogniframe.report import drop_plots

    result = verdict.check(spec_mod.load(ROOT / "params" / f"{preset}.yaml"))
    cd = verdict.check_dict(result)
    figs = []
    real_save = drop_plots._save
    monkeypatch.setattr(drop_plots, "_save", lambda fig, path: (figs.append(fig), real_save(fig, path))[1])
    drop_plots.plot_drop_response(result.drop, tmp_path / "a.png")
    drop_plots.plot_energy_split(result.drop, tmp_path / "b.png")
    report.plot_mass_groups(cd["mass"], tmp_path / "c.png")
    report.plot_stiffness(cd["drop"], tmp_path / "d.png")
    assert len(figs) == 4
    for fig in figs:
        assert not _text_outside(fig)
    title = figs[0].axes[0].get_title()
    assert f"max safe height {result.drop.max_safe_height_cm:.1f} cm" in title  # still says everything


def test_viewer_geometry_round_trips_within_the_quantisation_step():
    from cogniframe.report.viewer import ViewerItem, pack

    box = _box(40, 20, 3)
    cyl = trimesh.creation.cylinder(radius=7.5, height=12, sections=40)
    m = trimesh.transformations.translation_matrix([10, -5, 2]) @ trimesh.transformations.rotation_matrix(0.3, [0, 0, 1])
    items = [ViewerItem("plate_1", "part", "abs", 3.58, 1, "abs_1", "#404040", box),
             ViewerItem("plate_2", "part", "abs", 3.58, 1, "abs_1", "#404040", box.copy(), m),
             ViewerItem("motor", "vitamin", "motor 1104", 6.0, 4, "", "#888888", cyl)]
    meta, buf = pack(items)
    assert len(meta["geometries"]) == 2  # the two identical boxes share one geometry
    assert [o["geometry"] for o in meta["objects"]] == [0, 0, 1]
    for g, mesh in zip(meta["geometries"], (box, cyl)):
        q = np.frombuffer(buf, "<u2", g["n_vertices"] * 3, g["positions"]).reshape(-1, 3)
        v = np.asarray(g["min"]) + q * np.asarray(g["step"])
        assert np.abs(v - mesh.vertices).max() <= max(g["step"]) / 2 + 1e-6
        assert max(g["step"]) < 1e-3  # sub-micrometre steps for parts this size
        idx = np.frombuffer(buf, "<u2" if g["index_bytes"] == 2 else "<u4", g["n_triangles"] * 3, g["indices"])
        assert np.array_equal(idx.reshape(-1, 3), mesh.faces)
        rebuilt = trimesh.Trimesh(v, idx.reshape(-1, 3), process=False)
        assert rebuilt.volume == pytest.approx(mesh.volume, rel=1e-4)
    # column-major matrices, as three.js's Matrix4.fromArray reads them
    assert np.allclose(np.asarray(meta["objects"][1]["matrix"]).reshape(4, 4).T, m, atol=1e-6)
    assert meta["objects"][2] | {"matrix": None} == {"name": "motor", "kind": "vitamin", "material": "motor 1104", "mass_g": 6.0,
                                                     "qty": 4, "plate": "", "colour": "#888888", "note": "", "geometry": 1,
                                                     "matrix": None}
    with pytest.raises(ValueError, match="kind"):
        pack([ViewerItem("x", "screw", "steel", 1.0, 1, "", "#000000", box)])


@pytest.mark.cad
@pytest.mark.fe
def test_viewer_section_under_the_verdicts(tmp_path):
    from cogniframe.report.viewer import design_items

    spec = spec_mod.load(ROOT / "params" / "carbon.yaml")
    result = verdict.check(spec)
    d = result.design
    meshes = {p.name: _box(*(min(v, 60.0) for v in p.estimate.envelope)) for p in d.parts}
    plates = write_plates(pack_plates([PlateItem(p.name, p.material, p.qty, meshes[p.name]) for p in d.parts],
                                      spec.printer.bed, spec.printer.margin), tmp_path / "plates")
    items = design_items(d, meshes, {}, result.mass, plates)
    rods = [i for i in items if i.kind == "rod"]
    assert len(rods) == len(d.frame.rods)
    rod = rods[0]
    frame_rod = d.frame.rods[rod.name]
    length = float(np.linalg.norm(np.subtract(frame_rod.end, frame_rod.start)))
    tube = trimesh.Trimesh(rod.mesh.vertices, rod.mesh.faces, process=False)
    assert tube.is_watertight and tube.is_winding_consistent and tube.volume > 0  # closed, wound outwards
    tube.apply_transform(rod.matrix)
    assert tube.volume == pytest.approx(np.pi * (frame_rod.diameter / 2) ** 2 * length, rel=0.03)  # 16-sided tube
    html_path, md_path = report.write_report(result, tmp_path, plates=plates, viewer_items=items)
    text = html_path.read_text(encoding="utf-8")
    assert text.index('id="verdicts"') < text.index('id="viewer-section"') < text.index('<section id="mass"')
    assert '<li><a href="#viewer-section">3D view</a></li>' in text
    md = md_path.read_text(encoding="utf-8")
    assert "cf-viewer" not in md and md.index("3D view of the assembly is in report.html") < md.index("## Mass budget")
    knee = next(i for i in items if i.name == "knee_fl")
    assert knee.plate == "tpu_95a_1" and knee.qty == 4 and knee.mass_g == pytest.approx(
        next(m.mass_g_each for m in result.mass.items if m.name == "knee"))


def test_read_stl_matches_trimesh(tmp_path):
    from cogniframe.report.viewer import read_stl

    m = trimesh.creation.icosphere(subdivisions=2, radius=7.0)
    m.export(tmp_path / "s.stl")
    got = read_stl(tmp_path / "s.stl")
    ref = trimesh.load(tmp_path / "s.stl", force="mesh")
    assert len(got.vertices) == len(ref.vertices) == len(m.vertices) and len(got.faces) == len(m.faces)
    mine = trimesh.Trimesh(got.vertices, got.faces, process=False)
    assert mine.is_watertight and mine.volume == pytest.approx(ref.volume, rel=1e-6)
    # the corners merged as np.unique merges rows: the same vertices in the same order, the same faces
    corners = np.asarray(ref.vertices, np.float32)[np.asarray(ref.faces)].reshape(-1, 3)
    verts, inverse = np.unique(corners, axis=0, return_inverse=True)
    assert np.array_equal(got.vertices, verts.astype(float)) and np.array_equal(got.faces, inverse.reshape(-1, 3))

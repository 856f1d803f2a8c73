"""The Python API (cogniframe.load / Design / check / build / sweep; docs/api.md), against the CLI.

Real values: the carbon preset's check from the API is the `check --json` object of the CLI,
key for key; with_values changes the mass by what it should; a refused value's message is the
paragraph the CLI prints for the same file; a build writes the CLI's folder under its rules; the
3D view draws in Chromium; a sweep returns one row per design.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import tiers

from browser import CHROMIUM, FLAGS, browser_or_skip

import cogniframe as cf
from cogniframe.api import yamledit

ROOT = Path(__file__).resolve().parents[1]
CARBON = ROOT / "params" / "carbon.yaml"


@pytest.fixture(scope="module")
def carbon():
    return cf.load(CARBON)


@pytest.fixture(scope="module")
@tiers.needs('fe')
def carbon_check(carbon):
    return carbon.check()


# -- importing ------------------------------------------------------------------------------

@pytest.mark.process
def test_import_is_light_and_exports_the_api():
    code = ("import sys, cogniframe as cf; heavy = [m for m in ('pydantic', 'numpy', 'cadquery', 'yaml', 'pandas') if m in sys.modules];"
            "print(heavy, callable(cf.sweep), cf.ParamsError.__mro__[1].__name__, sorted(n for n in cf.__all__))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == ("[] True UserError ['BuildResult', 'CheckResult', 'Design', 'ParamsError', 'UserError', "
                           "'__version__', 'load', 'sweep']"), out


def test_sweep_is_the_package_and_the_call():
    import cogniframe.sweep.run  # noqa: F401  (the import system binds the subpackage to cogniframe.sweep)

    assert callable(cf.sweep)
    assert cf.sweep.run.RESULTS == "results.parquet"
    from cogniframe import sweep

    assert sweep is cf.sweep


# -- check ----------------------------------------------------------------------------------

@pytest.mark.fe
def test_check_equals_the_cli_json(carbon_check, run_cli):
    code, out, _ = run_cli("check", CARBON, "--json")
    cli = json.loads(out)
    assert carbon_check.to_dict() == cli
    assert carbon_check.verdict == cli["verdict"] == "PASS" and code == 0
    assert carbon_check.mass_g == cli["mass"]["total_g"]
    assert carbon_check.k_n_per_m == cli["drop"]["k_n_per_m"] == cli["stiffness"]["k_n_per_m"]
    assert carbon_check.max_safe_drop_cm == cli["drop"]["max_safe_height_cm"]
    assert carbon_check.hover_time_min == cli["flight"]["hover_time_min"]
    assert carbon_check.stiffness_model == "fe"
    design_drop = next(h for h in cli["peak_g"]["heights"] if h["height_cm"] == 100)
    assert carbon_check.peak_g == design_drop["peak_g"]
    assert 200 < carbon_check.mass_g < 250 and 1000 < carbon_check.k_n_per_m < 50_000


def test_to_dict_is_a_copy(carbon_check):
    d = carbon_check.to_dict()
    d["mass"]["total_g"] = 0
    assert carbon_check.to_dict()["mass"]["total_g"] == carbon_check.mass_g


@pytest.mark.fe
def test_with_values_changes_the_mass_and_not_the_original(carbon, carbon_check):
    heavier = carbon.with_values({"core.battery.mass": 70})
    assert carbon.get("core.battery.mass") == 58 and heavier.get("core.battery.mass") == 70
    r = heavier.check()
    assert r.mass_g == pytest.approx(carbon_check.mass_g + 12, abs=0.011)  # a 12 g heavier pack, nothing else
    assert r.verdict == "FAIL" and any("over the 250 g limit" in p for p in r.problems)
    # the example: thicker rods and walls (screened with the analytic joints: milliseconds)
    d = carbon.with_values({"rods.diameter": 4.0, "joints.wall": 1.6, "model.stiffness_model": "analytic",
                            "core.link": "tab"})  # the closed forms' link
    assert (d.get("rods.diameter"), d.get("joints.wall")) == (4.0, 1.6)
    fast = d.check()
    assert fast.stiffness_model == "analytic" and fast.mass_g > carbon_check.mass_g + 5  # 4 mm rods weigh more
    assert carbon.check().to_dict() == carbon_check.to_dict()  # the original is as it was


def test_with_values_edits_only_those_lines(carbon):
    d = carbon.with_values({"rods.diameter": 4.0, "joints.wall": 1.6})
    old, new = carbon.text.splitlines(), d.text.splitlines()
    assert len(old) == len(new)
    changed = [(a, b) for a, b in zip(old, new) if a != b]
    assert changed == [("  diameter: 3.0          # mm", "  diameter: 4.0          # mm"),
                       ("  wall: 1.2              # TPU around each rod socket, mm (>= 2 extrusion lines and >= 40 % of the rod)",
                        "  wall: 1.6              # TPU around each rod socket, mm (>= 2 extrusion lines and >= 40 % of the rod)")]
    assert carbon.text == CARBON.read_text(encoding="utf-8") and not carbon.modified and d.modified


# -- bad values: the CLI's paragraph ----------------------------------------------------------

@pytest.mark.parametrize("values, old, new, key", [
    ({"rods.diameter": 20}, "  diameter: 3.0 ", "  diameter: 20  ", "rods.diameter"),        # the schema's bound
    ({"joints.wall": 0.9}, "  wall: 1.2 ", "  wall: 0.9 ", "joints.wall"),                   # a cross-field rule
    ({"frame.width": 90}, "  width: 209.6 ", "  width: 90    ", "motors.prop_diameter"),     # the frame geometry
    ({"motors.model": "9999"}, 'model: "1104"', 'model: "9999"', "motors.model"),           # an unknown name
])
def test_params_error_is_the_cli_paragraph(values, old, new, key, tmp_path, monkeypatch, run_cli):
    (tmp_path / "params").mkdir()
    shutil.copy(CARBON, tmp_path / "params" / "carbon.yaml")
    monkeypatch.chdir(tmp_path)
    d = cf.load("params/carbon.yaml")
    with pytest.raises(cf.ParamsError) as err:
        d.with_values(values)
    assert isinstance(err.value, cf.UserError) and err.value.key == key
    # the same mistake made by hand in the file: the CLI's paragraph, word for word
    text = (tmp_path / "params" / "carbon.yaml").read_text(encoding="utf-8")
    assert text.count(old) == 1
    (tmp_path / "params" / "carbon.yaml").write_text(text.replace(old, new), encoding="utf-8")
    code, out, errtext = run_cli("check", "params/carbon.yaml")
    assert code == 2 and out == ""
    assert errtext == f"error: {err.value}\n"
    assert str(err.value).startswith(f"params/carbon.yaml: {key} (line ")


def test_unknown_key_names_the_file_and_suggests(carbon):
    with pytest.raises(cf.ParamsError) as err:
        carbon.with_values({"rods.diamter": 3.5})
    assert str(err.value).startswith(f"{CARBON}: rods.diamter (line ")
    assert "did you mean 'diameter'?" in str(err.value) and err.value.key == "rods.diamter"


def test_load_errors_are_params_errors(tmp_path):
    with pytest.raises(cf.ParamsError, match="no such params file"):
        cf.load(tmp_path / "missing.yaml")
    p = tmp_path / "x.yaml"
    p.write_text("rods:\n  diameter: 3\n  diameter: 4\n", encoding="utf-8")
    with pytest.raises(cf.ParamsError, match="written twice"):
        cf.load(p)


# -- the YAML edits ----------------------------------------------------------------------------

def test_yamledit_keeps_everything_but_the_value():
    text = ("# top comment\nname: x   # the name\n\nframe:\n  width: 210   # mm\n  struts: true\n"
            "motors:\n  model: \"1104\"  # quoted\n  kv:   # empty\ncomponents:\n  - {name: fc, mass: 6}  # a row\n"
            "core:\n  camera: null   # none\n  battery:\n    mass: 58\n\n# trailing comment\n")
    out = yamledit.set_values(text, {"frame.width": 230.5, "motors.model": "1404", "motors.kv": 3000,
                                     "components.0.mass": 7, "components.0.qty": 2, "core.camera.tilt_deg": 5,
                                     "core.battery.cells": 4, "frame.knee_inset": 10, "model.stiffness_model": "analytic"})
    assert out == ("# top comment\nname: x   # the name\n\nframe:\n  width: 230.5   # mm\n  struts: true\n  knee_inset: 10\n"
                   "motors:\n  model: \"1404\"  # quoted\n  kv: 3000   # empty\ncomponents:\n  - {name: fc, mass: 7, qty: 2}  # a row\n"
                   "core:\n  camera: {tilt_deg: 5}   # none\n  battery:\n    mass: 58\n    cells: 4\n\n"
                   "model:\n  stiffness_model: analytic\n\n# trailing comment\n")
    import yaml

    assert yaml.safe_load(out)["motors"]["model"] == "1404"  # still a string
    assert yamledit.render([120, 120.5, 1e-5]) == "[120, 120.5, 1.0e-05]" and yamledit.render(None) == "null"
    assert yamledit.render("1404") == "'1404'" and yamledit.render(True) == "true"
    with pytest.raises(KeyError):
        yamledit.set_value(text, "components.5.mass", 1)


# -- save -------------------------------------------------------------------------------------

def test_save_writes_the_file_with_its_comments(tmp_path, carbon):
    p = tmp_path / "carbon.yaml"
    shutil.copy(CARBON, p)
    d = cf.load(p).with_values({"core.battery.mass": 61})
    assert d.save() == p
    saved = p.read_text(encoding="utf-8")
    assert saved == CARBON.read_text(encoding="utf-8").replace("    mass: 58             # g", "    mass: 61             # g")
    assert cf.load(p).get("core.battery.mass") == 61
    other = tmp_path / "other.yaml"
    other.write_text("keep me\n", encoding="utf-8")
    with pytest.raises(cf.UserError, match="already exists"):
        d.save(other)
    assert other.read_text() == "keep me\n"
    assert d.save(tmp_path / "new.yaml").read_text(encoding="utf-8") == saved
    assert sorted(f.name for f in tmp_path.iterdir()) == ["carbon.yaml", "new.yaml", "other.yaml"]  # no temp file left


# -- build ------------------------------------------------------------------------------------

@pytest.mark.cad
@pytest.mark.slicer
@pytest.mark.fe
def test_build_writes_the_cli_folder_under_its_rules(tmp_path, carbon):
    d = carbon.with_values({"core.battery.mass": 60})  # an edit that is not on disk: built from the design's text
    out = tmp_path / "out" / "carbon-60"
    result = d.build(out, jobs=2)
    assert result.out_dir == out and result.verdict == "PASS" and not result.up_to_date
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["params_file"] == "carbon.yaml"
    assert manifest["params_sha256"] == hashlib.sha256(d.text.encode()).hexdigest()  # the edited text was built
    assert sorted(result.files) == sorted([out / f["path"] for f in manifest["files"]] + [out / "manifest.json"])
    assert result.report == out / "report.html" and result.report.is_file()
    assert result.plates and all(p.suffix == ".3mf" and p.is_file() for p in result.plates)
    check = json.loads((out / "check.json").read_text())
    assert result.check.mass_g == check["mass"]["total_g"] and check["verdict"] == result.verdict
    assert d.build(out, jobs=2).up_to_date  # the same design again: nothing rebuilt
    # a folder cogniframe did not make is never touched
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(cf.UserError, match="not a cogniframe output folder"):
        d.build(foreign)
    assert [f.name for f in foreign.iterdir()] == ["notes.txt"]


# -- the 3D view in Jupyter -------------------------------------------------------------------



@pytest.mark.browser
@pytest.mark.cad
def test_repr_html_draws_the_design_offline(carbon, tmp_path):
    fragment = carbon._repr_html_()
    assert fragment.count('class="cf-viewer"') == 1 and "three.js" in fragment
    assert "http://" not in fragment.replace("http://www.w3.org", "") and "https://" not in fragment
    again = carbon._repr_html_()
    assert again != fragment  # ids of its own: two views can sit in one notebook
    page = tmp_path / "notebook.html"
    page.write_text(f"<!doctype html><html><body>{fragment}<hr>{again}</body></html>", encoding="utf-8")
    browser_or_skip()
    import io

    import numpy as np
    from PIL import Image
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        try:
            tab = browser.new_page(viewport={"width": 1000, "height": 800})
            seen, errors = [], []
            tab.on("request", lambda r: seen.append(r.url))
            tab.on("pageerror", lambda e: errors.append(str(e)))
            tab.goto(page.as_uri())
            tab.wait_for_function("document.querySelectorAll('.cf-viewer[data-ready=\"1\"], .cf-viewer[data-error]').length == 2",
                                  timeout=60_000)
            assert not errors and not tab.query_selector(".cf-viewer[data-error]")
            assert {u.split(":", 1)[0] for u in seen} <= {"file", "blob"}, seen
            tab.evaluate("document.querySelectorAll('.cf-bar, .cf-info').forEach(e => e.style.visibility = 'hidden')")
            img = np.asarray(Image.open(io.BytesIO(tab.locator(".cf-viewer canvas").first.screenshot())).convert("RGB")).astype(int)
        finally:
            browser.close()
    bg = np.array([0xf4, 0xf6, 0xf8])
    drawn = (np.abs(img[2:-2, 2:-2] - bg).sum(axis=2) > 30).mean()
    red = ((img[..., 0] > 110) & (img[..., 1] < 80) & (img[..., 2] < 80)).sum()  # the TPU joints
    assert drawn > 0.04 and red > 1000, (drawn, red)


# -- sweep ------------------------------------------------------------------------------------

@pytest.mark.cluster
def test_sweep_from_a_dict_returns_a_dataframe(carbon):
    df = cf.sweep({"base": carbon, "samples": 3, "sampler": "lhs", "seed": 1,
                   "set": {"model.stiffness_model": "analytic", "core.link": "tab"}, "vary": {"rods.diameter": [2.4, 3.0]}},
                  workers=1)
    assert len(df) == 3 and set(df["verdict"]) <= {"PASS", "FAIL"}
    assert df["rods.diameter"].between(2.4, 3.0).all()
    assert (df["mass_g"] > 150).all() and df["rods.diameter"].is_unique
    # thicker rods weigh more: the rows are real checks
    ordered = df.sort_values("rods.diameter")
    assert ordered["mass_g"].is_monotonic_increasing
    assert df.attrs["summary"]["designs"] == 3 and df.attrs["out_dir"] is None


def test_build_file_refuses_bad_params_before_it_writes_anything(tmp_path):
    """`cogniframe build`'s entry in the API: a bad params file is a ParamsError naming the key,
    and no output folder appears."""
    from cogniframe import api

    bad = tmp_path / "bad.yaml"
    bad.write_text("rods:\n  diametr: 3\n")
    with pytest.raises(api.ParamsError) as e:
        api.build_file(bad, tmp_path / "out", server=False)
    assert "rods.diametr (line 2)" in str(e.value) and "diameter" in str(e.value)
    assert not (tmp_path / "out").exists()

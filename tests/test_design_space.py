"""The schema's bounds are a contract: any params file that validates is checked and built, or
refused with a key (exit 2); never a crash (exit 3). Designs come from tests/design_space.py: every
bounded key of the schema, boxes square or not.

Example counts: the `ci` profile runs a few (each new joint geometry is one solid FE, seconds);
`HYPOTHESIS_PROFILE=nightly` runs many more (conftest.py)."""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import design_space
import tiers
from conftest import copy_cache

NIGHTLY = os.environ.get("HYPOTHESIS_PROFILE") == "nightly"
ROOT = Path(__file__).resolve().parents[1]
KEYS = design_space.bounded_keys()


@st.composite
def edited_designs(draw):
    """A preset with its box and up to three other bounded keys changed, anywhere in their bounds."""
    doc = design_space.preset(draw(st.sampled_from(design_space.PRESETS)))
    side = min(doc["frame"]["width"], doc["frame"]["depth"])
    lo, hi = design_space.BOX["frame.width"]
    width = draw(st.floats(lo, hi).map(lambda v: round(v, 1)))
    square = draw(st.booleans())
    depth = width if square else draw(st.floats(*design_space.BOX["frame.depth"]).map(lambda v: round(v, 1)))
    design_space.put(doc, "frame.width", width)
    design_space.put(doc, "frame.depth", depth)
    design_space.put(doc, "frame.height", draw(st.floats(*design_space.BOX["frame.height"]).map(lambda v: round(v, 1))))
    design_space.follow_the_box(doc, side)
    design_space.put(doc, "frame.struts", draw(st.booleans()))
    for key, lo, hi, kind in draw(st.lists(st.sampled_from(KEYS), max_size=3, unique=True)):
        value = draw(st.integers(int(lo), int(hi)) if kind == "integer" else st.floats(lo, hi).map(lambda v: round(v, 3)))
        design_space.put(doc, key, value)
    return doc


@st.composite
def designs_anywhere(draw):
    """Every bounded key drawn at once (most of these must be refused, each with its key)."""
    doc = design_space.preset(draw(st.sampled_from(design_space.PRESETS)))
    for key, lo, hi, kind in KEYS:
        value = draw(st.integers(int(lo), int(hi)) if kind == "integer" else st.floats(lo, hi).map(lambda v: round(v, 3)))
        design_space.put(doc, key, value)
    return doc


def _check(doc: dict, folder: Path) -> tuple[int, str, str]:
    from cogniframe.cli import main

    folder.mkdir(parents=True, exist_ok=True)
    params = design_space.write(doc, folder / "design.yaml")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", str(params), "--json"])
    return code, out.getvalue(), err.getvalue()


def _assert_contract(code: int, out: str, err: str, doc: dict) -> None:
    design = yaml.safe_dump(doc, sort_keys=False)
    assert code in (0, 1, 2), f"exit {code}: {err[-1500:]}\n{design}"
    if code == 2:
        # one paragraph naming the file and a key
        assert "design.yaml" in err and "Traceback" not in err and ("." in err), err
        return
    result = json.loads(out)
    assert result["verdict"] in ("PASS", "FAIL")
    assert math.isfinite(result["mass"]["total_g"]) and result["mass"]["total_g"] > 0
    stiffness = result["stiffness"]
    assert math.isfinite(stiffness["k_n_per_m"]) and stiffness["k_n_per_m"] > 0, design
    assert stiffness["modes_hz"] and all(math.isfinite(f) and f > 0 for f in stiffness["modes_hz"]), design


_SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@settings(max_examples=400 if NIGHTLY else 6, **_SETTINGS)
@given(doc=edited_designs())
@pytest.mark.fe
def test_check_of_an_edited_preset_exits_0_1_or_2_never_3(doc, tmp_path_factory):
    """The path `check` takes by default: the joints' solid FE (each new geometry solved once,
    then from the cache)."""
    code, out, err = _check(doc, tmp_path_factory.mktemp("design"))
    _assert_contract(code, out, err, doc)


@settings(max_examples=300 if NIGHTLY else 10, **_SETTINGS)
@given(doc=designs_anywhere())
def test_check_of_a_design_drawn_anywhere_in_the_schema_exits_0_1_or_2_never_3(doc, tmp_path_factory):
    code, out, err = _check(doc, tmp_path_factory.mktemp("design"))
    _assert_contract(code, out, err, doc)


# -- the known failures, each a regression test ----------------------------------------------

def _preset_with(name: str, **changes) -> dict:
    doc = design_space.preset(name)
    for key, value in changes.items():
        design_space.put(doc, key.replace("__", "."), value)
    return doc


@pytest.mark.parametrize("preset,changes", [
    ("carbon", {"frame__width": 212}),                 # any box that is not square
    ("carbon", {"frame__width": 240, "frame__depth": 180}),
    ("bamboo", {"frame__width": 200}),
    ("carbon", {"frame__knee_inset": 0}),              # straight sides
    ("bamboo", {"rods__diameter": 2.3, "frame__height": 91.5}),
    ("carbon", {"rods__diameter": 2.3, "frame__height": 91.5}),
])
@pytest.mark.fe
def test_designs_that_crashed_check_now_pass_fail_or_name_a_key(preset, changes, tmp_path):
    doc = _preset_with(preset, **changes)
    code, out, err = _check(doc, tmp_path)
    _assert_contract(code, out, err, doc)


# -- random CAD builds -----------------------------------------------------------------------

def _build(params: Path, out: Path, env: dict, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cogniframe", "build", str(params), "-o", str(out), *extra],
                          capture_output=True, text=True, timeout=900, env=env, cwd=ROOT)


@pytest.mark.parametrize("seed", range(12 if NIGHTLY else 2))
@pytest.mark.fe
@pytest.mark.process
def test_a_random_design_builds_watertight_parts_and_a_clash_report(seed, tmp_path):
    """The FE's surrogate (model.stiffness_model: surrogate: the presets' pegged link has no closed
    form) keeps this mostly to the CAD: the FE of the same joint shapes is what the check tests
    above run."""
    import trimesh

    rnd = random.Random(1000 + seed)
    env = {**os.environ, "COGNIFRAME_CACHE": str(tmp_path / "cache"), "COGNIFRAME_CAD_SERVER": "0"}
    for _ in range(50):  # the first design the validation accepts
        doc = design_space.random_design(rnd, "edit")
        doc["model"]["stiffness_model"] = "surrogate"
        doc["name"] = "random"
        params = design_space.write(doc, tmp_path / "random.yaml")
        code, _, _ = _check(doc, tmp_path / "check")
        if code in (0, 1):
            break
    else:
        pytest.fail("no accepted design in 50 draws")
    r = _build(params, tmp_path / "out", env)
    assert r.returncode in (0, 1), r.stderr[-3000:] + yaml.safe_dump(doc)
    stls = sorted((tmp_path / "out" / "stl").rglob("*.stl"))
    assert stls
    for stl in stls:
        mesh = trimesh.load(stl, force="mesh")
        assert mesh.is_watertight and mesh.volume > 0, stl
    clash = json.loads((tmp_path / "out" / "clash.json").read_text())
    assert "clashes" in clash


# -- the maker's loop ------------------------------------------------------------------------

def _files(out: Path) -> dict:
    return {f["path"]: f["sha256"] for f in json.loads((out / "manifest.json").read_text())["files"]}


HEIGHTS = (112.0, 117.0, 118.0, 125.0, 131.0) if NIGHTLY else (112.0, 117.0)


@pytest.fixture(scope="module")
@tiers.needs("process")
def cold_builds(tmp_path_factory):
    """{height: the folder of a cold build (an empty cache, no server) of the bamboo preset at that
    frame.height}: the bytes both edit-rebuild loops below must give, built once for the two."""
    root = tmp_path_factory.mktemp("cold")
    env = {**os.environ, "COGNIFRAME_CAD_SERVER": "0"}
    out = {}
    for h in HEIGHTS:
        folder = root / f"cold-{h}"
        folder.mkdir()
        params = design_space.write(_preset_with("bamboo", frame__height=h), folder / "bamboo.yaml")
        r = _build(params, folder / "out", {**env, "COGNIFRAME_CACHE": str(folder / "cache")})
        assert r.returncode in (0, 1), f"cold build at height {h}: {r.stderr[-3000:]}"
        out[h] = (folder, r.returncode)
    return out


@pytest.mark.parametrize("server", [True, False], ids=["server", "no-server"])
@pytest.mark.process
def test_the_edit_rebuild_loop_builds_every_time_and_matches_cold_builds(server, cold_builds, tmp_path):
    """A maker edits frame.height and rebuilds into the same folder, again and again, the CAD
    server warm after the first: every build ends with 0 or 1, and each output is the bytes of a
    cold build (an empty cache, no server) of the same params."""
    cache = tmp_path / "cache"
    env = {**os.environ, "COGNIFRAME_CACHE": str(cache), "COGNIFRAME_CAD_SERVER": "1" if server else "0"}
    # PrusaSlicer's time estimate moves by seconds between runs of one plate (a part's print time
    # can then round to the next minute): the loop starts with the cold builds' measurements of
    # their plates, keyed by the plates' bytes (a plate that differs from the cold build's is
    # sliced anew, and the manifests below differ anyway), and cold for everything else
    for folder, _ in cold_builds.values():
        if (folder / "cache" / "slice").is_dir():
            copy_cache(folder / "cache" / "slice", cache / "slice")
    base = design_space.preset("bamboo")
    try:
        first = _build(design_space.write(base, tmp_path / "bamboo.yaml"), tmp_path / "out", env)
        assert first.returncode in (0, 1), first.stderr[-3000:]
        for h in HEIGHTS:
            params = design_space.write(_preset_with("bamboo", frame__height=h), tmp_path / "bamboo.yaml")
            r = _build(params, tmp_path / "out", env)
            assert r.returncode in (0, 1), f"height {h}: {r.stderr[-3000:]}"
            cold_dir, cold_code = cold_builds[h]
            assert cold_code == r.returncode, f"height {h}"
            assert _files(tmp_path / "out") == _files(cold_dir / "out"), f"height {h}"
    finally:
        if server:
            subprocess.run([sys.executable, "-m", "cogniframe", "server", "stop"], env=env, cwd=ROOT,
                           capture_output=True, timeout=60)

"""The real build graph (steps.py): which steps a params change reruns, and that an incremental
build gives the same bytes as a cold one.

One cold build of the carbon preset warms a cache shared by this module. Each single-value change
is then built twice: incrementally on the shared cache (the steps that ran are asserted: exactly
the ones that read the changed value), and cold (no cache at all); the two manifests must list
the same files with the same sha256. PrusaSlicer only runs for the changes that touch what it
reads (and is skipped where it is not installed); elsewhere it is switched off in both builds.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

import tiers
from conftest import copy_cache

from cogniframe import spec as spec_mod
from cogniframe.pipeline import run_build
from cogniframe.export import slicer as slicer_mod

ROOT = Path(__file__).resolve().parents[1]
HAVE_SLICER = slicer_mod.find_slicer() is not None
TPU, ABS = "tpu_95a", "abs"
TPU_PARTS = ("corner_top", "corner_bottom", "knee", "core_link", "core_link_mirrored", "motor_mount")
ABS_PARTS = ("core_plate", "battery_holder", "sensor_mount", "front_camera_mount", "computer_mount")


def _params(folder: Path, change: tuple[str, object] | None = None) -> Path:
    data = yaml.safe_load((ROOT / "params" / "carbon.yaml").read_text())
    if change is not None:
        *path, last = change[0].split(".")
        node = data
        for k in path:
            node = node[k]
        node[last] = change[1]
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "carbon.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


def _build(params: Path, out: Path, slicer: bool, use_cache: bool = True, console=None, server: bool = False):
    with pytest.MonkeyPatch.context() as mp:
        if not slicer:
            mp.setattr(slicer_mod, "find_slicer", lambda: None)
        return run_build(spec_mod.load(params), params, out, jobs=2, use_cache=use_cache, console=console, server=server)


def _ran(result) -> set[str]:
    return {task for task, status in result.steps if status == "ran"}


def _files(out: Path) -> list:
    return json.loads((out / "manifest.json").read_text())["files"]


@pytest.fixture(scope="session")
@tiers.needs("cad", "fe", "slicer")
def warm_root(tmp_path_factory):
    """The cold build of the carbon preset whose cache the changes below build on: made once a run
    (the first worker to ask builds it, the others wait), its step records kept beside it."""
    from conftest import once, shared_dir

    root = shared_dir(tmp_path_factory) / "steps-warm"
    with once(root.parent / ".steps-warm.lock"):
        if not (root / "first.json").is_file():
            with pytest.MonkeyPatch.context() as mp:
                mp.setenv("COGNIFRAME_CACHE", str(root / "cache"))
                first = _build(_params(root / "base"), root / "out-base", slicer=True)
            (root / "first.json").write_text(json.dumps({"steps": first.steps}))
    return root


@pytest.fixture
def warm(warm_root, monkeypatch):
    """(root, params, the cold build's record); the test builds on the shared warm cache. The
    changes' builds may run beside each other on the run's workers: each writes only its own
    entries (atomically, keyed by content), so a test that edits or counts the cache's entries
    copies it first (`own_cache`)."""
    monkeypatch.setenv("COGNIFRAME_CACHE", str(warm_root / "cache"))
    steps = tuple(tuple(s) for s in json.loads((warm_root / "first.json").read_text())["steps"])
    return warm_root, warm_root / "base" / "carbon.yaml", SimpleNamespace(steps=steps, out_dir=warm_root / "out-base")


def own_cache(root: Path, tmp_path: Path, monkeypatch) -> Path:
    """A copy of the warm cache for this test alone."""
    cache = tmp_path / "cache"
    copy_cache(root / "cache", cache)
    monkeypatch.setenv("COGNIFRAME_CACHE", str(cache))
    return cache


def test_cold_build_runs_every_step_once(warm):
    _, _, first = warm
    names = [t for t, _ in first.steps]
    assert len(names) == len(set(names))
    assert {f"part:{TPU}/{p}" for p in TPU_PARTS} | {f"part:{ABS}/{p}" for p in ABS_PARTS} <= _ran(first)
    assert {"assembly", "plots", "figures", "renders", f"plates:{TPU}", f"previews:{ABS}", "render:knee"} <= _ran(first)
    assert not any(s == "cached" for _, s in first.steps)
    assert (f"slice:{TPU}" in _ran(first)) == HAVE_SLICER


@pytest.mark.cad
@pytest.mark.slicer
def test_unchanged_build_reruns_nothing_and_gives_the_same_bytes(warm, tmp_path):
    import io

    from rich.console import Console

    root, params, first = warm
    log = io.StringIO()
    again = _build(params, tmp_path / "again", slicer=True, console=Console(file=log, width=100))
    assert _ran(again) == set()
    assert {t for t, s in again.steps if s == "cached"} == _ran(first)
    assert _files(tmp_path / "again") == _files(first.out_dir)
    # not a terminal: one plain line per step, cached ones marked, then a count
    lines = log.getvalue().splitlines()
    n = len(again.steps)
    assert sum(line.startswith("[") for line in lines) == n
    assert any(line.endswith("cached") and "part:tpu_95a/knee" in line for line in lines)
    assert f"{n} steps: {n - len(_ran(first))} ran, {len(_ran(first))} cached" in lines
    assert "\x1b[" not in log.getvalue()  # no colours or cursor moves in a log file


@pytest.mark.cad
@pytest.mark.slicer
def test_a_damaged_cache_entry_is_rebuilt_in_a_real_build(warm, tmp_path, monkeypatch):
    """A truncated cached render and a cached part STL with edited bytes: both rebuilt, same output."""
    root, params, first = warm
    cache = own_cache(root, tmp_path, monkeypatch)
    (render,) = cache.glob("steps/render/*/files/renders/parts/knee.png")
    render.write_bytes(render.read_bytes()[:500])
    (stl,) = cache.glob("steps/part/*/files/stl/tpu_95a/core_link.stl")
    data = bytearray(stl.read_bytes())
    data[-10] ^= 0xFF
    stl.write_bytes(bytes(data))
    again = _build(params, tmp_path / "again", slicer=True)
    assert _ran(again) == {"render:knee", f"part:{TPU}/core_link"}  # its STL is the same again: nothing downstream
    assert _files(tmp_path / "again") == _files(first.out_dir)


MASS = {"plots", "figures"}  # what a change of the mass budget or the drop model reruns
VIEW = {"viewer"}  # the report's 3D view: it shows each part's and rod's grams and material
FLIGHT = {"flight"}  # the flight files: the mass properties, the modes, the rotors (not the drop model)


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="the CAD server is Linux-only")
@pytest.mark.cad
@pytest.mark.fe
@pytest.mark.process
@pytest.mark.slicer
def test_builds_through_the_cad_server_give_the_same_bytes(warm, tmp_path, monkeypatch, capsys):
    """A cold `cogniframe build` whose parts, joint FEs, clash check and assembly run in the CAD
    server's workers (runtime/cad_server.py) equals the module's cold build with a process pool of
    its own; the server is the one the CLI started before validating the params (`prestart`).
    A one-part change then reuses the server and equals a cold build of the changed params."""
    import io

    from rich.console import Console

    from cogniframe.cli import main
    from cogniframe.runtime import cad_server
    from cogniframe.stack import versions as stack_versions

    root, params, first = warm
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "cache"))
    # PrusaSlicer's time estimate moves by seconds between runs of one plate (a part's print time can
    # then round to the next minute in bom.csv): the served build gets the first build's measurements
    # of the plates, keyed by their bytes, and starts cold for the rest
    if (root / "cache" / "slice").is_dir():
        copy_cache(root / "cache" / "slice", tmp_path / "cache" / "slice")
    monkeypatch.setenv(cad_server.ENV, "1")
    early = []
    real = cad_server.prestart
    monkeypatch.setattr(cad_server, "prestart", lambda *a, **k: early.append(real(*a, **k)) or early[-1])
    try:
        assert main(["build", str(params), "-o", str(tmp_path / "served"), "--jobs", "2"]) == 0
        pid = cad_server.running(stack_versions())
        assert pid is not None and f"started a CAD server (pid {pid})" in capsys.readouterr().err
        assert len(early) == 1 and early[0].adopted and early[0].proc.pid == pid
        # its joint FEs were solved there (4, and the mirrored core link derived): a cache of its own
        assert len(list((tmp_path / "cache" / "joint").glob("*.json"))) == 5
        assert _files(tmp_path / "served") == _files(first.out_dir)
        changed = _params(tmp_path / "params", ("motors.bolt_spacing", 9.7))
        again = _build(changed, tmp_path / "served", slicer=False, server=True, console=Console(file=io.StringIO()))
        assert _ran(again) == (_part_change("motor_mount") - MASS) | {"figures", "plots"}
        assert cad_server.running(stack_versions()) == pid  # the same server, warm
    finally:
        cad_server.stop(stack_versions())
    _build(changed, tmp_path / "cold", slicer=False, use_cache=False)
    assert _files(tmp_path / "served") == _files(tmp_path / "cold")


def _part_change(*parts: str) -> set[str]:
    """Steps that rerun when exactly these parts' geometry changes (their mass changes too)."""
    out = set(MASS) | FLIGHT | {"assembly", "glb", "renders", "step_views", "viewer", "clash"}  # clash: keyed like the assembly
    for p in parts:
        m = TPU if p in TPU_PARTS else ABS
        out |= {f"part:{m}/{p}", f"render:{p}", f"plates:{m}", f"previews:{m}"}
    return out


CHANGES = [
    # (key, new value, slice?, steps that must rerun (slice:* only listed when sliced))
    ("core.battery.mass", 61, False, MASS | FLIGHT),
    ("requirements.design_drop_height_cm", 80, False, set()),  # the verdict and report only
    ("rods.kerf", 1.5, False, set()),  # the stock plan only
    ("model.damping_ratio", 0.6, False, MASS),
    ("rods.material", "bamboo", False, MASS | VIEW | FLIGHT),  # same diameter: no part changes
    # the motor's holes move on their circle: the mount's shape changes, its volume (same holes) and so
    # the mass budget do not
    # (the CAD's mass properties move with the holes: the flight figures and plots rerun)
    ("motors.bolt_spacing", 9.5, False, (_part_change("motor_mount") - MASS) | {"figures", "plots"}),
    # the wall insets the frame's joints: the core links move out, and the plate's peg tubes with them
    ("joints.wall", 1.4, False, _part_change(*TPU_PARTS, "core_plate")),
    # level arms: the plate hangs at the new knee height and the arms stay level, so the motor mount
    # keeps its shape; a larger plate moves the links out along the same level diagonal, so the
    # knees and the motor mounts keep theirs
    ("frame.height", 130, False, _part_change(*(p for p in TPU_PARTS if p != "motor_mount"))),
    # (the pegged plate's spacer is a bar under the rear standoffs: the plate's size does not move it)
    ("core.plate_size", 44, False, _part_change("core_plate", "core_link", "core_link_mirrored", "corner_bottom",
                                                "front_camera_mount")),
    # the wider gaps move a part to another plate, which the 3D view lists
    ("printer.margin", 5, True, {f"plates:{TPU}", f"plates:{ABS}", f"previews:{TPU}", f"previews:{ABS}",
                                 f"slice:{TPU}", f"slice:{ABS}", "viewer"}),
    # print settings: no part changes; the plates carry them in the 3MF, the previews stay
    ("core.infill", 0.15, True, MASS | VIEW | FLIGHT | {f"plates:{ABS}", f"slice:{ABS}"}),
    ("printer.layer_height", 0.25, True, MASS | VIEW | FLIGHT | {f"plates:{TPU}", f"plates:{ABS}", f"slice:{TPU}", f"slice:{ABS}"}),
]


@pytest.mark.parametrize("key, value, sliced, expected", CHANGES, ids=[c[0] for c in CHANGES])
@pytest.mark.cad
@pytest.mark.fe
@pytest.mark.slicer
def test_a_change_reruns_exactly_its_dependents_and_matches_a_cold_build(warm, tmp_path, key, value, sliced, expected):
    root, _, _ = warm
    sliced = sliced and HAVE_SLICER
    if not HAVE_SLICER:
        expected = {s for s in expected if not s.startswith("slice:")}
    params = _params(tmp_path / "params", (key, value))
    incremental = _build(params, tmp_path / "incremental", slicer=sliced)
    assert _ran(incremental) == expected
    # PrusaSlicer's time estimate moves by seconds between runs of one plate (a part's print time
    # can then round to the next minute, in the report): the cold build gets the incremental
    # build's measurements of the plates, keyed by their bytes, and starts cold for the rest
    cold_cache = tmp_path / "cold-cache"
    if sliced and (root / "cache" / "slice").is_dir():
        copy_cache(root / "cache" / "slice", cold_cache / "slice")
    # the joints' solid FE is keyed by the joint's geometry and tested on its own (test_joint_fe,
    # test_cache): the cold build reads the solutions the warm cache holds (3-4 s of a 15 s build),
    # and reruns every step of the graph
    copy_cache(root / "cache" / "joint", cold_cache / "joint")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("COGNIFRAME_CACHE", str(cold_cache))
        cold = _build(params, tmp_path / "cold", slicer=sliced)
    assert not any(s == "cached" and not t.startswith("slice:") for t, s in cold.steps)
    assert _files(tmp_path / "incremental") == _files(tmp_path / "cold")
    shutil.rmtree(tmp_path / "cold")


@pytest.mark.process
def test_a_no_geometry_change_imports_no_cad_mesh_or_render_library(warm, tmp_path, monkeypatch):
    """The battery's mass moves no part: a fresh `cogniframe build` process on the warm cache reruns
    only plots, figures and the flight files, and never imports CadQuery, OCP, trimesh, pyvista or vtk."""
    import os
    import subprocess
    import sys

    root, _, _ = warm
    cache = own_cache(root, tmp_path, monkeypatch)
    params = _params(tmp_path / "params", ("core.battery.mass", 59))
    env = {**os.environ, "COGNIFRAME_CACHE": str(cache), "PYTHONPATH": str(ROOT)}
    solved = {kind: len(list((cache / kind).glob("*.json"))) for kind in ("cases", "peaks")}
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "cogniframe", "build", str(params), "-o",
                           str(tmp_path / "out")], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    imported = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines() if line.startswith("import time:")}
    assert not imported & {"cadquery", "OCP", "trimesh", "pyvista", "vtk", "rectpack"}
    # the load cases and peaks are solved once, for the mass with the CAD volumes (`estimate` no
    # longer solves them for the estimated mass too, only k and the joints, which the mass leaves alone)
    assert {kind: len(list((cache / kind).glob("*.json"))) - n for kind, n in solved.items()} == {"cases": 1, "peaks": 1}
    ran = {line.split("]", 1)[1].split()[0] for line in proc.stderr.splitlines()
           if line.startswith("[") and not line.endswith("cached")}
    assert ran == ({"estimate", "budget", "physics", "check", "plots", "figures", "flight", "bom", "report"}
                   | ({"slice:tpu_95a", "slice:abs"} if not HAVE_SLICER else set()))

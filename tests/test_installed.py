"""The package as pip installs it, not the checkout the other tests import.

A wheel is built from this tree and installed into a temporary folder, and `python -m cogniframe
build` runs from there in a fresh process. This catches what tests of the checkout cannot see: a
file the wheel leaves out (package data: the viewer's three.js, the presets, the schema), a path
that only a checkout has, or one only an install has (the viewer step once hashed its installed
folder's `__pycache__` and every `pip install .` build died with IsADirectoryError).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.process
def test_a_build_from_the_installed_wheel_writes_the_whole_package(tmp_path):
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "-q", "-w", str(wheels)],
                   check=True, capture_output=True, timeout=600)
    (wheel,) = wheels.glob("cogniframe-*.whl")
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True, capture_output=True, timeout=600)
    env = {**os.environ, "PYTHONPATH": str(site)}
    where = subprocess.run([sys.executable, "-c", "import cogniframe; print(cogniframe.__file__)"], cwd=tmp_path,
                           env=env, capture_output=True, text=True, check=True).stdout.strip()
    assert Path(where).is_relative_to(site), where  # the installed copy, not the checkout
    # the carbon preset with closed-form joints (and the tab link they model): the build's own steps, without
    # the joints' FE
    text = (ROOT / "params" / "carbon.yaml").read_text()
    params = tmp_path / "carbon.yaml"
    params.write_text(text.replace("stiffness_model: fe", "stiffness_model: analytic").replace("link: pegs", "link: tab"))
    assert "stiffness_model: analytic" in params.read_text()
    r = subprocess.run([sys.executable, "-m", "cogniframe", "build", str(params), "-o", str(tmp_path / "out")],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    out = tmp_path / "out"
    manifest = json.loads((out / "manifest.json").read_text())
    files = {f["path"] for f in manifest["files"]}
    assert {"report.html", "assembly.step", "assembly.glb", "check.json", "plates/tpu_95a_1.3mf"} <= files
    assert json.loads((out / "check.json").read_text())["verdict"] == "PASS"
    html = (out / "report.html").read_text()
    assert "OrbitControls" in html and len(html) > 700_000  # the viewer's three.js bundle came with the wheel

"""Same params -> the same bytes as the reference tree: `check --json` of the presets and the
example design, and every file a build of each preset writes, against the sha256s in
tests/data/golden_outputs.json (written by tools/golden_outputs.py from a tree known good). A
restructuring that moves one byte fails here, naming the file."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = json.loads((ROOT / "tests" / "data" / "golden_outputs.json").read_text())

_spec = importlib.util.spec_from_file_location("golden_outputs", ROOT / "tools" / "golden_outputs.py")
golden = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden)


@pytest.mark.parametrize("params", sorted(GOLDEN["check_json"]))
@pytest.mark.process
def test_check_json_is_byte_identical_to_the_reference(params):
    assert golden.check_sha256(ROOT, params) == GOLDEN["check_json"][params]


def test_the_exclusions_are_the_files_that_carry_slicer_estimates():
    assert set(GOLDEN["excluded"]) == set(golden.EXCLUDED) == {"bom.csv", "bom.md", "report.md", "report.html"}
    for files in GOLDEN["build"].values():
        assert not set(files) & set(GOLDEN["excluded"])
        assert {"check.json", "cutlist.csv", "mass.md", "assembly.step"} <= set(files)  # the build's own numbers


@pytest.mark.parametrize("params", sorted(GOLDEN["build"]))
@pytest.mark.process
def test_every_build_output_is_byte_identical_to_the_reference(params, preset_build):
    found = golden.manifest_sha256(preset_build(Path(params).stem))  # the run's build of the preset
    want = GOLDEN["build"][params]
    assert sorted(found) == sorted(want), "the build writes other files than the reference"
    moved = sorted(p for p in want if found[p] != want[p])
    assert not moved, f"bytes differ from the reference: {moved}"

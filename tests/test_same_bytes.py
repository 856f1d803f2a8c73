"""Same params, same bytes, in every file of a build, the report's slicer figures among them:
PrusaSlicer runs on one CPU with the classic perimeter generator (export/slicer.py), which makes
its G-code, hence its grams and print time, the same on every run of the same plate."""

from __future__ import annotations

import hashlib
from pathlib import Path

from cogniframe import spec as spec_mod

PARAMS = Path(__file__).resolve().parents[1] / "params"


def _files(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_two_builds_with_empty_caches_write_the_same_bytes(preset_build, tmp_path, monkeypatch):
    """The run's carbon build (shared with the other tests; its slicer numbers come from a fresh
    run unless a kept COGNIFRAME_TEST_CACHE holds that plate's) against a build with an empty
    cache: every part, joint FE, plate, slice, render and report made again. Every file is
    compared, report.html, report.md and the BOM (which carry the slicer's grams and times) and
    the manifest included."""
    from cogniframe.pipeline import run_build

    first = _files(preset_build("carbon"))
    monkeypatch.setenv("COGNIFRAME_CACHE", str(tmp_path / "empty-cache"))
    params = PARAMS / "carbon.yaml"
    run_build(spec_mod.load(params), params, tmp_path / "out", jobs=2)
    second = _files(tmp_path / "out")
    assert sorted(second) == sorted(first)
    assert {"report.html", "report.md", "bom.md", "bom.csv", "plates/tpu_95a_1.3mf"} <= set(first)
    assert [p for p in sorted(first) if first[p] != second[p]] == []
    report = (tmp_path / "out" / "report.md").read_text(encoding="utf-8")
    assert "PrusaSlicer" in report  # the slicer ran: its figures are among the bytes compared

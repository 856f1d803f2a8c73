"""`check` answered from the cache: same answer as computing it, no pydantic/numpy import on a
hit, and any change to the params gives a fresh answer (check_cache.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parents[1]

HEAVY = ("pydantic", "numpy", "yaml", "typer", "cogniframe.spec", "cogniframe.analysis.verdict")


def _check(params: Path, cache: Path, *extra: str) -> tuple[str, list[str], int]:
    """`python -m cogniframe check PARAMS ...` in a fresh process: (stdout, heavy modules it imported, exit code)."""
    env = {**os.environ, "COGNIFRAME_CACHE": str(cache), "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "cogniframe", "check", str(params), *extra],
                          capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
    imported = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines() if line.startswith("import time:")}
    return proc.stdout, [m for m in HEAVY if m in imported], proc.returncode


@pytest.mark.process
def test_repeated_check_is_answered_from_the_cache_without_heavy_imports(tmp_path):
    params = tmp_path / "carbon.yaml"
    params.write_text((ROOT / "params" / "carbon.yaml").read_text())
    first, heavy, code = _check(params, tmp_path / "cache", "--json")
    assert "pydantic" in heavy and "numpy" in heavy and code == 0
    again, heavy, code2 = _check(params, tmp_path / "cache", "--json")
    assert again == first and code2 == code == 0
    assert heavy == []  # answered before the CLI, the spec, pydantic or numpy were imported
    assert json.loads(again)["mass"]["total_g"] == json.loads(first)["mass"]["total_g"] > 200
    # the tables (not --json) are cached separately and come back identical too
    tables, _, _ = _check(params, tmp_path / "cache")
    tables2, heavy, _ = _check(params, tmp_path / "cache")
    assert tables2 == tables and "all-up weight" in tables and heavy == []


@pytest.mark.process
def test_a_changed_params_file_is_checked_again(tmp_path):
    params = tmp_path / "carbon.yaml"
    text = (ROOT / "params" / "carbon.yaml").read_text()
    params.write_text(text)
    first, _, _ = _check(params, tmp_path / "cache", "--json")
    params.write_text(text.replace("    mass: 58 ", "    mass: 68 "))
    second, heavy, _ = _check(params, tmp_path / "cache", "--json")
    assert "pydantic" in heavy  # computed, not read back
    assert json.loads(second)["mass"]["total_g"] - json.loads(first)["mass"]["total_g"] == __import__("pytest").approx(10.0)


def test_bad_params_are_never_answered_from_the_cache(run_cli, tmp_path):
    params = tmp_path / "carbon.yaml"
    text = (ROOT / "params" / "carbon.yaml").read_text()
    params.write_text(text.replace("  diameter: 3.0 ", "  diameter: -3 "))
    for _ in range(2):
        code, out, err = run_cli("check", params, "--json")
        assert code == 2 and "rods.diameter" in err and out == ""

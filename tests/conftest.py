"""Shared fixtures: the presets, and a runner for the CLI entry point (exit codes included)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cogniframe import spec as spec_mod

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / "params"
PRESETS = ("carbon", "bamboo")


@pytest.fixture(params=PRESETS)
def preset(request) -> spec_mod.Spec:
    return spec_mod.load(PARAMS / f"{request.param}.yaml")


@pytest.fixture
def carbon() -> spec_mod.Spec:
    return spec_mod.load(PARAMS / "carbon.yaml")


@pytest.fixture
def bamboo() -> spec_mod.Spec:
    return spec_mod.load(PARAMS / "bamboo.yaml")


@pytest.fixture
def run_cli(capsys, monkeypatch):
    """Run `cogniframe ARGS` in-process; returns (exit code, stdout, stderr)."""
    from cogniframe.cli import main

    def run(*args: str, cwd: Path | None = None):
        if cwd is not None:
            monkeypatch.chdir(cwd)
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    """Tests never read or write the user's ~/.cache/cogniframe."""
    import os

    os.environ["COGNIFRAME_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    # builds run by the tests use their own process pools; tests/test_cad_server.py starts and
    # stops CAD servers itself (a server per test cache would outlive the run by 10 minutes)
    os.environ["COGNIFRAME_CAD_SERVER"] = "0"
    yield


# Property-based tests (hypothesis): a short, reproducible profile by default (CI), a long one for a
# nightly run: `HYPOTHESIS_PROFILE=nightly python -m pytest tests/test_properties.py`.
from hypothesis import settings  # noqa: E402

settings.register_profile("ci", max_examples=15, deadline=None, derandomize=True, database=None)
settings.register_profile("nightly", max_examples=2000, deadline=None, database=None)
settings.load_profile(__import__("os").environ.get("HYPOTHESIS_PROFILE", "ci"))

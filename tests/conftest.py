"""Shared fixtures: the presets, a runner for the CLI entry point (exit codes included), the run's
shared cache and builds, and the tiers (tests/tiers.py: markers, the fast tier's guard)."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

import pytest

import tiers
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


def pytest_configure(config):
    for kind, what in tiers.NEEDS.items():
        config.addinivalue_line("markers", f"{kind}: {what} (heavy: left out of the fast tier)")
    config.addinivalue_line("markers", f"{tiers.HEAVY}: needs one of {', '.join(tiers.NEEDS)}; added automatically")


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups
def pytest_collection_modifyitems(config, items):
    tiers.mark_from_fixtures(items)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    """The guard watches a test from before its fixtures are made (a module fixture's work counts
    for the first test that asks for it) to after they are torn down (tests/tiers.py)."""
    if not tiers.item_needs(item) >= set(tiers.NEEDS):
        item.stash[_GUARD] = tiers.Guard(item)
    return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    try:
        return (yield)
    finally:
        guard = item.stash.get(_GUARD, None)
        if guard is not None:
            guard.stop()
            record = os.environ.get("COGNIFRAME_TIERS_RECORD")  # a survey of the suite: what each test needed, failing none
            if record and guard.found:
                with open(record, "a") as fh:
                    fh.write(json.dumps({"test": item.nodeid, "needs": sorted(guard.found)}) + "\n")
            elif guard.failures():
                pytest.fail("\n".join(guard.failures()), pytrace=False)


_GUARD = pytest.StashKey()


def shared_dir(tmp_path_factory) -> Path:
    """A folder every worker of this run sees (pytest-xdist's workers share their base's parent)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def copy_cache(src: Path, dst: Path) -> Path:
    """Copy a cache folder (or one kind of it) that other workers may be writing to: its entries
    only, never the temporary files a writer is about to rename (`cache.store_text`), which may be
    gone by the time they are copied. An entry, once there, is never removed or changed."""
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns(".*.tmp"), dirs_exist_ok=True)
    return dst


@contextlib.contextmanager
def once(path: Path):
    """Hold an exclusive lock on `path` (a file beside what it guards): one worker of the run makes a
    shared thing while the others wait, then they read it."""
    import fcntl

    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


@pytest.fixture(scope="session")
@tiers.needs("cad", "fe", "slicer")
def preset_build(tmp_path_factory):
    """`build(name)`: the folder of `cogniframe build params/<name>.yaml`, made once a run (the first
    worker that asks builds it, the others wait for it) and read by every test that needs a
    preset's whole build. Read it, never write into it: copy it to change it."""
    from cogniframe.pipeline import run_build

    shared = shared_dir(tmp_path_factory) / "preset-builds"

    def build(name: str) -> Path:
        out = shared / name
        with once(shared / f".{name}.lock"):
            if not (out / "manifest.json").is_file():
                params = PARAMS / f"{name}.yaml"
                run_build(spec_mod.load(params), params, out, jobs=2)
        return out

    return build


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory):
    """Tests never read or write the user's ~/.cache/cogniframe. The run's workers share one cache
    (its writes are atomic, its keys the content), so a joint's FE is solved once a run, not once a
    worker. COGNIFRAME_TEST_CACHE=DIR keeps it across runs: a second run of the suite reads the FE
    and CAD it made before (entries are keyed by their inputs and cogniframe's code, so a stale one
    is never read)."""
    keep = os.environ.get("COGNIFRAME_TEST_CACHE")
    os.environ["COGNIFRAME_CACHE"] = str(Path(keep).expanduser().resolve() if keep else shared_dir(tmp_path_factory) / "cache")
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

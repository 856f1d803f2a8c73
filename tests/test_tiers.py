"""The fast tier stays fast: a heavy test is marked, by hand, through its fixtures or by the guard
that catches it at work (tests/tiers.py). Each case runs a small suite of its own with pytester,
under this suite's conftest."""

from __future__ import annotations

from pathlib import Path

import pytest

import tiers

pytest_plugins = ["pytester"]
HERE = Path(__file__).resolve().parent


@pytest.fixture
def suite(pytester, monkeypatch):
    """A pytester folder with this suite's conftest and tiers module, its guard failing tests (not
    recording them, as a survey of this suite would: COGNIFRAME_TIERS_RECORD)."""
    monkeypatch.delenv("COGNIFRAME_TIERS_RECORD", raising=False)
    pytester.makeconftest((HERE / "conftest.py").read_text())
    pytester.makepyfile(tiers=(HERE / "tiers.py").read_text())
    (pytester.path / "params").mkdir()  # conftest's preset fixtures read ROOT/params lazily
    return pytester


HEAVY_FIXTURE = '''
import pytest
import tiers

@pytest.fixture(scope="module")
@tiers.needs("cad", "fe")
def built():
    return "a build"

@pytest.fixture
def report(built):  # uses the heavy fixture through another fixture
    return built + " report"

def test_uses_it(built):
    assert built == "a build"

def test_uses_it_through_another(report):
    assert report

def test_light():
    assert 1 + 1 == 2
'''


def test_a_test_using_a_heavy_fixture_is_marked_and_left_out_of_the_fast_tier(suite):
    suite.makepyfile(test_x=HEAVY_FIXTURE)
    fast = suite.runpytest_subprocess("-m", "not heavy", "-p", "no:cacheprovider")
    fast.assert_outcomes(passed=1, deselected=2)
    heavy = suite.runpytest_subprocess("-m", "cad and fe and heavy", "-p", "no:cacheprovider", "-v")
    heavy.assert_outcomes(passed=2, deselected=1)
    heavy.stdout.fnmatch_lines(["*test_uses_it PASSED*", "*test_uses_it_through_another PASSED*"])


def test_the_marks_a_fixture_declares_reach_the_items():
    """The same rule, on pytest's own objects: what `mark_from_fixtures` reads."""
    @tiers.needs("slicer")
    def f():
        pass

    assert getattr(f, "_cogniframe_needs") == ("slicer",)
    with pytest.raises(ValueError, match="unknown needs"):
        tiers.needs("gpu")


UNMARKED_FE = '''
from concurrent.futures import Future

from cogniframe import spec as spec_mod
from cogniframe.analysis import joints
from cogniframe.design import design


def test_solves_a_joint_fe_unmarked():
    spec = spec_mod.from_dict({"name": "t"})
    part = next(p for p in design(spec).parts if p.family == "joint")

    def submit(fn, spec, p, mesh_mm):  # a worker that answers at once instead of meshing
        done = Future()
        done.set_result((p.name, None, "a stub"))
        return done

    assert joints._solve(spec, [(part, "key")], 1.0, submit) == {part.name: "a stub"}
'''


def test_an_unmarked_test_that_solves_a_joint_fe_fails_naming_the_marker(suite):
    suite.makepyfile(test_y=UNMARKED_FE)
    r = suite.runpytest_subprocess("-p", "no:cacheprovider")
    r.assert_outcomes(passed=1, errors=1)
    r.stdout.fnmatch_lines(["*solved the FE of 1 new joint geometry: mark it @pytest.mark.fe*"])
    marked = suite.runpytest_subprocess("-p", "no:cacheprovider", "-m", "not heavy")
    marked.assert_outcomes(passed=1, errors=1)  # the fast tier runs it: the guard is what keeps it out
    (suite.path / "test_y.py").write_text("import pytest\npytestmark = pytest.mark.fe\n" + UNMARKED_FE)
    fixed = suite.runpytest_subprocess("-p", "no:cacheprovider")
    fixed.assert_outcomes(passed=1)
    assert suite.runpytest_subprocess("-p", "no:cacheprovider", "-m", "not heavy").ret == pytest.ExitCode.NO_TESTS_COLLECTED

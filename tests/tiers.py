"""The suite's two tiers: what a heavy test needs, as pytest markers, and the guard that keeps
the fast tier fast.

    python -m pytest -n auto                  # everything (what .ci/run runs)
    python -m pytest -n auto -m "not heavy"   # the fast tier: the loop to run after each edit

A test is heavy when it needs one of `NEEDS`; `heavy` is added to it automatically. It gets its
markers in three ways, so that a new heavy test cannot slip into the fast tier:
1. written on the test (`@pytest.mark.fe`) or its module (`pytestmark = pytest.mark.cad`);
2. from a fixture it uses, directly or through other fixtures: a fixture declares what it needs
   with `@needs("cad", "fe")` under its `@pytest.fixture` (`mark_from_fixtures`);
3. found while it runs (`Guard`): a test that solves a joint's FE, loads the CAD kernel, runs
   PrusaSlicer or Chromium, or starts a Dask worker without its marker fails, naming the marker.
"""

from __future__ import annotations

import shlex
import subprocess
import sys
import threading

import pytest

NEEDS = {
    "cad": "builds solids with the CAD kernel (CadQuery/OCP): a build, a part's solid, a STEP",
    "fe": "solves a joint's solid finite-element model (gmsh + scikit-fem): seconds a new geometry",
    "slicer": "runs PrusaSlicer",
    "browser": "drives Chromium through Playwright",
    "cluster": "starts a Dask cluster or its workers",
    "process": "runs cogniframe (or a server of it, or a notebook's kernel) in a fresh Python process: seconds of imports each",
    # the one need the guard cannot see: set by hand on a fixture or test that computes for many
    # seconds with nothing but numpy (a fit over every drop log, a Monte Carlo of drops)
    "long": "computes for many seconds in this process (fits over every drop log, Monte Carlo drops)",
}
# a joint's FE meshes the joint's CAD solid, made in the test's own process
IMPLIES = {"fe": ("cad",)}
HEAVY = "heavy"
_ATTR = "_cogniframe_needs"


def needs(*kinds: str):
    """Declare what a fixture needs; every test that uses it gets these markers (and `heavy`).
    Put it under `@pytest.fixture`."""
    unknown = set(kinds) - set(NEEDS)
    if unknown:
        raise ValueError(f"unknown needs {sorted(unknown)}; known: {sorted(NEEDS)}")

    def mark(fn):
        setattr(fn, _ATTR, tuple(kinds))
        return fn

    return mark


def fixture_needs(item) -> set[str]:
    """What the fixtures `item` uses (transitively: pytest's closure) declare they need."""
    found: set[str] = set()
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return found
    for name in info.names_closure:
        for fdef in info.name2fixturedefs.get(name, ()):
            found.update(getattr(fdef.func, _ATTR, ()))
    return found


def item_needs(item) -> set[str]:
    return {k for k in NEEDS if item.get_closest_marker(k) is not None}


def mark_from_fixtures(items) -> None:
    """Collection: add the markers a test's fixtures declare, and `heavy` to every heavy test. The
    tests of one module that share a heavy module-scoped fixture go to one pytest-xdist worker
    (`--dist loadgroup`), so that the fixture is made once a run, not once a worker."""
    for item in items:
        wanted = fixture_needs(item) | item_needs(item)
        wanted |= {implied for kind in wanted for implied in IMPLIES.get(kind, ())}
        for kind in sorted(wanted - item_needs(item)):
            item.add_marker(getattr(pytest.mark, kind))
        if item_needs(item):
            item.add_marker(HEAVY)
        if _shares_a_heavy_fixture(item) and item.get_closest_marker("xdist_group") is None:
            item.add_marker(pytest.mark.xdist_group(item.module.__name__))


def _shares_a_heavy_fixture(item) -> bool:
    info = getattr(item, "_fixtureinfo", None)
    return info is not None and any(getattr(fdef.func, _ATTR, ()) and fdef.scope in ("module", "class", "package")
                                    for name in info.names_closure for fdef in info.name2fixturedefs.get(name, ()))


# -- the guard -------------------------------------------------------------------------------

# modules whose first import in a test means it needs that marker
_MODULES = {"OCP": "cad", "playwright.sync_api": "browser", "distributed.deploy.local": "cluster"}


def _subprocess_needs(argv) -> str | None:
    """What a command line started from a test needs, if anything heavy."""
    args = [str(a) for a in (argv if isinstance(argv, (list, tuple)) else shlex.split(str(argv)))]
    text = " ".join(args)
    if not args:
        return None
    # export.slicer starts PrusaSlicer through a Python one-liner that pins it to one CPU and execs it
    if "prusa-slicer" in args[0] or (args[0] == sys.executable and any(a.endswith("prusa-slicer") for a in args[1:8])):
        return "slicer"
    if "chromium" in args[0]:
        return "browser"
    if "dask" in text or "distributed" in text:
        return "cluster"
    if "cogniframe" in text and (args[0] == sys.executable or args[0].endswith(("python", "python3", "cogniframe"))):
        return "process"
    return None


class Guard:
    """Watch one test that lacks some markers; `failures()` names each marker it turned out to need."""

    def __init__(self, item):
        self.item, self.have = item, item_needs(item)
        self.found: dict[str, str] = {}
        self.before = {m for m in _MODULES if m in sys.modules}
        self.elsewhere = {t.ident for t in threading.enumerate()} - {threading.main_thread().ident}
        self._patches = monkeypatch = pytest.MonkeyPatch()
        if "fe" not in self.have:
            self._guard_fe(monkeypatch)
        if "slicer" not in self.have:
            self._guard_slicer(monkeypatch)
        if "cad" not in self.have:
            self._guard_cad(monkeypatch)
        self._watch_subprocesses(monkeypatch)

    def stop(self) -> None:
        """Undo the patches; the modules imported since the start count too."""
        self._patches.undo()
        for module, kind in _MODULES.items():
            if module not in self.before and module in sys.modules:
                self._note(kind, f"imported {module}")

    def _note(self, kind: str, what: str) -> None:
        # a thread an earlier test left running (a studio session's, a build's warm-up) is not this
        # test's work: only the main thread and the threads started since this test began count
        if kind not in self.have and threading.get_ident() not in self.elsewhere:
            self.found.setdefault(kind, what)

    def _guard_fe(self, monkeypatch) -> None:
        # A joint's FE is read from the cache or solved: a test that reads one needs `fe` even when
        # an earlier test of the run solved it, since in another order (or in the fast tier, on an
        # empty cache) it would solve it itself. Every FE result goes through `cache.load_json("joint", ...)`.
        from cogniframe import cache
        from cogniframe.analysis import joints

        load_json = cache.load_json

        def guarded_load_json(kind, key):
            if kind == "joint":
                self._note("fe", "read a joint's solid FE (solved here on an empty cache)")
            return load_json(kind, key)

        solve = joints._solve

        def guarded_solve(spec, todo, *a, **k):  # the solves handed to worker processes
            if todo:
                self._note("fe", f"solved the FE of {len(todo)} new joint geometr{'y' if len(todo) == 1 else 'ies'}")
            return solve(spec, todo, *a, **k)

        monkeypatch.setattr(cache, "load_json", guarded_load_json)
        monkeypatch.setattr(joints, "_solve", guarded_solve)
        monkeypatch.setattr(joints, "fe_joint", self._noting("fe", "solved a joint's FE", joints.fe_joint))

    def _guard_cad(self, monkeypatch) -> None:
        # the build graph and the part files run their CAD on worker processes, where this
        # process never imports OCP: their entry points say it instead
        from cogniframe.export import part_files
        from cogniframe.pipeline import graph

        for module, name, what in ((graph, "run", "ran the build graph"),
                                   (part_files, "build_parts", "built the parts' solids")):
            monkeypatch.setattr(module, name, self._noting("cad", what, getattr(module, name)))
        # every solid CadQuery makes is a Shape: where the kernel is loaded (the test modules that
        # import it load it at collection), its use is what counts
        if "cadquery" in sys.modules:
            from cadquery.occ_impl.shapes import Shape

            monkeypatch.setattr(Shape, "__init__", self._noting("cad", "made a CadQuery solid", Shape.__init__))

    def _noting(self, kind: str, what: str, fn):
        def noted(*a, **k):
            self._note(kind, what)
            return fn(*a, **k)

        return noted

    def _guard_slicer(self, monkeypatch) -> None:
        from cogniframe.export import slicer

        find = slicer.find_slicer

        def guarded_find():
            exe = find()
            if exe:
                self._note("slicer", "looked for PrusaSlicer to run it")
            return exe

        monkeypatch.setattr(slicer, "find_slicer", guarded_find)

    def _watch_subprocesses(self, monkeypatch) -> None:
        popen_init = subprocess.Popen.__init__
        guard = self

        def watched(popen, args, *a, **k):
            kind = _subprocess_needs(args)
            if kind:
                guard._note(kind, f"started `{' '.join(map(str, args if isinstance(args, (list, tuple)) else [args]))[:120]}`")
            return popen_init(popen, args, *a, **k)

        monkeypatch.setattr(subprocess.Popen, "__init__", watched)

    def failures(self) -> list[str]:
        return [f"{self.item.nodeid} {what}: mark it @pytest.mark.{kind} ({NEEDS[kind]}), or declare the fixture "
                f"that does it with tiers.needs({kind!r}), so that the fast tier (-m 'not heavy') leaves it out"
                for kind, what in sorted(self.found.items())]

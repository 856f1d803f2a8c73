"""The build graph engine (graph.py) on small made-up steps, and the verified cache entries (no CAD).

What is checked: a step reruns exactly when what it reads changes (not when an upstream step
merely reran), an unchanged graph reruns nothing and gives the same bytes, a truncated or
edited cache entry is detected and rebuilt, waiting steps overlap with main-thread steps, and
an error stops the graph.
"""

from __future__ import annotations

import hashlib
import json
import threading
from pathlib import Path

import pytest

from cogniframe import cache
from cogniframe.pipeline import graph
from cogniframe.pipeline.graph import Made, Step


@pytest.fixture
def private_cache(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    monkeypatch.setenv("COGNIFRAME_CACHE", str(root))
    return root


def _sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _word_steps(ran: list):
    """word:{w} writes the word's text; letters counts the letters of all words; shout:{w} upper-cases one."""

    def word(ctx, w):
        ran.append(f"word:{w}")
        (ctx.out / f"{w}.txt").write_text(ctx.inputs["text"][w])
        return Made((f"{w}.txt",), {"letters": len(ctx.inputs["text"][w])})

    def letters(ctx):
        ran.append("letters")
        total = sum(v["letters"] for v in ctx.each("word:*").values())
        (ctx.out / "letters.txt").write_text(f"{total}\n")
        return Made(("letters.txt",), total)

    def shout(ctx, w):
        ran.append(f"shout:{w}")
        (ctx.out / f"{w}.upper.txt").write_text((ctx.out / f"{w}.txt").read_text().upper())
        return Made((f"{w}.upper.txt",))

    return (
        Step("word:{w}", (), word, key=lambda ctx, w: ctx.inputs["text"][w]),
        Step("letters", ("word:*",), letters, key=lambda ctx: [v["letters"] for v in ctx.each("word:*").values()]),
        Step("shout:{w}", ("word:{w}",), shout, key=lambda ctx, w: _sha(ctx.out / f"{w}.txt")),
        Step("summary", ("letters", "shout:*"), lambda ctx: Made((), f"{ctx['letters']} letters")),
    )


def _run(tmp_path: Path, name: str, text: dict, ran: list):
    out = tmp_path / name
    out.mkdir()
    ctx = graph.Context(out, {"text": text})
    records = graph.run(graph.expand(_word_steps(ran), [{"w": w} for w in text]), ctx)
    return out, {r.task: r.status for r in records}, ctx


def test_expand_binds_vars_and_resolves_patterns():
    tasks = {t.name: t for t in graph.expand(_word_steps([]), [{"w": "a"}, {"w": "b"}, {"w": "a"}])}
    assert list(tasks) == ["word:a", "word:b", "letters", "shout:a", "shout:b", "summary"]
    assert tasks["letters"].needs == ("word:a", "word:b")
    assert tasks["shout:b"].needs == ("word:b",)
    assert tasks["summary"].needs == ("letters", "shout:a", "shout:b")


def test_a_need_that_no_earlier_step_makes_is_an_error():
    with pytest.raises(ValueError, match="needs 'later'"):
        graph.expand((Step("first", ("later",), lambda ctx: Made()), Step("later", (), lambda ctx: Made())), [{}])


@pytest.mark.cad
def test_a_stop_ends_the_run_as_an_error_would_and_starts_nothing_new(tmp_path):
    """A caller that no longer wants the result (a studio closing) sets `stop` while a step runs:
    the caller's cancel is called once, the running step ends, the one after it never starts."""
    started, cancelled, stop, running = [], [], threading.Event(), threading.Event()

    def slow(ctx):
        started.append("slow")
        running.set()
        assert stop.wait(timeout=600)  # a bound on a hang only
        return Made()

    steps = (Step("slow", (), slow, where="wait"),
             Step("later", ("slow",), lambda ctx: started.append("later") or Made(), where="wait"))
    threading.Thread(target=lambda: running.wait(600) and stop.set(), daemon=True).start()
    with pytest.raises(graph.Stopped):
        graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}), on_error=lambda: cancelled.append(1), stop=stop)
    assert started == ["slow"] and cancelled == [1]


@pytest.mark.cad
def test_unchanged_inputs_rerun_nothing_and_give_the_same_bytes(tmp_path, private_cache):
    ran = []
    a, status, _ = _run(tmp_path, "a", {"x": "abc", "y": "hello"}, ran)
    assert set(ran) == {"word:x", "word:y", "letters", "shout:x", "shout:y"}
    assert set(status.values()) == {"ran", "always"} and status["summary"] == "always"
    ran.clear()
    b, status, ctx = _run(tmp_path, "b", {"x": "abc", "y": "hello"}, ran)
    assert ran == []
    assert {s for t, s in status.items() if t != "summary"} == {"cached"}
    assert ctx["summary"] == "8 letters"
    assert sorted(p.name for p in b.iterdir()) == sorted(p.name for p in a.iterdir())
    assert all(_sha(a / p.name) == _sha(b / p.name) for p in a.iterdir())


@pytest.mark.cad
def test_a_change_reruns_exactly_what_reads_it(tmp_path, private_cache):
    ran = []
    _run(tmp_path, "a", {"x": "abc", "y": "hello"}, ran)
    ran.clear()
    # same length: word:x and shout:x read the text and rerun; letters reads only the counts and does not
    out, _, ctx = _run(tmp_path, "b", {"x": "xyz", "y": "hello"}, ran)
    assert sorted(ran) == ["shout:x", "word:x"]
    assert (out / "x.upper.txt").read_text() == "XYZ" and (out / "letters.txt").read_text() == "8\n"
    ran.clear()
    _, _, ctx = _run(tmp_path, "c", {"x": "abcd", "y": "hello"}, ran)
    assert sorted(ran) == ["letters", "shout:x", "word:x"]
    assert ctx["summary"] == "9 letters"


@pytest.mark.parametrize("damage", ["truncate", "edit", "drop_meta", "bad_meta"])
@pytest.mark.cad
def test_a_damaged_cache_entry_is_rebuilt_not_used(tmp_path, private_cache, damage):
    ran = []
    a, _, _ = _run(tmp_path, "a", {"x": "abc" * 1000, "y": "hello"}, ran)
    (entry,) = [p.parent.parent for p in (private_cache / "steps" / "word").glob("*/files/x.txt")]
    if damage == "truncate":
        f = entry / "files" / "x.txt"
        f.write_bytes(f.read_bytes()[:100])
    elif damage == "edit":
        (entry / "files" / "x.txt").write_text("ABC" * 1000)  # same size, other bytes
    elif damage == "drop_meta":
        (entry / "meta.json").unlink()
    else:
        (entry / "meta.json").write_text('{"files": {"x.txt": ')  # truncated JSON
    ran.clear()
    b, status, _ = _run(tmp_path, "b", {"x": "abc" * 1000, "y": "hello"}, ran)
    assert ran == ["word:x"] and status["word:x"] == "ran" and status["word:y"] == "cached"
    assert _sha(b / "x.txt") == _sha(a / "x.txt")
    ran.clear()
    _run(tmp_path, "c", {"x": "abc" * 1000, "y": "hello"}, ran)  # stored again, whole
    assert ran == []


def test_put_files_is_whole_or_nothing(tmp_path, private_cache):
    src = tmp_path / "src"
    src.mkdir()
    (src / "a.bin").write_bytes(b"x" * 5000)
    cache.put_files("demo", "k1", src, ["a.bin", "missing.bin"], {"v": 1})  # a file vanished: nothing stored
    assert not (private_cache / "demo" / "k1").exists()
    assert [p.name for p in (private_cache / "demo").iterdir()] == []  # no temp folder left behind
    cache.put_files("demo", "k2", src, ["a.bin"], {"v": 2})
    meta = json.loads((private_cache / "demo" / "k2" / "meta.json").read_text())
    assert meta == {"files": {"a.bin": _sha(src / "a.bin")}, "value": {"v": 2}}
    dest = tmp_path / "dest"
    assert cache.get_files("demo", "k2", dest) == {"value": {"v": 2}} and _sha(dest / "a.bin") == _sha(src / "a.bin")


@pytest.mark.cad
def test_waiting_steps_overlap_with_main_thread_steps(tmp_path):
    """A 'wait' step (stand-in for PrusaSlicer) blocks until a later main-thread step has run:
    this finishes only if the two really run at the same time."""
    go = threading.Event()
    threads = {}

    def slicer(ctx):
        threads["slicer"] = threading.current_thread().name
        assert go.wait(timeout=20), "the main-thread step never ran while the waiting step was running"
        return Made()

    def render(ctx):
        threads["render"] = threading.current_thread().name
        go.set()
        return Made()

    steps = (Step("slice", (), slicer, where="wait"), Step("render", (), render))
    records = graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert [r.task for r in records] == ["render", "slice"]
    assert threads["render"] == threading.main_thread().name and threads["slicer"] != threads["render"]


@pytest.mark.cad
def test_an_error_stops_the_graph_and_is_raised(tmp_path):
    ran = []

    def bad(ctx):
        raise ValueError("boom")

    steps = (Step("bad", (), bad, where="wait"), Step("after", ("bad",), lambda ctx: ran.append("after") or Made()))
    with pytest.raises(ValueError, match="boom"):
        graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert ran == []


@pytest.mark.cad
def test_code_changes_are_part_of_the_key(tmp_path, private_cache, monkeypatch):
    ran = []
    steps = (Step("s", (), lambda ctx: ran.append(1) or Made(), key=lambda ctx: 1, code=("pipeline/graph.py",)),)
    for _ in range(2):
        graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert ran == [1]
    monkeypatch.setitem(cache._CODE, ("pipeline/graph.py",), "edited")  # as if graph.py had been edited
    graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert ran == [1, 1]


@pytest.mark.cad
def test_after_orders_without_being_an_input(tmp_path, private_cache):
    """`after` only orders: the step waits for it but its key does not read it."""
    order = []
    seen = {"slow": 0}

    def steps():
        return (Step("render", (), lambda ctx: order.append("render") or Made(), key=lambda ctx: "same", after=("plates",)),
                Step("plates", (), lambda ctx: order.append("plates") or Made(), key=lambda ctx: seen["slow"]))

    with pytest.raises(ValueError, match="needs 'plates'"):  # like needs: only earlier steps
        graph.expand(steps(), [{}])
    good = (Step("plates", (), lambda ctx: order.append("plates") or Made(), key=lambda ctx: seen["slow"]),
            Step("render", (), lambda ctx: order.append("render") or Made(), key=lambda ctx: "same", after=("plates",)))
    (plates, render) = graph.expand(good, [{}])
    assert render.after == ("plates",) and render.needs == ()
    graph.run([render, plates], graph.Context(tmp_path, {}))  # listed first, still runs second
    assert order == ["plates", "render"]
    seen["slow"] = 1  # plates reruns; render's key does not read it, so it stays cached
    records = graph.run([render, plates], graph.Context(tmp_path, {}))
    assert {r.task: r.status for r in records} == {"plates": "ran", "render": "cached"}


@pytest.mark.cad
def test_a_wait_step_starts_as_soon_as_its_needs_finish_even_during_a_main_step(tmp_path):
    """`slice` needs `plates` (a wait step); a long main step (a render) is running when `plates`
    finishes. `slice` must start then, not after the render: here the render only ends once
    `slice` has started, so the graph finishes only if that is so."""
    sliced = threading.Event()

    def render(ctx):
        assert sliced.wait(timeout=20), "slice waited for the main-thread step to end"
        return Made()

    def plates(ctx):
        return Made()

    def slice_(ctx):
        sliced.set()
        return Made()

    steps = (Step("render", (), render), Step("plates", (), plates, where="wait"),
             Step("slice", ("plates",), slice_, where="wait"))
    records = graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert [r.task for r in records][0] == "plates" and {r.task for r in records} == {"plates", "slice", "render"}


@pytest.mark.cad
def test_a_main_step_error_waits_for_running_threads_and_starts_nothing_new(tmp_path):
    started, release = [], threading.Event()

    def slow(ctx):
        started.append("slow")
        assert release.wait(timeout=20)
        return Made()

    def bad(ctx):
        release.set()
        raise ValueError("main failed")

    steps = (Step("slow", (), slow, where="wait"), Step("bad", (), bad),
             Step("later", ("slow",), lambda ctx: started.append("later") or Made(), where="wait"))
    with pytest.raises(ValueError, match="main failed"):
        graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}))
    assert started == ["slow"]


@pytest.mark.cad
def test_will_run_tells_before_the_build_which_keyed_tasks_the_cache_lacks(tmp_path, private_cache):
    """`graph.will_run` (the build's reason to start the CAD server early): a keyed task whose
    entry is stored will not run; a changed input, or no key at all, will."""
    steps = _word_steps([])
    tasks = {t.name: t for t in graph.expand(steps, [{"w": "x"}, {"w": "y"}])}
    ctx = graph.Context(tmp_path, {"text": {"x": "abc", "y": "hello"}})
    assert graph.will_run(tasks["word:x"], ctx) and graph.will_run(tasks["word:y"], ctx)
    _run(tmp_path, "a", {"x": "abc", "y": "hello"}, [])
    assert not graph.will_run(tasks["word:x"], ctx) and not graph.will_run(tasks["word:y"], ctx)
    changed = graph.Context(tmp_path, {"text": {"x": "abd", "y": "hello"}})
    assert graph.will_run(tasks["word:x"], changed) and not graph.will_run(tasks["word:y"], changed)
    assert graph.will_run(tasks["summary"], ctx)  # no key: always runs
    assert graph.will_run(tasks["word:y"], graph.Context(tmp_path, {"text": {"y": "hello"}}, use_cache=False))


def test_the_cad_pool_connects_once_in_the_background_and_the_first_job_waits_for_it(monkeypatch):
    """`CadPool.start_server` (called by the build before its own set-up) connects in a thread;
    a job submitted meanwhile waits for that connection instead of opening a second one, and a
    pool that had to start its server is marked cold."""
    from concurrent.futures import Future

    from cogniframe.runtime import cad_server
    from cogniframe.runtime.pools import CadPool

    calls, release = [], threading.Event()

    class Pool:
        def submit(self, fn, *args, priority=0):
            f = Future()
            f.set_result(fn(*args))
            return f

        def shutdown(self, wait=True, cancel_futures=False):
            calls.append("shutdown")

    def connect(workers, stack, fe, log=None, on_start=None, early=None):
        calls.append(threading.current_thread().name)
        assert early == "the CLI's early server"  # handed on to connect, which waits for it
        on_start()  # no server ran: this call starts one
        release.wait(5)
        return Pool()

    monkeypatch.setattr(cad_server, "connect", connect)
    cad = CadPool(2, fe=False, server=True, early="the CLI's early server")
    cad.start_server()
    result = []
    t = threading.Thread(target=lambda: result.append(cad.run(sum, [1, 2, 3])))
    t.start()
    t.join(0.3)
    assert t.is_alive() and result == []  # waiting for the connection under way
    release.set()
    t.join(5)
    assert result == [6]
    assert calls == ["cad-connect"] and cad.cold.is_set() and cad.served is False  # (a stand-in pool)
    cad.close()
    assert calls[-1] == "shutdown"
    with pytest.raises(RuntimeError, match="closed"):
        cad.submit(sum, [1])




@pytest.mark.cad
def test_the_first_error_by_time_is_raised_with_its_step_and_the_rest_is_cancelled(tmp_path):
    """A waiting step fails first; the main thread's step under way then fails because of it (as
    a render failed when the part it drew was missing). The build reports the first failure, names
    its step, calls `on_error` once (the caller cancels its queued CAD jobs), starts nothing new."""
    first_failed, cancelled, started = threading.Event(), [], []

    def part(ctx):
        raise RuntimeError("joint geometry produced 2 solids instead of 1")

    def render(ctx):
        assert first_failed.wait(20)
        raise AttributeError("a consequence, reported before: module 'pyvista' has no attribute 'Plotter'")

    def on_error():
        cancelled.append(1)
        first_failed.set()

    steps = (Step("part:knee", (), part, where="wait"), Step("render", (), render),
             Step("later", ("part:knee",), lambda ctx: started.append(1) or Made(), where="wait"))
    with pytest.raises(RuntimeError, match="2 solids") as info:
        graph.run(graph.expand(steps, [{}]), graph.Context(tmp_path, {}), on_error=on_error)
    assert info.value.__notes__ == ["first failed step: part:knee"]
    assert cancelled == [1] and started == []


@pytest.mark.cad
def test_a_main_thread_step_runs_holding_the_main_lock(tmp_path):
    lock = threading.Lock()
    held = []
    steps = (Step("main", (), lambda ctx: held.append(lock.locked()) or Made()),
             Step("wait", (), lambda ctx: held.append(("wait", lock.locked())) or Made(), where="wait"))
    graph.run(graph.expand(steps[:1], [{}]), graph.Context(tmp_path, {}), main_lock=lock)
    assert held == [True] and not lock.locked()

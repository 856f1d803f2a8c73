"""The build's idle-time imports (runtime/warm.py) and what a step may assume about them."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest


def _run(code: str) -> list[str]:
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout.split()


@pytest.mark.process
def test_the_warm_up_imports_only_while_the_main_thread_holds_no_step():
    """Each module is imported under the baton that the build's main-thread steps hold: while a
    step holds it, nothing is imported; released, the rest follows, in order."""
    out = _run("""
        import sys, time
        from cogniframe.runtime.warm import Warmup
        w = Warmup(("colorsys", "wave"))
        with w.baton:  # a main-thread step runs
            w.start()
            time.sleep(0.5)
            held = "colorsys" not in sys.modules and "wave" not in sys.modules
        w.wait()
        print(held, "colorsys" in sys.modules, "wave" in sys.modules)
    """)
    assert out == ["True", "True", "True"]


@pytest.mark.process
def test_a_step_that_waits_goes_before_the_next_import(tmp_path):
    """A main-thread step that becomes ready while a module is being imported takes the baton when
    that import ends, before the warm-up's next module (a plain lock let the warm-up, which takes
    it again at once, import them all first)."""
    (tmp_path / "cf_slow_a.py").write_text("import builtins\nbuiltins.GATE.wait()\n")
    (tmp_path / "cf_slow_b.py").write_text("")
    out = _run(f"""
        import builtins, sys, threading, time
        sys.path.insert(0, {str(tmp_path)!r})
        builtins.GATE = threading.Event()
        from cogniframe.runtime.warm import Warmup
        w = Warmup(("cf_slow_a", "cf_slow_b"))
        w.start()
        while "cf_slow_a" not in sys.modules:  # its import has begun (and waits at the gate)
            time.sleep(0.001)
        seen = []

        def step():
            with w.baton:
                seen.append("cf_slow_b" in sys.modules)

        t = threading.Thread(target=step)
        t.start()
        while w.baton._waiting == 0:  # the step waits for the baton
            time.sleep(0.001)
        builtins.GATE.set()
        t.join()
        w.wait()
        print(seen[0], "cf_slow_b" in sys.modules)
    """)
    assert out == ["False", "True"]


@pytest.mark.process
def test_a_stopped_warm_up_imports_nothing_more():
    out = _run("""
        import sys
        from cogniframe.runtime.warm import Warmup
        w = Warmup(("colorsys",))
        with w.baton:
            w.start()
            w.stop_soon()
        w.stop()
        w.start()  # after stop: nothing
        print("colorsys" in sys.modules)
    """)
    assert out == ["False"]


@pytest.mark.process
def test_a_part_plotter_made_while_another_thread_imports_pyvista_plotting_works():
    """The edit-rebuild crash: the main thread asked pyvista for `Plotter` while a thread was still
    importing `pyvista.plotting`, and pyvista, seeing the module in sys.modules but not its
    attribute, raised AttributeError. The renders import that module themselves, which waits for
    an import under way."""
    out = _run("""
        import sys, threading, time
        import pyvista  # the package itself is cheap; its plotting module is the slow part
        from cogniframe.report import renders
        renders.ensure_headless()
        t = threading.Thread(target=__import__, args=("pyvista.plotting",))
        t.start()
        t0 = time.monotonic()
        while "pyvista.plotting" not in sys.modules and time.monotonic() - t0 < 30:
            time.sleep(0.0005)
        mid = not hasattr(sys.modules["pyvista.plotting"], "Plotter")  # half imported right now
        p = renders.part_plotter()
        print(mid, type(p).__name__)
        p.close()
        t.join()
    """)
    assert out[1] == "Plotter"

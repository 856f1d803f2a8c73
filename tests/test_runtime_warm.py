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

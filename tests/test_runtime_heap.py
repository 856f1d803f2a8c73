"""The collector around a process's big imports (heap.py): off while they run, their objects frozen
after, so that no later full collection walks them again."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest


def _run(code: str) -> list[str]:
    """Run `code` in a fresh interpreter (a freeze is for the life of a process) and return its
    printed lines."""
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True)
    return out.stdout.split()


@pytest.mark.process
def test_a_block_that_imports_runs_without_the_collector_then_freezes_its_objects():
    on_inside, frozen, on_after, again, off_stays_off = _run("""
        import gc
        from cogniframe.runtime.heap import imports_frozen
        assert gc.isenabled() and gc.get_freeze_count() == 0
        with imports_frozen():
            print(gc.isenabled())
            import decimal, fractions  # not imported by cogniframe.runtime.heap
        print(gc.get_freeze_count())
        print(gc.isenabled())
        n = gc.get_freeze_count()
        with imports_frozen():  # nothing new imported: no freeze (no garbage frozen for good)
            import decimal
            junk = [[] for _ in range(1000)]
        print(gc.get_freeze_count() - n)
        gc.disable()
        with imports_frozen():
            import statistics
        print(gc.isenabled())
    """)
    assert on_inside == "False" and on_after == "True" and off_stays_off == "False"
    assert int(frozen) > 1000  # at least the interpreter's and the two modules' objects
    assert int(again) == 0


@pytest.mark.process
def test_the_cad_workers_start_with_cadquery_frozen():
    """The forkserver (and the CAD server) import CadQuery, trimesh and the part builders inside
    the block: the ~400 000 objects are frozen, the collector has next to nothing left to walk."""
    frozen, tracked = map(int, _run("""
        import gc
        import cogniframe.runtime.worker
        print(gc.get_freeze_count(), len(gc.get_objects()))
    """))
    assert frozen > 200_000
    assert tracked < 0.02 * frozen


@pytest.mark.process
def test_the_build_command_freezes_its_imports_before_it_reads_the_params(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nrods:\n  diameter: -3\n")
    frozen, code = _run(f"""
        import gc
        from cogniframe.cli import main
        code = main(["build", {str(bad)!r}, "-o", {str(tmp_path / 'out')!r}, "--no-server"])
        print(gc.get_freeze_count(), code)
    """)
    assert code == "2"
    assert int(frozen) > 50_000  # pydantic, numpy and the pipeline's modules
    assert not (tmp_path / "out").exists()


@pytest.mark.process
def test_the_warm_up_imports_are_frozen():
    names = ("colorsys",)
    frozen, imported = _run(f"""
        import gc, sys
        from cogniframe.runtime.warm import Warmup
        n = gc.get_freeze_count()
        w = Warmup({names!r} + ("no_such_module_cogniframe",))
        w.start()
        w.wait()
        print(gc.get_freeze_count() - n, all(m in sys.modules for m in {names!r}))
    """)
    assert int(frozen) > 0 and imported == "True"

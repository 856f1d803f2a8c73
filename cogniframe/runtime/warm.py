"""The build's idle-time imports: the main thread's libraries, imported while it has nothing to do.

A build that makes new parts waits seconds for the CAD workers while its main thread, which will
lay out plates and draw previews, plots and renders, is idle. `Warmup` imports those libraries
(trimesh, matplotlib, VTK through pyvista) in a thread during that wait.

The contract that keeps this safe: the warm-up imports one module at a time, each while holding
`baton`, and the build holds the same `baton` around every main-thread step (`graph.run`'s
`main_lock`). So the warm-up never imports while a main-thread step runs: a step never meets a
library half imported by the warm-up (CPython's per-module locks do not cover a package that
resolves attributes lazily, such as pyvista's `Plotter`, nor imports that are circular across
threads), and the most a step waits for is the one module being imported when it became ready.
The libraries it imports are the main thread's only: the build's waiting threads (CAD jobs, the
slicer, the physics) do not use them.
"""

from __future__ import annotations

import importlib
import threading

# In the order the main thread needs them: the plates' first (they head the path to the slicer),
# then the previews', plots' and figures' (matplotlib), then the renders' (pyvista >= 0.45 loads
# `pyvista.plotting`, most of VTK, on first use).
MAIN_THREAD_LIBRARIES = ("rectpack", "trimesh", "matplotlib.backends.backend_agg", "matplotlib.figure", "pyvista",
                         "pyvista.plotting")


class Warmup:
    """Imports `modules` in a thread of its own, one at a time, each under `baton`."""

    def __init__(self, modules=MAIN_THREAD_LIBRARIES, before=None):
        self.modules = tuple(modules)
        self.before = before  # called first in the thread (e.g. asking PrusaSlicer its version)
        self.baton = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._start_lock = threading.Lock()

    def start(self) -> None:
        """Start the thread (once; later calls do nothing)."""
        with self._start_lock:
            if self._thread is not None or self._stop.is_set():
                return
            self._thread = threading.Thread(target=self._run, name="warm-imports", daemon=True)
            self._thread.start()

    def _run(self) -> None:
        from .heap import imports_frozen

        if self.before is not None:
            try:
                self.before()
            except Exception:  # left to the step that needs it, which reports it like any step's error
                pass
        for name in self.modules:
            with self.baton:
                if self._stop.is_set():
                    return
                with imports_frozen():
                    try:
                        importlib.import_module(name)
                    except ImportError:  # left to the step that needs it, which reports it
                        pass

    def wait(self) -> None:
        """Until every module is imported (or the thread was stopped)."""
        if self._thread is not None:
            self._thread.join()

    def stop_soon(self) -> None:
        """Import nothing more (callable from any thread, without waiting)."""
        self._stop.set()

    def stop(self) -> None:
        """Import nothing more and wait for the module under way (the build has ended)."""
        with self._start_lock:
            self._stop.set()
            thread = self._thread
        if thread is not None:
            thread.join()

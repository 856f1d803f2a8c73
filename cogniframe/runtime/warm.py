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

import contextlib
import importlib
import threading

# In the order the main thread needs them: the plates' first (they head the path to the slicer),
# then the previews', plots' and figures' (matplotlib), then the renders' (pyvista >= 0.45 loads
# `pyvista.plotting`, most of VTK, on first use).
MAIN_THREAD_LIBRARIES = ("rectpack", "trimesh", "matplotlib.backends.backend_agg", "matplotlib.figure", "pyvista",
                         "pyvista.plotting")


class Baton:
    """The lock the warm-up and the main-thread steps share, with the steps first: a step holds it
    with `with baton:`; the warm-up takes it for each module with `baton.idle()`, which first
    waits until no step is waiting for it. (A plain lock let the warm-up, which releases and
    takes it again at once, import every module while a ready step waited: a one-part rebuild's
    plate, the head of the path to the slicer, waited 0.6 s for matplotlib's and VTK's imports.)"""

    def __init__(self):
        self._lock = threading.Lock()
        self._waiting = 0  # steps waiting for the lock
        self._cv = threading.Condition()

    def __enter__(self):
        with self._cv:
            self._waiting += 1
        self._lock.acquire()
        with self._cv:
            self._waiting -= 1
            self._cv.notify_all()
        return self

    def __exit__(self, *exc) -> None:
        self._lock.release()

    @contextlib.contextmanager
    def idle(self):
        """Held while no step waits for it (the warm-up's side)."""
        while True:
            with self._cv:
                self._cv.wait_for(lambda: self._waiting == 0)
            self._lock.acquire()
            with self._cv:
                if self._waiting == 0:
                    break
            self._lock.release()  # a step came between the two: it goes first
        try:
            yield
        finally:
            self._lock.release()


class Warmup:
    """Imports `modules` in a thread of its own, one at a time, each under `baton` (`Baton.idle`)."""

    def __init__(self, modules=MAIN_THREAD_LIBRARIES, before=None):
        self.modules = tuple(modules)
        self.before = before  # called first in the thread (e.g. asking PrusaSlicer its version)
        self.baton = Baton()
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
            with self.baton.idle():
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

"""The build's worker processes: the CAD pool a build submits to, and the process pools behind it.

`CadPool` is what the build steps see: `submit(fn, *args, priority=...)` returns a Future,
`run(...)` its result, `cancel_pending()` drops the jobs not started yet (a failed build), and
`close()` ends the build's use of it. Behind it the workers are forks of the CAD server
(`runtime.cad_server`, kept between builds) or a process pool of this build's own (`make_pool`).

Every worker, whichever kind, starts with `start_worker`: it dies with the build that asked for
it and runs `BACKGROUND_NICE` steps nicer than the build (the build's main thread, which draws
the previews and renders, is the critical path in a build's second half).
"""

from __future__ import annotations

import contextlib
import os
import threading
from concurrent.futures import ProcessPoolExecutor

from .lifecycle import BACKGROUND_NICE, CAD_PRELOAD, FE_PRELOAD, behind_the_build, die_with_build, start_worker  # noqa: F401


# The order of the CAD workers' jobs (lower first, then in order of submission), by how much waits
# for each: the parts first (everything does: the plates, then the slicer, and the main thread's
# previews and renders); then the joints' FE, which heads the longest chain left (estimate ->
# physics -> check -> flight, 3D view, BOM -> report); then the clash check (check waits for it);
# the assembly STEP last, since nothing waits for it (it ran before the FE, which then ended last).
JOB_ORDER = {"part": 0, "joint FE": 1, "clash": 2, "assembly": 3}



class CadPool:
    """The CAD workers of one build, started by the first job (never on a fully cached build).
    `fe`: the workers preload the joint FE's modules too. `server`: the workers are forks of the
    CAD server that outlives the build (`runtime.cad_server`; `stack` is part of its key), started by
    the first build; without one, or when it cannot start, a process pool of this build's own.
    `early`: the server `cogniframe build` started first thing (`cad_server.prestart`), if any."""

    def __init__(self, workers: int, fe: bool = True, server: bool = False, stack: str = "", log=None, early=None):
        self.workers = workers
        self.fe = fe
        self.server = server
        self.stack = stack
        self.log = log
        self.early = early
        self._pool = None
        self._closed = False
        # set when the workers start cold (a new CAD server, or a process pool of this build's
        # own): their imports take seconds, which the build's own idle work can use
        self.cold = threading.Event()
        self._lock = threading.Lock()

    @property
    def closed(self) -> bool:
        """Whether the build closed the pool (it has ended)."""
        return self._closed

    @property
    def served(self) -> bool:
        """Whether the workers are the CAD server's (once started)."""
        from .cad_server import ServerPool

        return isinstance(self._pool, ServerPool)

    def start_server(self) -> None:
        """Connect to the CAD server in a thread now, starting it if none runs, instead of when the
        first job is submitted: the server's imports head a cold build's critical path. The first
        `submit` waits for that connection."""
        if self.server and self._pool is None:
            threading.Thread(target=self._connect_quietly, name="cad-connect", daemon=True).start()

    def _connect_quietly(self) -> None:
        try:
            self._ensure_pool()
        except Exception:  # the build closed first, or no pool could start: the first submit says so
            pass

    def _ensure_pool(self):
        with self._lock:
            if self._closed:
                raise RuntimeError("the CAD pool is closed")
            if self._pool is None:
                if self.server:
                    from . import cad_server

                    self._pool = cad_server.connect(self.workers, self.stack, self.fe, log=self.log,
                                                on_start=self.cold.set, early=self.early)
                if self._pool is None:
                    self.cold.set()
                    self._pool = make_pool(self.workers, self.fe)
            return self._pool

    def submit(self, fn, *args, priority: int = 0):
        """`fn(*args)` in a worker; returns its Future. `priority` (the server's pool; a process
        pool runs jobs in order): lower first, then in order of submission (`JOB_ORDER`)."""
        pool = self._ensure_pool()
        if self.served:
            return pool.submit(fn, *args, priority=priority)
        return pool.submit(fn, *args)

    def run(self, fn, *args, priority: int = 0):
        return self.submit(fn, *args, priority=priority).result()

    def run_in_pool_if_started(self, fn, *args, priority: int = 0):
        """`fn(*args)` in the pool when it is already running (its own process: Python work there
        does not hold this process's GIL), else right here (starting the pool costs a CadQuery import)."""
        with self._lock:
            started = self._pool is not None
        return self.run(fn, *args, priority=priority) if started else fn(*args)

    def cancel(self) -> None:
        """Drop every job not started yet and end the workers running one (the build calls this
        when a step fails: nothing else it submitted is wanted). Their Futures are cancelled or
        fail, and no new job is taken. The CAD server itself stays."""
        with self._lock:
            self._closed = True
            pool = self._pool
        if pool is not None:
            pool.cancel_pending()
            pool.kill_workers()

    def close(self) -> None:
        with self._lock:  # after a connection under way (`start_server`)
            self._closed = True
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


class _ProcessPool(ProcessPoolExecutor):
    """A ProcessPoolExecutor whose queued jobs can be dropped and whose workers can be ended."""

    def cancel_pending(self) -> None:
        """Nothing here: `kill_workers` fails every job, queued or running, at once (the pool's
        manager thread fails them all with BrokenProcessPool; it must not meet a cancelled one)."""

    def kill_workers(self) -> None:
        """End every worker now: the jobs they run fail (the pool is then broken; shut it down)."""
        for proc in list((self._processes or {}).values()):
            try:
                proc.kill()
            except (OSError, AttributeError):
                pass


@contextlib.contextmanager
def cad_workers(workers: int, fe: bool = False):
    """`submit(fn, *args) -> Future` on a process pool of `workers` CAD workers for the block
    (`make_pool`), for work outside a build (`export.part_files.build_parts`)."""
    with make_pool(workers, fe) as pool:
        yield pool.submit


def make_pool(workers: int, fe: bool = True) -> ProcessPoolExecutor:
    """A process pool for CadQuery work: forkserver with CadQuery preloaded (workers start warm), or
    spawn where forkserver is missing; never fork (a fork after any OCC operation can deadlock).
    `fe`: preload the joint FE's modules too (a build whose joints are all cached says False).
    The forkserver is one per process, started by the first pool: later pools get its preload,
    and import what else they need themselves. Workers die with the build: a killed build leaves
    no worker writing into its temp folder."""
    return _ProcessPool(max_workers=max(1, int(workers)), mp_context=_context(fe), initializer=start_worker,
                        initargs=(os.getpid(),))


@contextlib.contextmanager
def joint_fe_workers(jobs: int | None = None):
    """`submit(fn, *args) -> Future` on worker processes for the joint FE of `check`, started on
    the first submit and shut down when the block ends; None where the joints are better solved
    in this process: one job (`jobs`, else COGNIFRAME_JOBS, else the core count), a daemonic
    process (it cannot have children), or a Dask worker (the cluster schedules its cores).

    The workers are `fork`s when this process is single-threaded and has not loaded OpenCascade
    (no re-import of the main module, nothing to preload); otherwise the forkserver pool (a fork
    after OCC work or beside running threads can deadlock). Both die with this process."""
    import multiprocessing as mp
    import sys

    if jobs is None:
        jobs = int(os.environ.get("COGNIFRAME_JOBS") or 0) or (1 if in_dask_worker() else (os.cpu_count() or 1))
    if jobs <= 1 or mp.current_process().daemon:
        yield None
        return
    pool = []
    lock = threading.Lock()

    def submit(fn, *args):
        with lock:
            if not pool:
                if "OCP" not in sys.modules and threading.active_count() == 1 and "fork" in mp.get_all_start_methods():
                    pool.append(_ProcessPool(max_workers=jobs, mp_context=mp.get_context("fork"),
                                             initializer=die_with_build, initargs=(os.getpid(),)))
                else:
                    pool.append(make_pool(jobs))
        return pool[0].submit(fn, *args)

    try:
        yield submit
    finally:
        for p in pool:
            p.shutdown(wait=True, cancel_futures=True)


def in_dask_worker() -> bool:
    """True inside a Dask worker: its cores are the cluster's to schedule, one design per thread."""
    import sys

    if "distributed" not in sys.modules:
        return False
    try:
        from distributed import get_worker

        get_worker()
        return True
    except (ImportError, ValueError):
        return False


def _context(fe: bool = True):
    import multiprocessing as mp

    try:
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(list(CAD_PRELOAD + (FE_PRELOAD if fe else ())))
        return ctx
    except ValueError:
        return mp.get_context("spawn")

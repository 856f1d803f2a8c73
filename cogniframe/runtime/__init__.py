"""The build's machinery: processes, pools, threads, priorities and idle-time imports, in one place.

The stages and the build steps never start a process or a thread themselves; they are handed a
`BuildRuntime` (the build's `ctx.cad` and `ctx.warm`) and may assume, when a step runs:

- **Main-thread steps run one at a time, alone with their libraries.** No other thread imports
  while one runs (`warm`: the idle-time imports hold the same baton as the step), so a module a
  step imports is never half-imported by someone else. Matplotlib and VTK are used on the main
  thread only.
- **Waiting steps run in threads** and do their heavy work in other processes: `ctx.cad.submit(fn,
  *args, priority=JOB_ORDER[...])` runs `fn` in a CAD worker (CadQuery, trimesh and the part
  builders loaded; the joint FE's modules too when the build solves a joint) and returns a
  Future. `fn` and its arguments must pickle by reference.
- **A failed step stops the build.** The graph stops starting tasks, `cancel()` drops the CAD jobs
  not started yet and ends the workers running one (their Futures fail, which is never
  reported: the first error is), and the build ends when the steps under way have; nothing is written to the output.
- **Workers die with the build** and run nicer than it (`pools.behind_the_build`); the CAD server
  (`server`) outlives builds on purpose and serves only builds of the same code and environment.
- **BLAS runs one thread per process** while the build computes (`analysis.numerics.one_blas_thread`).

Modules: `pools` (the CAD pool, process pools, worker start-up and priority), `server` (the CAD
server kept between builds), `worker` (the CAD workers' bootstrap), `warm` (idle-time imports),
`heap` (the collector around big imports). The BLAS rule lives with the numbers it keeps stable
(`analysis.numerics`).
"""

from __future__ import annotations

import contextlib


class BuildRuntime(contextlib.AbstractContextManager):
    """What one build runs on: its CAD pool (`cad`), its idle-time imports (`warm`) and the lock
    its main-thread steps hold (`main_lock`). Leaving it stops the imports, closes the pool
    (cancelling what was not started) and restores the BLAS threads."""

    def __init__(self, workers: int, fe: bool, server: bool, stack: str, log=None, early=None, warm_before=None):
        from .pools import CadPool
        from .warm import Warmup

        self.cad = CadPool(workers, fe=fe, server=server, stack=stack, log=log, early=early)
        self.warm = Warmup(before=warm_before)
        self._blas = None

    @property
    def main_lock(self):
        return self.warm.baton

    def cancel(self) -> None:
        """A step failed: start no more imports, drop the CAD jobs and end the running ones."""
        self.cad.cancel()
        self.warm.stop_soon()

    def __enter__(self):
        from ..analysis.numerics import one_blas_thread

        self._blas = one_blas_thread()
        self._blas.__enter__()
        return self

    def __exit__(self, *exc):
        try:
            self.warm.stop()
            self.cad.close()
        finally:
            self._blas.__exit__(*exc)
        return False

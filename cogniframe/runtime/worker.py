"""Bootstrap of the CAD worker processes: the forkserver of `runtime.pools.make_pool` imports this
module once (its preload), then forks every worker from it warm. It is the one module of the
package whose import does something on purpose; nothing else imports it.

What it does, in that process only:
- makes `vtk` lazy. OCP's IVtkOCC binding (imported by CadQuery) imports the whole `vtk` package,
  a third of the CadQuery import, for CadQuery's VTK display helpers, which a worker never
  calls. The stand-in module imports the real `vtkmodules.all` the first time anything reads an
  attribute of it, so a use still works, only later.
- imports CadQuery, trimesh and the part builders, so each worker starts with them loaded,
  with the garbage collector off, then freezes their objects (`runtime.heap.imports_frozen`): no
  worker's collection walks them again.
- runs OpenCascade's algorithms on the calling thread only (below).
- lets the forkserver end without tearing OpenCascade down. It ends when the build does, and its
  interpreter's teardown would hold the build's stdout and stderr open for another second: a
  build piped into another program (`| tee`, a benchmark, CI) would seem to run that much longer.
  It has no files or buffers to flush, so it leaves with `os._exit` once its exit handlers have
  run. (Its forked workers leave by `os._exit` already.)

docs/build.md ("Who gets the cores") has what each of these measured.
"""

from __future__ import annotations

import atexit
import importlib
import os
import sys
import types


class _LazyModule(types.ModuleType):
    """A module that becomes `target` the first time one of its attributes is read."""

    def __init__(self, name: str, target: str):
        super().__init__(name)
        self.__dict__["_target"] = target

    def __getattr__(self, attr: str):
        real = importlib.import_module(self.__dict__["_target"])
        sys.modules[self.__name__] = real
        return getattr(real, attr)


# exit handlers run last-registered first: this one runs after anything registered later in the
# forkserver and ends it before multiprocessing's own (registered earlier, on its import), which
# has nothing to do there: the workers are plain forks, not Process objects to join
atexit.register(os._exit, 0)
if "vtk" not in sys.modules:
    sys.modules["vtk"] = _LazyModule("vtk", "vtkmodules.all")

from .heap import imports_frozen  # noqa: E402

with imports_frozen():  # the forks start with nothing for the collector to walk
    import cadquery  # noqa: E402,F401
    import trimesh  # noqa: E402,F401

    from ..families import registry  # noqa: E402,F401

# OpenCascade's own thread pool, which CadQuery's booleans (SetRunParallel) and the tessellation
# use, with the calling thread only: the build runs one worker per core already, and the pool's
# threads (one per core in each worker) only fight the other worker and PrusaSlicer for the same
# cores, for the same STL bytes. Set before any fork, it starts no thread (nothing a fork could
# leave half-held).
from OCP.OSD import OSD_ThreadPool  # noqa: E402

OSD_ThreadPool.DefaultPool_s(1).Init(1)

"""The garbage collector around a process's big imports.

CPython's cyclic collector walks every tracked object in its oldest generation on each full
collection. A CAD process holds ~400 000 of them once CadQuery, trimesh and VTK are imported,
nearly all of them module-level objects that live as long as the process, and each full
collection during the imports walks them all again (docs/build.md has what that cost).

`imports_frozen()` turns the collector off while a block imports (imports make few cycles) and
then moves every object alive into the permanent generation (`gc.freeze`), which no collection
walks. Used where a process imports for the rest of its life: the CAD server and the
forkserver before they fork their workers (the forks start with nothing to walk, and pages are
not written by the collector's bookkeeping, so they stay shared), the `build` command's own
imports and the build's warm-up imports. Frozen garbage is never freed, so a block that imports
nothing new freezes nothing: a session that builds again and again freezes once at most.
"""

from __future__ import annotations

import contextlib
import gc
import sys


@contextlib.contextmanager
def imports_frozen():
    """No cyclic collection while the block runs; afterwards, if the block imported a module,
    every tracked object is frozen (see the module docstring), and the collector is as it was.

    `gc.freeze` also freezes cyclic garbage not collected yet, for good: in a session that builds
    again and again (a notebook, the tests) only the first block imports, so that happens once."""
    was_on = gc.isenabled()
    n_modules = len(sys.modules)
    gc.disable()
    try:
        yield
    finally:
        if len(sys.modules) != n_modules:
            gc.freeze()
        if was_on:
            gc.enable()

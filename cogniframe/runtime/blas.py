"""One BLAS thread per process while cogniframe computes (threadpoolctl).

The frame's matrices are small (a few hundred to a few thousand unknowns): OpenBLAS's threads
save little on them and, on a machine with as many busy processes as cores (the build runs the
CAD pool, PrusaSlicer and its own threads side by side), they spin-wait for each other
(docs/build.md has the measurements). One thread also makes the sums' order, and so the
numbers, the same on every machine.

`one_blas_thread()` limits every BLAS library loaded in this process (numpy's and scipy's
OpenBLAS: scipy.linalg is imported first so that both are) and restores them on exit.
"""

from __future__ import annotations

import contextlib


@contextlib.contextmanager
def one_blas_thread():
    try:
        import scipy.linalg  # noqa: F401 - loads scipy's own OpenBLAS, so the limit reaches it too
        from threadpoolctl import threadpool_limits
    except ImportError:  # no threadpoolctl: run with the libraries' defaults
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"):
        yield

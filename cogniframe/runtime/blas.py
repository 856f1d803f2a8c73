"""One BLAS thread per process while cogniframe computes (threadpoolctl).

The frame's matrices are small (a few hundred to a few thousand unknowns): OpenBLAS's threads
save little on them and, on a machine with as many busy processes as cores (the build runs the
CAD pool, PrusaSlicer and its own threads side by side), they spin-wait for each other. Measured
on the shared 2-core machine (load ~6): the carbon preset's k solve 0.96 -> 0.14 s CPU and its
load cases 3.4-5.2 -> 1.2 s CPU (wall 5-6 -> 1.3-2 s) with one thread.

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

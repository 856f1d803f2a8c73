"""One BLAS thread while cogniframe computes (threadpoolctl): the same numbers on any machine.

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
import threading


# The BLAS thread count is the process's, not a thread's: while any thread of this process is
# inside `one_blas_thread`, the limit holds; the last one out restores the libraries' own.
_LOCK = threading.Lock()
_USERS = [0, None]  # threads inside, the limiter that restores on the last exit


@contextlib.contextmanager
def one_blas_thread():
    try:
        import scipy.linalg  # noqa: F401 - loads scipy's own OpenBLAS, so the limit reaches it too
        from threadpoolctl import ThreadpoolController
    except ImportError:  # no threadpoolctl: run with the libraries' defaults
        yield
        return
    with _LOCK:
        if _USERS[0] == 0:
            _USERS[1] = ThreadpoolController().limit(limits=1, user_api="blas")
        _USERS[0] += 1
    try:
        yield
    finally:
        with _LOCK:
            _USERS[0] -= 1
            if _USERS[0] == 0:
                _USERS[1].restore_original_limits()
                _USERS[1] = None

"""BLAS on one thread for small linear algebra: interactive queries and a build's factorisations.

Small BLAS/LAPACK calls (a click's inverse map, a synthesis path, a 28,833 x 110 QR)
gain nothing from a second OpenBLAS thread and collapse when the cores are shared: at
load average 12-14 on two cores a 28,833 x 110 QR took 5.5 s on two threads and 0.41 s
on one. The big GEMMs over the frames keep every thread.

:func:`one_blas_thread` limits every loaded BLAS library (numpy's and scipy's OpenBLAS)
to one thread while any caller is inside it, and restores the previous limit when the
last caller leaves. The limit is process-wide (OpenBLAS has no per-thread setting), so
the entries are counted under a lock: a click on the window's thread and a build's QR
on a worker thread may overlap in any order without leaving BLAS stuck at one thread
(nesting ``threadpoolctl.threadpool_limits`` from two threads restores in the wrong
order); threadpoolctl's rule that only one thread may change a shared OpenBLAS pool
is respected by handing control back after each change. Entering costs about a
millisecond (one cached ``ThreadpoolController``), against about 40 ms for
``threadpool_limits``, which scans the loaded libraries on every call.
"""
from __future__ import annotations

import functools
import threading
from contextlib import contextmanager

__all__ = ["one_blas_thread", "single_blas_thread"]

_lock = threading.Lock()
_depth = 0
_limiter = None
_controller = None


def _blas_controller():
    """The controller of the BLAS libraries, created once (after numpy and scipy.linalg load theirs)."""
    global _controller
    import numpy  # noqa: F401  (numpy's and scipy's OpenBLAS must be loaded to be limited)
    import scipy.linalg  # noqa: F401
    from threadpoolctl import ThreadpoolController

    if _controller is None:
        _controller = ThreadpoolController()
    return _controller


@contextmanager
def one_blas_thread():
    """Context manager: every BLAS library on one thread while any caller is inside.

    Re-entrant and safe across threads (entries counted under a lock; the limit found
    by the first entrant is restored when the last one leaves).
    """
    global _depth, _limiter
    with _lock:
        if _depth == 0:
            ctl = _blas_controller()
            _release_control()
            _limiter = ctl.limit(limits=1, user_api="blas")
            _release_control()
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                _release_control()
                _limiter.restore_original_limits()
                _limiter = None
                _release_control()


def _release_control():
    """Let any thread set OpenBLAS's limit next.

    threadpoolctl (3.8) lets only one "controlling" thread change a pthreads OpenBLAS
    pool and silently ignores the others until that thread leaves a ``with`` block. The
    limit set here on one thread may be restored on another, and a window thread inside
    someone's ``threadpool_limits`` block must not make an interactive query ignore its
    limit, so control is cleared before and after every change made here (the changes
    are serialised by this module's lock; the pool is process-wide either way).
    """
    from threadpoolctl import OpenBLASController

    OpenBLASController.clear_controlling_thread(force=True)


def single_blas_thread(fn):
    """Decorator: run ``fn`` inside :func:`one_blas_thread` (for interactive query methods)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return fn(*args, **kwargs)

    return wrapper

"""One BLAS thread in the processes the package runs: the command line and the batch workers (issue #8).

The linear algebra of the lab preprocessing is small (Gram matrices of at most a few hundred harmonics,
Cholesky factors, triangular solves), far below the size where OpenBLAS's threads pay.  Its threads do
cost when the cores are busy: they spin while they wait, so on a 2-core machine with other work (or with
the other files of a folder prepared on the other core) a 401 x 401 Cholesky factor took 40 ms instead
of 1 ms, and ``bouc-wen-id identify`` on 10 lab files took 4-7 s instead of 1 s (measured, load 3-5).
The parallelism of this package is across files, jobs and starts, never inside a small matrix.

So the processes the package controls (``bouc-wen-id``'s and the workers of
:func:`~bouc_wen_id.batch.identify_many` and of the command line) run BLAS on one thread, through
``threadpoolctl`` (which finds every BLAS the process has loaded: NumPy's and SciPy's own OpenBLAS, MKL,
BLIS).  A library call does not change the caller's BLAS.  A user who sets ``OPENBLAS_NUM_THREADS``,
``MKL_NUM_THREADS`` or ``OMP_NUM_THREADS`` keeps that choice.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["BLAS_THREAD_VARIABLES", "one_blas_thread", "limit_blas_threads"]

#: Environment variables by which a user states the BLAS thread count (then it is left alone).
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS")


#: Set to 1 for the BLAS libraries loaded later (SciPy's own OpenBLAS comes with the first SciPy call,
#: after the limit on the loaded ones; OpenBLAS, MKL and BLIS read these when they load).  Worker
#: processes started meanwhile inherit them.
_LATER = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")


def _user_chose() -> bool:
    return any(os.environ.get(v) for v in BLAS_THREAD_VARIABLES)


def _limit_loaded() -> object:
    """One thread for every BLAS loaded now; the handle restores them (``None`` without threadpoolctl)."""
    try:
        from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]
    except ImportError:  # pragma: no cover - a declared dependency; a slower run, not a wrong one
        return None
    return threadpool_limits(limits=1, user_api="blas")


def limit_blas_threads() -> None:
    """One BLAS thread in this process from now on, for the BLAS loaded and those loaded later (a worker
    process of the package), unless the user chose a count."""
    if _user_chose():
        return
    os.environ.update(dict.fromkeys(_LATER, "1"))
    _limit_loaded()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """One BLAS thread inside the block (the BLAS loaded and those loaded in it, and the environment of
    the processes started in it).  After it the environment and the BLAS loaded before it are restored; a
    BLAS first loaded inside it (SciPy's) keeps one thread: the CLI's process ends there, and an
    in-process caller (a test, a bench) keeps a faster, not a different, SciPy."""
    if _user_chose():
        yield
        return
    os.environ.update(dict.fromkeys(_LATER, "1"))
    limits = _limit_loaded()
    try:
        yield
    finally:
        for v in _LATER:
            os.environ.pop(v, None)
        restore = getattr(limits, "restore_original_limits", None)
        if restore is not None:
            restore()

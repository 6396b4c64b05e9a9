"""A selection step's candidate fits on up to one thread per core (:data:`speed.THREAD_CANDIDATE_FITS`).

Each candidate of a step is fitted from the same model, independently of the others, and almost all of a
fit's time is the Rust core's refinement, which runs without the interpreter's lock: fitted on threads they
overlap (review 40: one MR level used 1.1 of 2 cores). The results are those of the fits run one after the
other (each fit depends on its inputs only; the memo of :func:`.select.memo_fit_with` and the store of
:mod:`.fit_share` take each key once). Each thread runs in a copy of the caller's context, so a
:func:`.fit_share.scope` of the caller holds there too.

The fits silence their own warnings (``warnings.catch_warnings``, fitting.py), which on Python < 3.14 saves
and restores the process's one filter list: two threads interleaving could restore each other's and leave
warnings ignored after the diagnosis. So the threads run inside one ``catch_warnings`` of the caller's
thread, whose exit restores the caller's filters whatever the threads did.
"""

from __future__ import annotations

import contextvars
import os
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, wait
from typing import Optional, TypeVar

from . import speed

T = TypeVar("T")


def in_order(
    fit: Callable[[str], T], terms: Sequence[str], before: Optional[Callable[[int, str], None]] = None
) -> list[T]:
    """``[fit(t) for t in terms]``, on up to one thread per core when :data:`speed.THREAD_CANDIDATE_FITS`
    (and more than one term). ``before(k, t)`` is called in the caller's thread before the k-th result is
    waited for (progress, as the loop said it before each fit). An error of a fit is raised at its turn, as
    in the loop; the fits queued behind it are dropped."""
    workers = min(len(terms), os.cpu_count() or 1) if speed.THREAD_CANDIDATE_FITS else 1
    if workers <= 1:
        out = []
        for k, t in enumerate(terms):
            if before is not None:
                before(k, t)
            out.append(fit(t))
        return out
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _threaded(fit, terms, before, workers)


def _threaded(
    fit: Callable[[str], T], terms: Sequence[str], before: Optional[Callable[[int, str], None]], workers: int
) -> list[T]:
    pool = ThreadPoolExecutor(max_workers=workers)
    futures: list[Future[T]] = [pool.submit(contextvars.copy_context().run, fit, t) for t in terms]
    out = []
    try:
        for k, (t, f) in enumerate(zip(terms, futures)):
            if before is not None:
                before(k, t)
            # Wait in short slices: Ctrl-C may reach a worker thread, and a main thread blocked without a
            # timeout would not run Python's handler until the fit ended (drift._run_all does the same).
            while not f.done():
                wait([f], timeout=0.05)
            out.append(f.result())
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return out


__all__ = ["in_order"]

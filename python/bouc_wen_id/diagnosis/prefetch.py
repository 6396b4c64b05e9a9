"""A selection step's candidate fits on up to one thread per core (:data:`speed.THREAD_CANDIDATE_FITS`).

Each candidate of a step is fitted from the same model, independently of the others, and almost all of a
fit's time is the Rust core's refinement, which runs without the interpreter's lock: fitted on threads they
overlap (review 40: one MR level used 1.1 of 2 cores). The results are those of the fits run one after the
other (each fit depends on its inputs only; the memo of :func:`.select.memo_fit_with` and the store of
:mod:`.fit_share` take each key once). Each thread runs in a copy of the caller's context, so a
:func:`.fit_share.scope` of the caller holds there too.
"""

from __future__ import annotations

import contextvars
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, wait
from typing import Optional, TypeVar

from . import speed

T = TypeVar("T")


def in_order(fit: Callable[[str], T], terms: Sequence[str]) -> Iterator[T]:
    """``fit(t)`` for each of ``terms``, yielded in their order; computed on up to one thread per core when
    :data:`speed.THREAD_CANDIDATE_FITS` (and more than one term), else one after the other as they are
    asked for. An error of a fit is raised when its turn comes, as it would have been in the loop; the
    queued fits are then dropped."""
    workers = min(len(terms), os.cpu_count() or 1) if speed.THREAD_CANDIDATE_FITS else 1
    if workers <= 1:
        for t in terms:
            yield fit(t)
        return
    pool = ThreadPoolExecutor(max_workers=workers)
    futures: list[Optional[Future[T]]] = [pool.submit(contextvars.copy_context().run, fit, t) for t in terms]
    try:
        for k in range(len(terms)):
            f = futures[k]
            assert f is not None
            # Wait in short slices: Ctrl-C may reach a worker thread, and a main thread blocked without a
            # timeout would not run Python's handler until the fit ended (drift._run_all does the same).
            while not f.done():
                wait([f], timeout=0.05)
            futures[k] = None
            yield f.result()
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


__all__ = ["in_order"]

"""The package's worker processes: one pool per size, shared by :func:`~bouc_wen_id.batch.identify_many`,
:func:`~bouc_wen_id.batch.average_many` and the command line (issue #8, #17, #19).

* **Capped.** ``workers`` may not exceed the machine's CPU count (:func:`check_workers`): a request for a
  million workers is a named error, not a fork bomb.
* **Cached, and rebuilt when broken.** Starting worker processes costs more than a small batch, so a pool is
  kept for the life of the process and reused.  A pool whose worker died (killed, out of memory, a crash in
  native code) is discarded: the call that met the death raises, and the next call starts fresh workers.
* **The caller's budgets travel.** Every task runs under the limits of :mod:`bouc_wen_id.budget` in force in
  the process that submitted it (a worker process has its own copy of the module), so
  ``with bw.budget.budget(max_steps=...)`` means the same serial or pooled.
* **Quiet workers.** Each worker runs one rayon thread and one BLAS thread (the parallelism is across the
  tasks; nested threads would only compete for the same cores: see :mod:`bouc_wen_id._threads`), and when
  the pool has one worker per usable CPU each worker is pinned to one.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Optional

import numpy as np

from . import budget as _budget
from .errors import BoucWenIdError, InvalidParameterError

__all__ = ["cpu_count", "usable_cores", "check_workers", "get_pool", "submit", "ordered", "warm", "stop_all"]

#: Environment of the worker processes: one rayon thread each, so that n workers do not run n x n threads.
_WORKER_ENV = {"RAYON_NUM_THREADS": "1"}

#: What a worker's fork server imports once, unless the caller names more (the CLI adds the plotting).
DEFAULT_PRELOAD = ("bouc_wen_id.identification", "bouc_wen_id.signal")


def cpu_count() -> int:
    """The CPUs of this machine: the most workers a pool may have."""
    return os.cpu_count() or 1


def usable_cores() -> int:
    """The cores this process may run on (its affinity mask where the OS has one, e.g. under taskset)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return cpu_count()


def check_workers(workers: object, name: str = "workers") -> int:
    """A worker count: ``None`` is one per usable core; else an integer in ``[1, cpu_count()]``.

    ``name`` is how the caller spells it in the message (``"workers"`` in Python, ``"--workers"`` on the
    command line).  Raises :class:`~bouc_wen_id.errors.InvalidParameterError` otherwise.
    """
    if workers is None:
        return usable_cores()
    said = f"{name} {workers!r}" if name.startswith("--") else f"{name} = {workers!r}"
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise InvalidParameterError(f"{said} must be an integer >= 1")
    cap = cpu_count()
    if workers > cap:
        raise InvalidParameterError(
            f"{said} is more than the {cap} CPU(s) of this machine; give at most {cap} (default: one per "
            "usable core)"
        )
    return int(workers)


# --------------------------------------------------------------------------------------------------
# Worker processes
# --------------------------------------------------------------------------------------------------


def _init_worker(counter: Any = None, cpus: Optional[Sequence[int]] = None) -> None:
    os.environ.update(_WORKER_ENV)
    if counter is not None and cpus:
        # One CPU per worker when there are as many workers as CPUs: a worker the scheduler moves between
        # cores loses its caches; measured on the 2-core machine, 20 identifications of ~15 ms took 0.168 s
        # on two free workers and 0.152 s on two pinned ones (0.300 s serial).
        with counter.get_lock():
            i = int(counter.value)
            counter.value += 1
        os.sched_setaffinity(0, {cpus[i % len(cpus)]})
    from ._threads import limit_blas_threads

    limit_blas_threads()


def _context(preload: Sequence[str]) -> Any:
    """Worker processes from a fork server that has imported ``preload`` once (cheap to start, and free of
    the parent's threads), else spawned ones.  The fork server is one per process: the first pool's preload
    is the one it keeps."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(list(preload))
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows, macOS


def _worker_cpus(workers: int) -> Optional[list[int]]:
    """The CPUs to pin the workers to, one each: when the pool has exactly as many workers as this process
    may run on (else the scheduler places them)."""
    if not hasattr(os, "sched_getaffinity") or not hasattr(os, "sched_setaffinity"):
        return None
    cpus = sorted(os.sched_getaffinity(0))
    return cpus if len(cpus) == workers else None


#: The pools of this process, by size (``get_pool``), and the lock that guards the dict.
_POOLS: dict[int, ProcessPoolExecutor] = {}
_LOCK = threading.Lock()


def _is_broken(pool: Executor) -> bool:
    # ProcessPoolExecutor marks itself broken when a worker dies; submit() then raises.  The attribute is
    # CPython's (3.8+); without it, submit() still raises BrokenProcessPool and ``submit`` rebuilds.
    return bool(getattr(pool, "_broken", False))


def get_pool(workers: int, preload: Sequence[str] = DEFAULT_PRELOAD) -> ProcessPoolExecutor:
    """The process-wide pool of ``workers`` processes (``check_workers`` first), started on first use and
    started afresh when the previous one broke."""
    with _LOCK:
        pool = _POOLS.get(workers)
        if pool is not None and not _is_broken(pool):
            return pool
        if pool is not None:
            _discard_locked(workers, pool)
        ctx = _context(preload)
        cpus = _worker_cpus(workers)
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=ctx,
            initializer=_init_worker,
            initargs=(ctx.Value("i", 0), cpus) if cpus else (),
        )
        if not _POOLS:
            atexit.register(_shutdown_pools)
        _POOLS[workers] = pool
        return pool


def _discard_locked(workers: int, pool: ProcessPoolExecutor) -> None:
    if _POOLS.get(workers) is pool:
        del _POOLS[workers]
    pool.shutdown(wait=False, cancel_futures=True)


def discard(pool: Executor) -> None:
    """Forget a broken pool: the next :func:`get_pool` of its size starts new workers."""
    with _LOCK:
        for workers, p in list(_POOLS.items()):
            if p is pool:
                _discard_locked(workers, p)


def stop_all() -> None:
    """End every worker now, running tasks and all (after Ctrl-C or SIGTERM nobody wants their results,
    and an exit that waited for them could take seconds)."""
    with _LOCK:
        pools = list(_POOLS.values())
        _POOLS.clear()
    for pool in pools:
        workers = list((getattr(pool, "_processes", None) or {}).values())  # CPython's: pid -> process
        pool.shutdown(wait=False, cancel_futures=True)
        for worker in workers:
            worker.terminate()


def _shutdown_pools() -> None:
    with _LOCK:
        pools = list(_POOLS.values())
        _POOLS.clear()
    for pool in pools:
        pool.shutdown(wait=True, cancel_futures=True)


# --------------------------------------------------------------------------------------------------
# Tasks: the caller's budget travels with each one
# --------------------------------------------------------------------------------------------------


def call_within(limits: _budget.Budget, fn: Callable[..., Any], args: Sequence[Any]) -> Any:
    """``fn(*args)`` under the budget ``limits`` (in a worker process: the submitter's)."""
    with _budget.budget(
        max_samples=limits.max_samples, max_steps=limits.max_steps, max_bytes=limits.max_bytes
    ):
        return fn(*args)


def submit(pool: Executor, fn: Callable[..., Any], *args: Any) -> Future[Any]:
    """``pool.submit(fn, *args)`` under this process's budget; a broken pool is discarded first (then
    :class:`BrokenProcessPool` is raised: the caller asks :func:`get_pool` for a new one)."""
    try:
        return pool.submit(call_within, _budget.get_budget(), fn, args)
    except BrokenProcessPool as exc:
        # A worker that died while earlier jobs were being submitted breaks the pool here, before any
        # result is read: the same named error as :func:`result`'s, whichever of the two sees it first.
        raise _died(pool, "the batch") from exc


def _died(pool: Executor, what: str) -> BrokenProcessPool:
    """Discard the broken ``pool``; the error to raise, which says what happened and what comes next."""
    discard(pool)
    return BrokenProcessPool(
        f"a worker process died (killed, out of memory, or a crash) while running {what}; its pool is "
        "discarded, and the next call starts new workers"
    )


def result(pool: Executor, future: Future[Any], what: str) -> Any:
    """The future's result; when its worker died, the pool is discarded and the error says so."""
    try:
        return future.result()
    except BrokenProcessPool as exc:
        raise _died(pool, what) from exc


def ordered(
    pool: Executor, fn: Callable[..., Any], jobs: Sequence[tuple[Any, ...]], here: bool = True
) -> Iterator[Any]:
    """``fn(*job)`` for every job, yielded in the jobs' order.

    The pool's workers take the jobs from the front; with ``here``, this process takes them from the back
    (each job it can still withdraw from the pool) until the two meet, so that no core waits while the
    workers start.  An error is raised when its job's turn comes, as a loop over the jobs would.
    """
    futures = [submit(pool, fn, *job) for job in jobs]
    local: dict[int, tuple[bool, Any]] = {}
    if here:
        for i in reversed(range(len(jobs))):
            if not futures[i].cancel():
                break
            try:
                local[i] = (True, fn(*jobs[i]))
            except BoucWenIdError as exc:
                local[i] = (False, exc)
    try:
        for i, f in enumerate(futures):
            if i in local:
                ok, value = local.pop(i)
                if not ok:
                    raise value
                yield value
            else:
                yield result(pool, f, f"job {i}")
    finally:
        for f in futures:
            f.cancel()


def warm(pool: Executor, workers: int) -> threading.Thread:
    """Start every worker of ``pool`` on a helper thread (a start waits for the fork server's imports: off
    the main thread, that overlaps with the caller's own work, e.g. loading the files).  Join the thread
    before leaving the pool."""

    def run() -> None:
        try:
            for f in [pool.submit(os.getpid) for _ in range(workers)]:
                f.result()
        except Exception:  # noqa: BLE001 - a pool that cannot start fails the first real task, by name
            pass

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread

"""Many independent identifications at once: on the local cores, or on a Dask cluster (issue #8).

:func:`identify_many` runs :func:`bouc_wen_id.identify` on every job of a batch (the folds of a
cross-validation, the candidate models of a diagnosis, the files of a campaign) and returns the results in
the order of the jobs.  Each identification is deterministic and independent of the others, so the
results are identical, bit for bit, whether the batch runs serially, on a local pool of worker processes
(the default: one per core) or on a ``dask.distributed`` cluster.

Dask is optional (``pip install "bouc_wen_id[dask]"``) and imported only when a client is given.
"""

from __future__ import annotations

import atexit
import copy
import multiprocessing
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import TYPE_CHECKING, Any, Literal, Optional, Union

from . import _optional
from .errors import BoucWenIdError, InvalidParameterError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .result import IdentificationResult

__all__ = ["identify_many", "Job"]

#: A job: the experiments of one identification (what ``identify`` takes as its first argument), or a
#: mapping ``{"experiments": [...], **identify_options}`` whose options override the batch's.
Job = Union[Sequence[Any], Mapping[str, Any]]

#: Environment of the worker processes: one rayon thread each, so that a batch on n cores does not run
#: n x n threads (the parallelism is across the jobs).
_WORKER_ENV = {"RAYON_NUM_THREADS": "1"}


def _split(job: Job, common: Mapping[str, Any], index: int) -> tuple[Sequence[Any], dict[str, Any]]:
    if isinstance(job, Mapping):
        if "experiments" not in job:
            raise InvalidParameterError(f"job {index} is a mapping without an 'experiments' key")
        options = {**common, **{k: v for k, v in job.items() if k != "experiments"}}
        return job["experiments"], options
    if isinstance(job, (str, bytes)) or not isinstance(job, Sequence):
        raise InvalidParameterError(
            f"job {index} is a {type(job).__name__}; a job is a sequence of experiments or a mapping "
            "{'experiments': [...], **identify_options}"
        )
    return job, dict(common)


def _run(experiments: Sequence[Any], options: Mapping[str, Any], errors: str) -> Any:
    """One identification (in whatever process runs it)."""
    from .identification import identify

    # Fresh copies of the experiments' arrays: a process that received them (Dask deserialises straight
    # from its network frames) may hold read-only, unaligned buffers that the core cannot borrow.
    experiments = copy.deepcopy(experiments)
    try:
        return identify(experiments, **options)
    except BoucWenIdError as exc:
        if errors == "return":
            return exc
        raise


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
    # One BLAS thread too: n workers with OpenBLAS's default threads each spin 2n threads on n cores
    # (see bouc_wen_id._threads).
    from ._threads import limit_blas_threads

    limit_blas_threads()


def _context() -> Any:
    """Worker processes from a fork server that has imported the package once (cheap to start, and free
    of the parent's threads), else spawned ones."""
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["bouc_wen_id.identification"])
        return ctx
    return multiprocessing.get_context("spawn")


def identify_many(
    jobs: Sequence[Job],
    *,
    workers: Optional[int] = None,
    client: Any = None,
    errors: Literal["raise", "return"] = "raise",
    **options: Any,
) -> list[Union[IdentificationResult, BoucWenIdError]]:
    """Run :func:`bouc_wen_id.identify` on every job; results in the order of the jobs.

    Parameters
    ----------
    jobs : sequence of jobs
        Each job is what ``identify`` takes as its first argument (a sequence of ``Recording``,
        ``Measurement`` or ``AveragedPeriod``), or a mapping ``{"experiments": [...], **options}`` whose
        options override the batch's ``options`` for that job.
    workers : int, optional
        Local worker processes.  Default: one per core (``os.cpu_count()``), at most one per job.  ``1``
        runs the batch serially in this process.  Ignored when ``client`` is given.
    client : distributed.Client, optional
        Run the jobs on this Dask cluster instead (one task per job).  Needs the ``dask`` extra.
    errors : {"raise", "return"}
        What a job refused by ``identify`` (a :class:`~bouc_wen_id.errors.BoucWenIdError`) does: raise it
        (default), or stand in the results list in that job's place.
    **options
        Keyword arguments of ``identify`` for every job (``method``, ``backend``, ``mu_bracket``, ...).

    Returns
    -------
    list
        One :class:`~bouc_wen_id.identification.IdentificationResult` per job (or, with
        ``errors="return"``, the error it raised).  Identical whatever ``workers`` or ``client``: every
        identification is deterministic and runs on its own, with BLAS on one thread (see
        :mod:`bouc_wen_id._threads`; a plain ``identify`` of lab measurements in a process whose BLAS runs
        several threads can differ from it in the last bits).

    Raises
    ------
    InvalidParameterError
        A malformed job, ``workers < 1``, an unknown ``errors``.
    ImportError
        ``client`` given but ``dask.distributed`` is not installed.
    BoucWenIdError
        The first (in job order) error of ``identify``, with ``errors="raise"``.
    """
    if errors not in ("raise", "return"):
        raise InvalidParameterError(f"errors must be 'raise' or 'return', got {errors!r}")
    split = [_split(job, options, i) for i, job in enumerate(jobs)]
    if not split:
        return []
    if client is not None:
        return _on_dask(client, split, errors)
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidParameterError(f"workers = {workers!r} must be an integer >= 1")
    workers = min(workers, len(split))
    if workers == 1:
        # One BLAS thread here as in the workers (and Dask's, whose nannies set it too): the last bits of
        # a threaded BLAS call can depend on its thread count, and the results must not on ``workers``.
        from ._threads import one_blas_thread

        with one_blas_thread():
            return [_run(e, o, errors) for e, o in split]
    pool = _local_pool(workers)
    futures = [pool.submit(_run, e, o, errors) for e, o in split]
    return [f.result() for f in futures]


#: Local pools kept for the life of the process (by size): starting worker processes costs more than a
#: small batch, so a second batch reuses the first one's workers.
_POOLS: dict[int, ProcessPoolExecutor] = {}


def _worker_cpus(workers: int) -> Optional[list[int]]:
    """The CPUs to pin the workers to, one each: when the pool has exactly as many workers as this process
    may run on (else the scheduler places them)."""
    if not hasattr(os, "sched_getaffinity") or not hasattr(os, "sched_setaffinity"):
        return None
    cpus = sorted(os.sched_getaffinity(0))
    return cpus if len(cpus) == workers else None


def _local_pool(workers: int) -> ProcessPoolExecutor:
    pool = _POOLS.get(workers)
    if pool is None:
        ctx = _context()
        cpus = _worker_cpus(workers)
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=ctx,
            initializer=_init_worker,
            initargs=(ctx.Value("i", 0), cpus) if cpus else (),
        )
        _POOLS[workers] = pool
        if len(_POOLS) == 1:
            atexit.register(_shutdown_pools)
    return pool


def _shutdown_pools() -> None:
    for pool in _POOLS.values():
        pool.shutdown(wait=True, cancel_futures=True)
    _POOLS.clear()


def _on_dask(client: Any, split: Sequence[tuple[Sequence[Any], dict[str, Any]]], errors: str) -> list[Any]:
    _optional.require("distributed", "identify_many(client=...)")
    # pure=False: the jobs are not hashed (their arrays can be large) and every call runs.
    futures = [client.submit(_run, e, o, errors, pure=False) for e, o in split]
    return list(client.gather(futures))

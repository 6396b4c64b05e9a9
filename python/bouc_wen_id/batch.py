"""Many independent jobs at once: on the local cores, or on a Dask cluster (issue #8).

:func:`identify_many` runs :func:`bouc_wen_id.identify` on every job of a batch (the folds of a
cross-validation, the candidate models of a diagnosis, the files of a campaign) and returns the results in
the order of the jobs.  :func:`average_many` prepares a folder of lab measurements the same way (the steady
segments of each, averaged: :func:`bouc_wen_id.signal.average_segments`).  Each job is deterministic and
independent of the others, so the results are identical, bit for bit, whether the batch runs serially, on a
local pool of worker processes (:mod:`bouc_wen_id._pool`: at most one per CPU, rebuilt when a worker dies,
the caller's budgets in force in every worker) or on a ``dask.distributed`` cluster.

Dask is optional (``pip install "bouc_wen_id[dask]"``) and imported only when a client is given.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal, Optional, Union

from . import _optional, _pool
from . import budget as _budget
from .errors import BoucWenIdError, InsufficientDataError, InvalidParameterError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .measurement import Measurement
    from .result import IdentificationResult
    from .signal import SegmentedMeasurement

__all__ = ["identify_many", "average_many", "Job"]

#: A job: the experiments of one identification (what ``identify`` takes as its first argument), or a
#: mapping ``{"experiments": [...], **identify_options}`` whose options override the batch's.
Job = Union[Sequence[Any], Mapping[str, Any]]


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
        Local worker processes, at most the machine's CPU count.  Default: one per usable core, at most
        one per job.  ``1`` runs the batch serially in this process.  Ignored when ``client`` is given.
        The workers are kept for the next batch; one that dies is replaced at the next call.
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
        A malformed job, ``workers`` not in ``[1, os.cpu_count()]``, an unknown ``errors``.
    ImportError
        ``client`` given but ``dask.distributed`` is not installed.
    BoucWenIdError
        The first (in job order) error of ``identify``, with ``errors="raise"``.
    concurrent.futures.process.BrokenProcessPool
        A worker process died (killed, out of memory); the next call starts new ones.

    Notes
    -----
    The limits of :mod:`bouc_wen_id.budget` in force in this process apply in every worker (and on Dask).
    """
    if errors not in ("raise", "return"):
        raise InvalidParameterError(f"errors must be 'raise' or 'return', got {errors!r}")
    split = [_split(job, options, i) for i, job in enumerate(jobs)]
    if not split:
        return []
    if client is not None:
        return _on_dask(client, split, errors)
    workers = min(_pool.check_workers(workers), len(split))
    if workers == 1:
        return _serial(lambda e, o: _run(e, o, errors), split)
    pool = _pool.get_pool(workers)
    return list(_pool.ordered(pool, _run, [(e, o, errors) for e, o in split], here=False))


def _serial(fn: Callable[..., Any], jobs: Sequence[tuple[Any, ...]]) -> list[Any]:
    # One BLAS thread here as in the workers (and Dask's, whose nannies set it too): the last bits of a
    # threaded BLAS call can depend on its thread count, and the results must not on ``workers``.
    from ._threads import one_blas_thread

    with one_blas_thread():
        return [fn(*job) for job in jobs]


#: Below this many samples in all (about 2 MB of CSV) ``average_many`` with ``workers=None`` works here:
#: starting the workers (a fork server that imports the package, ~0.5 s of one core) would cost more
#: than it saves.  A lab file of 20,000 samples is about 1.2 MB of CSV.
PARALLEL_MIN_SAMPLES = 32_000


def average_many(
    items: Sequence[Any],
    *,
    min_periods: float = 2.0,
    workers: Optional[int] = None,
    on_each: Optional[Callable[[int, SegmentedMeasurement], None]] = None,
) -> tuple[list[Any], list[SegmentedMeasurement]]:
    """Every :class:`~bouc_wen_id.measurement.Measurement` of ``items`` cut into its steady segments and
    averaged (:func:`bouc_wen_id.signal.average_segments`), on local worker processes.

    What ``bouc-wen-id identify`` does to a folder of lab files before it identifies them.

    Parameters
    ----------
    items : sequence
        Measurements, and experiments that need no preparation (``Recording``, ``AveragedPeriod``), mixed.
    min_periods : float
        Shortest steady stretch kept, in periods.
    workers : int, optional
        Worker processes (at most the CPU count).  Default: one per usable core when the measurements hold
        at least ``PARALLEL_MIN_SAMPLES`` samples in all, else this process alone.  ``1``: this process.
    on_each : callable, optional
        Called as ``on_each(i, segmented)`` for the i-th measurement, in order, as soon as it is ready (a
        progress bar, a printed report).

    Returns
    -------
    experiments : list
        What :func:`bouc_wen_id.identify` takes: ``items`` in order, each measurement replaced by its
        averaged periods (one per steady segment).
    segmented : list of SegmentedMeasurement
        Per measurement, what was kept and dropped (``to_dict()`` is JSON-ready).  A measurement's name
        is its own, else ``"measurement <i>"``.

    Raises
    ------
    InsufficientDataError
        A measurement without a steady segment of at least ``min_periods`` periods (from
        :func:`~bouc_wen_id.signal.average_segments`), or no experiment at all.
    InvalidParameterError
        ``workers`` not in ``[1, os.cpu_count()]``.
    """
    from .measurement import Measurement

    measurements = [m for m in items if isinstance(m, Measurement)]
    jobs = [(m, min_periods, m.name or f"measurement {i}") for i, m in enumerate(measurements)]
    segmented: list[SegmentedMeasurement] = []
    for i, found in enumerate(_each_averaged(jobs, workers)):
        segmented.append(found)
        if on_each is not None:
            on_each(i, found)
    averaged = iter(segmented)
    out: list[Any] = []
    for item in items:
        out.extend(next(averaged).periods if isinstance(item, Measurement) else [item])
    if not out:
        raise InsufficientDataError(
            "no experiment: items is empty, or it holds only measurements without a steady segment of at "
            f"least min_periods = {min_periods:g} periods"
        )
    return out, segmented


def _each_averaged(jobs: Sequence[tuple[Measurement, float, str]], workers: Optional[int]) -> Any:
    """``_average_job(*job)`` of every job, in order: here, or on the pool (which, with the workers still
    starting, this process helps from the back)."""
    if workers is None:
        samples = sum(m.t.size for m, _, _ in jobs)
        workers = _pool.usable_cores() if samples >= PARALLEL_MIN_SAMPLES else 1
    workers = min(_pool.check_workers(workers), max(len(jobs), 1))
    if workers == 1:
        return (_average_job(*job) for job in jobs)
    return _pool.ordered(_pool.get_pool(workers), _average_job, jobs, here=True)


def _average_job(measurement: Measurement, min_periods: float, name: str) -> SegmentedMeasurement:
    """One measurement's steady segments, averaged (a task of the workers)."""
    from .signal import average_segments

    return average_segments(measurement, min_periods=min_periods, name=name)


def _on_dask(client: Any, split: Sequence[tuple[Sequence[Any], dict[str, Any]]], errors: str) -> list[Any]:
    _optional.require("distributed", "identify_many(client=...)")
    # pure=False: the jobs are not hashed (their arrays can be large) and every call runs.
    # The caller's budget travels with every task, as to the local workers.
    limits = _budget.get_budget()
    futures = [client.submit(_pool.call_within, limits, _run, (e, o, errors), pure=False) for e, o in split]
    return list(client.gather(futures))

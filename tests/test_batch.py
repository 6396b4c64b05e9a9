"""identify_many: a batch of independent identifications, serial, on local worker processes and on a Dask
LocalCluster, with results identical to one-by-one ``identify`` calls."""

from __future__ import annotations

import os
import warnings

import bouc_wen_id as bw
import pytest
from bouc_wen_id.batch import Job, identify_many
from bouc_wen_id.errors import InsufficientDataError, InvalidParameterError

#: A pool of two workers (as many as the CPUs allow: workers are capped at the CPU count).
POOLED = min(2, os.cpu_count() or 1)


@pytest.fixture(scope="module")
def recordings() -> list[bw.Recording]:
    plan = bw.demo_plan(samples_per_period=128, periods=6, settle_periods=10, seed=11)
    return bw.simulate(bw.demo_plant(), plan)


def _jobs(recs: list[bw.Recording]) -> list[Job]:
    # Four different joint fits: pairs of experiments, one with its own method.
    return [
        [recs[0], recs[1]],
        [recs[2], recs[3]],
        {"experiments": [recs[4], recs[5]], "method": "profile"},
        [recs[1], recs[6]],
    ]


def test_local_pool_is_identical_to_serial_and_to_identify(recordings: list[bw.Recording]) -> None:
    jobs = _jobs(recordings)
    serial = identify_many(jobs, workers=1)
    pooled = identify_many(jobs, workers=POOLED)
    one_by_one = [
        bw.identify([recordings[0], recordings[1]]),
        bw.identify([recordings[2], recordings[3]]),
        bw.identify([recordings[4], recordings[5]], method="profile"),
        bw.identify([recordings[1], recordings[6]]),
    ]
    assert [r.to_json() for r in serial] == [r.to_json() for r in one_by_one]  # type: ignore[union-attr]
    assert [r.to_json() for r in pooled] == [r.to_json() for r in serial]  # type: ignore[union-attr]
    assert serial[2].method == "profile" and serial[0].method == "refined"  # type: ignore[union-attr]


def test_errors_raise_or_stand_in_place(recordings: list[bw.Recording]) -> None:
    # method='refined' needs >= 2 averaged periods: a one-period recording is refused.
    short = bw.simulate(
        bw.demo_plant(), bw.demo_plan(samples_per_period=64, periods=1, settle_periods=5, seed=3)
    )[0]
    jobs = [[recordings[0]], [short]]
    with pytest.raises(InsufficientDataError):
        identify_many(jobs, workers=1)
    out = identify_many(jobs, workers=POOLED, errors="return")
    assert isinstance(out[1], InsufficientDataError)
    assert out[0].to_json() == bw.identify([recordings[0]]).to_json()  # type: ignore[union-attr]


def test_bad_batches_are_refused(recordings: list[bw.Recording]) -> None:
    assert identify_many([]) == []
    with pytest.raises(InvalidParameterError, match="workers"):
        identify_many([[recordings[0]]], workers=0)
    with pytest.raises(InvalidParameterError, match="experiments"):
        identify_many([{"method": "paper"}])
    with pytest.raises(InvalidParameterError, match="job 0"):
        identify_many([recordings[0]])  # type: ignore[list-item]
    with pytest.raises(InvalidParameterError, match="errors"):
        identify_many([[recordings[0]]], errors="ignore")  # type: ignore[arg-type]


def test_dask_local_cluster_is_identical_to_local(recordings: list[bw.Recording]) -> None:
    import distributed  # the test extra installs it: the Dask path is tested, not skipped

    jobs = _jobs(recordings)
    local = identify_many(jobs, workers=1)
    periods = [
        bw.average_measurement(bw.Measurement(r.t, r.u, r.y, nominal_frequency=r.frequency))[0]
        for r in recordings[:4]
    ]
    lab_jobs: list[Job] = [periods[:2], periods[2:]]
    with warnings.catch_warnings():
        # distributed's own start-up warnings (ports, resources) are not ours to fail on.
        warnings.simplefilter("ignore")
        with (
            distributed.LocalCluster(  # type: ignore[no-untyped-call]
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            distributed.Client(cluster) as client,  # type: ignore[no-untyped-call]
        ):
            remote = identify_many(jobs, client=client)
            # Averaged lab periods too: Dask hands their arrays over as buffers the core must not be
            # given as they are (a bug the pipeline bench found).
            averaged = identify_many(lab_jobs, client=client)
    assert [r.to_json() for r in remote] == [r.to_json() for r in local]  # type: ignore[union-attr]
    assert [r.to_json() for r in averaged] == [  # type: ignore[union-attr]
        r.to_json()  # type: ignore[union-attr]
        for r in identify_many(lab_jobs, workers=1)
    ]


@pytest.mark.skipif(not hasattr(os, "sched_getaffinity"), reason="no CPU affinity on this platform")
def test_a_pool_with_one_worker_per_cpu_pins_each_worker_to_one_cpu() -> None:
    from bouc_wen_id._pool import get_pool

    cpus = os.sched_getaffinity(0)
    pool = get_pool(len(cpus))
    seen = [pool.submit(os.sched_getaffinity, 0).result() for _ in range(4 * len(cpus))]
    assert all(len(s) == 1 and s <= cpus for s in seen), seen
    assert os.sched_getaffinity(0) == cpus  # the caller is not pinned


# --------------------------------------------------------------------------------------------------
# The pool (bouc_wen_id._pool): capped, rebuilt after a dead worker, the caller's budget in every worker
# --------------------------------------------------------------------------------------------------


def test_workers_beyond_the_cpu_count_are_refused_before_any_process_starts(
    recordings: list[bw.Recording],
) -> None:
    from bouc_wen_id import _pool

    before = dict(_pool._POOLS)
    for workers in (10**6, (os.cpu_count() or 1) + 1):
        with pytest.raises(InvalidParameterError, match=r"workers = \d+ is more than the \d+ CPU"):
            identify_many([[recordings[0]], [recordings[1]]], workers=workers)
    for bad in (0, -3, 1.5, True, "2"):
        with pytest.raises(InvalidParameterError, match="workers"):
            identify_many([[recordings[0]]], workers=bad)  # type: ignore[arg-type]
    assert _pool._POOLS == before  # no pool was started for a refused request


class _KillsItsWorker:
    """Unpickled in a worker process, it ends that process at once (a crash in native code, an OOM kill)."""

    def __reduce__(self) -> tuple[object, tuple[int]]:
        return (os._exit, (7,))


@pytest.mark.skipif(POOLED < 2, reason="needs a pool: the job would end this very process")
def test_a_pool_whose_worker_died_is_rebuilt_for_the_next_call(recordings: list[bw.Recording]) -> None:
    from concurrent.futures.process import BrokenProcessPool

    jobs = _jobs(recordings)
    first = identify_many(jobs, workers=POOLED)
    dying = [*jobs[:1], [_KillsItsWorker()], *jobs[1:]]
    with pytest.raises(BrokenProcessPool, match="worker process died"):
        identify_many(dying, workers=POOLED)
    # The next batch in this process starts new workers and gives the same results.
    again = identify_many(jobs, workers=POOLED)
    assert [r.to_json() for r in again] == [r.to_json() for r in first]  # type: ignore[union-attr]


def test_a_pool_found_broken_while_submitting_gets_the_same_named_error() -> None:
    """A worker can die before the last job is submitted: submit() then sees the broken pool first, and
    must raise the named error (not CPython's 'A child process terminated abruptly') and drop the pool."""
    from concurrent.futures import Executor, Future
    from concurrent.futures.process import BrokenProcessPool

    from bouc_wen_id import _pool

    class _Broken(Executor):
        def submit(self, fn: object, /, *args: object, **kwargs: object) -> Future[object]:  # type: ignore[override]
            raise BrokenProcessPool("A child process terminated abruptly, the process pool is not usable")

    broken = _Broken()
    _pool._POOLS[-7] = broken  # type: ignore[assignment]
    try:
        with pytest.raises(BrokenProcessPool, match="worker process died.*next call starts new workers"):
            list(_pool.ordered(broken, max, [(1, 2)], here=False))
        assert -7 not in _pool._POOLS
    finally:
        _pool._POOLS.pop(-7, None)


def test_the_callers_budget_applies_in_the_workers(recordings: list[bw.Recording]) -> None:
    jobs = _jobs(recordings)
    # identify's phase profile needs ~3e5 steps: refused under max_steps = 1000, serial or pooled.
    with bw.budget.budget(max_steps=1000):
        for workers in (1, POOLED):
            with pytest.raises(bw.BudgetExceededError, match="max_steps = 1000"):
                identify_many(jobs, workers=workers)
    # Outside the block the workers have the default budget again.
    assert all(isinstance(r, bw.IdentificationResult) for r in identify_many(jobs, workers=POOLED))


def test_average_many_is_average_segments_of_each_in_order(recordings: list[bw.Recording]) -> None:
    measurements = [
        bw.Measurement(r.t, r.u, r.y, nominal_frequency=r.frequency, name=f"m{i}")
        for i, r in enumerate(recordings[:3])
    ]
    items = [measurements[0], recordings[5], measurements[1], measurements[2]]
    seen: list[tuple[int, str]] = []
    for workers in (1, POOLED):
        seen.clear()
        experiments, segmented = bw.batch.average_many(
            items, workers=workers, on_each=lambda i, s: seen.append((i, s.name))
        )
        assert seen == [(0, "m0"), (1, "m1"), (2, "m2")]
        expected = [bw.signal.average_segments(m) for m in measurements]
        assert [s.to_dict() for s in segmented] == [e.to_dict() for e in expected]
        assert experiments[len(expected[0].periods)] is recordings[5]
        assert len(experiments) == 1 + sum(len(e.periods) for e in expected)
    # A measurement without a steady stretch is refused by average_segments, by name; nothing at all too.
    with pytest.raises(InsufficientDataError, match="1000 steady periods"):
        bw.batch.average_many(measurements[:1], min_periods=1000)
    with pytest.raises(InsufficientDataError, match="no experiment"):
        bw.batch.average_many([])


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads process states from /proc")
def test_stop_all_ends_busy_workers_at_once_and_the_next_pool_works(recordings: list[bw.Recording]) -> None:
    """What Ctrl-C and SIGTERM do to the command line's workers: no wait for their running tasks."""
    import time

    from bouc_wen_id import _pool

    workers = min(2, os.cpu_count() or 1)
    pool = _pool.get_pool(workers)
    busy = pool.submit(time.sleep, 60)
    pids = list(pool._processes)
    while not busy.running():
        time.sleep(0.01)
    t0 = time.monotonic()
    _pool.stop_all()
    assert time.monotonic() - t0 < 5
    deadline = time.monotonic() + 10
    while any(_alive(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(pid) for pid in pids)
    assert _pool.get_pool(workers) is not pool
    assert len(identify_many(_jobs(recordings), workers=workers)) == 4


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (dead, not yet reaped) counts as ended
        with open(f"/proc/{pid}/stat", encoding="ascii") as fh:
            return fh.read().split(") ")[-1][:1] != "Z"
    except OSError:
        return True

"""The generic time-domain pieces: TimeRecord's checks and the bounded Levenberg-Marquardt (issue #20)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from bouc_wen_id.errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    TimeAxisError,
)
from bouc_wen_id.timedomain import TimeRecord, as_time_records, check_memory, levenberg_marquardt

least_squares = pytest.importorskip("scipy.optimize").least_squares

Fun = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def _exp_problem(seed: int) -> tuple[np.ndarray, np.ndarray, Fun]:
    """y = sum a_k exp(-b_k t) + noise, two terms: a small, curved, well-posed problem."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 4.0, 60)
    a = rng.uniform(0.5, 2.0, 2)
    b = np.sort(rng.uniform(0.3, 3.0, 2)) * np.array([1.0, 2.5])
    y = a[0] * np.exp(-b[0] * t) + a[1] * np.exp(-b[1] * t) + 0.01 * rng.standard_normal(t.size)

    def fun(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        e0, e1 = np.exp(-p[1] * t), np.exp(-p[3] * t)
        r = p[0] * e0 + p[2] * e1 - y
        jac = np.stack([e0, -p[0] * t * e0, e1, -p[2] * t * e1], axis=1)
        return r, jac

    return t, np.concatenate([a[:1], b[:1], a[1:], b[1:]]), fun


@pytest.mark.parametrize("seed", range(6))
def test_lm_matches_scipy_trf_on_random_problems(seed: int) -> None:
    _, truth, fun = _exp_problem(seed)
    rng = np.random.default_rng(100 + seed)
    p0 = truth * rng.uniform(0.7, 1.4, truth.size)
    lo, hi = np.zeros(4), np.full(4, 20.0)
    ours = levenberg_marquardt(fun, p0, lo, hi, max_iter=200)
    ref = least_squares(
        lambda p: fun(p)[0],
        p0,
        jac=lambda p: fun(p)[1],
        bounds=(lo, hi),
        method="trf",
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
    )
    assert ours.converged, ours.reason
    assert ours.cost == pytest.approx(ref.cost, rel=1e-7)
    np.testing.assert_allclose(ours.p, ref.x, rtol=1e-4, atol=1e-7)
    # The covariance: sigma^2 (J^T J)^-1 at the optimum, as computed from scipy's Jacobian.
    s2 = 2 * ref.cost / (ref.fun.size - 4)
    np.testing.assert_allclose(ours.covariance, s2 * np.linalg.inv(ref.jac.T @ ref.jac), rtol=1e-3)


@pytest.mark.parametrize("seed", range(4))
def test_lm_stops_on_an_active_bound_like_trf(seed: int) -> None:
    _, truth, fun = _exp_problem(seed)
    # Hold the slow rate below its best value: the optimum of the box is on that bound.
    hi = np.full(4, 20.0)
    hi[1] = 0.8 * truth[1]
    lo = np.zeros(4)
    p0 = np.minimum(truth, hi * 0.99)
    ours = levenberg_marquardt(fun, p0, lo, hi, max_iter=300)
    ref = least_squares(
        lambda p: fun(p)[0],
        p0,
        jac=lambda p: fun(p)[1],
        bounds=(lo, hi),
        method="trf",
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
    )
    assert ours.reason == "converged_at_bound"
    assert ours.at_upper[1] and not ours.at_bound[[0, 2, 3]].any()
    assert ours.p[1] == hi[1]
    assert ours.cost == pytest.approx(ref.cost, rel=1e-7)
    np.testing.assert_allclose(ours.p, ref.x, rtol=1e-4)
    assert np.isnan(ours.covariance[1]).all() and np.isfinite(ours.covariance[0, 0])


def test_lm_budgets_and_cancellation_name_their_reason() -> None:
    _, truth, fun = _exp_problem(0)
    p0 = truth * 1.5
    assert levenberg_marquardt(fun, p0, max_iter=2).reason == "max_iter"
    assert levenberg_marquardt(fun, p0, max_iter=50, max_evaluations=3).reason == "max_evaluations"
    calls = []

    def stop() -> bool:
        calls.append(1)
        return len(calls) > 2

    out = levenberg_marquardt(fun, p0, max_iter=50, should_stop=stop)
    assert out.reason == "cancelled" and out.iterations == 2
    assert out.cost < 0.5 * float(np.sum(fun(p0)[0] ** 2))  # the best so far, not the start


def test_lm_refuses_bad_input() -> None:
    _, truth, fun = _exp_problem(1)
    with pytest.raises(NonFiniteError):
        levenberg_marquardt(fun, [np.nan, 1, 1, 1])
    with pytest.raises(InvalidParameterError):
        levenberg_marquardt(fun, truth, lower=np.ones(4), upper=np.ones(4))
    with pytest.raises(InvalidParameterError):
        levenberg_marquardt(fun, truth, lower=np.zeros(3))
    with pytest.raises(InvalidParameterError):
        levenberg_marquardt(fun, truth, max_iter=0)


def test_lm_does_not_modify_the_start() -> None:
    _, truth, fun = _exp_problem(2)
    p0 = truth * 1.2
    keep = p0.copy()
    levenberg_marquardt(fun, p0)
    np.testing.assert_array_equal(p0, keep)


def test_time_record_copies_and_freezes() -> None:
    t = np.arange(20) * 0.01
    u = np.sin(t)
    y = np.cos(t)
    rec = TimeRecord(t, u, y, name="a")
    u[0] = 99.0
    assert rec.u[0] == 0.0
    with pytest.raises(ValueError):
        rec.y[0] = 1.0
    assert rec.dt == pytest.approx(0.01) and len(rec) == 20
    assert len(as_time_records([(t, u, y), rec])) == 2
    assert as_time_records((t, u, y))[0].name == "record 0"


def test_time_record_names_bad_input() -> None:
    t = np.arange(20) * 0.01
    u = np.sin(t)
    with pytest.raises(NonFiniteError):
        TimeRecord(t, np.where(t > 0.1, np.nan, u), u)
    back = t.copy()
    back[5] = back[3]
    with pytest.raises(TimeAxisError, match="not strictly increasing"):
        TimeRecord(back, u, u)
    jitter = t.copy()
    jitter[5] += 0.004
    with pytest.raises(TimeAxisError, match="not uniformly sampled"):
        TimeRecord(jitter, u, u)
    with pytest.raises(InvalidParameterError, match="equal lengths"):
        TimeRecord(t, u[:-1], u)
    with pytest.raises(InsufficientDataError):
        TimeRecord(t[:4], u[:4], u[:4])
    rec = TimeRecord(t, u, u)
    check_memory(rec, 0.1)
    with pytest.raises(InsufficientDataError, match="memory"):
        check_memory(rec, 0.5)
    with pytest.raises(InvalidParameterError):
        as_time_records([])
    with pytest.raises(InvalidParameterError):
        as_time_records("abc")  # type: ignore[arg-type]

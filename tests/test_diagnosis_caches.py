"""The diagnosis's result caches (speed, issue 18 item 4) return what the uncached code returns, and never a
stale result for other inputs: the drift correction's mean-period simulation (:func:`drift._mean_period`,
content-keyed) and the selection's memo of ``fit_with`` per (model, term) (:func:`select.memo_fit_with`)."""

from __future__ import annotations

import importlib
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bouc_wen_id.diagnosis import drift, fitting, select
from bouc_wen_id.diagnosis.data import prepare

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def _case(seed: int) -> tuple[list[Any], list[Any], Any, int]:
    case = gen.make_case("library", "degradation", "", 30.0, seed)
    exps = prepare(case.recordings)
    s = fitting.scale_of(exps)
    sx = fitting.scaled(exps, s)
    substeps = fitting.substeps_for([e.ybar.size for e in sx])
    return exps, sx, fitting.fit_plain(exps, sx, s, substeps), substeps


@pytest.mark.parametrize("seed", [5, 17])
def test_mean_period_cache_equals_a_fresh_simulation_and_is_never_stale(seed: int) -> None:
    rng = np.random.default_rng(seed)
    beta, gamma = rng.uniform(0.4, 1.0), rng.uniform(-0.3, 0.3)
    hyst = (float(beta), float(gamma), float(rng.uniform(1.0, 2.0)))
    terms = (("offset", float(rng.normal(0, 0.1))),)
    plan = (float(rng.uniform(1.0, 8.0)), 2, 3, 64, 4)
    amp, phi = float(rng.uniform(0.5, 3.0)), float(rng.uniform(0.0, 6.0))
    dvs = [0.0, float(rng.uniform(0.01, 0.2))]
    drift._mean_period.cache_clear()
    first = [drift._mean_period(hyst, terms, amp, phi, plan, "degradation", dv) for dv in dvs]
    again = [drift._mean_period(hyst, terms, amp, phi, plan, "degradation", dv) for dv in dvs]
    assert drift._mean_period.cache_info().hits == 2
    fresh = [drift._mean_period.__wrapped__(hyst, terms, amp, phi, plan, "degradation", dv) for dv in dvs]
    for a, b, c in zip(first, again, fresh):
        assert np.array_equal(a, c) and np.array_equal(b, c)
        assert not a.flags.writeable  # a caller cannot spoil the cached array
    assert not np.allclose(first[0], first[1])  # the drift changes the loop: the comparison says something
    # Any other input is another simulation, not the cached one.
    moved = drift._mean_period(hyst, terms, amp, phi + 0.3, plan, "degradation", dvs[1])
    assert np.array_equal(
        moved, drift._mean_period.__wrapped__(hyst, terms, amp, phi + 0.3, plan, "degradation", dvs[1])
    )
    assert not np.allclose(moved, first[1])


def test_corrected_with_a_warm_cache_equals_a_cold_one() -> None:
    """The refinement's sequence of d at one fit (d = 0 from the cache after the first) gives the periods a
    cold cache gives at each d, and each d its own correction."""
    exps, sx, plain, substeps = _case(31)
    ds = [0.02, 0.05, 0.035]
    drift._mean_period.cache_clear()
    warm = [drift.corrected(exps, sx, plain, d, 1.0, substeps)[1] for d in ds]
    assert drift._mean_period.cache_info().hits >= len(ds) - 1
    for d, w in zip(ds, warm):
        drift._mean_period.cache_clear()
        cold = drift.corrected(exps, sx, plain, d, 1.0, substeps)[1]
        for a, b in zip(w, cold):
            assert np.array_equal(a.ybar, b.ybar)
    moved = [not np.array_equal(a.ybar, b.ybar) for a, b in zip(warm[0], sx)]
    assert any(moved)  # the correction did something
    assert not all(np.array_equal(a.ybar, b.ybar) for a, b in zip(warm[0], warm[1]))


def test_memo_of_fit_with_equals_fit_with_and_keys_by_model() -> None:
    exps, sx, plain, substeps = _case(44)
    memo = select.memo_fit_with(sx, substeps)
    a = memo(plain, "viscous")
    b = fitting.fit_with(sx, plain, "viscous", substeps)
    assert a is not None and b is not None
    assert a.cost == b.cost and np.array_equal(a.params.values, b.params.values)
    assert memo(plain, "viscous") is a  # the hit
    # Another model (another object, other values) is fitted anew, never handed the first model's fit.
    other = fitting.fit_from(sx, replace(plain.params, mu=plain.params.mu * 1.05), substeps, max_iter=2)
    assert other is not None
    c = memo(other, "viscous")
    d = fitting.fit_with(sx, other, "viscous", substeps)
    assert c is not None and d is not None and c is not a
    assert c.cost == d.cost and np.array_equal(c.params.values, d.params.values)
    assert memo(plain, "offset") is not a


def test_limits_profile_evaluates_each_value_once_and_returns_the_fresh_sizes() -> None:
    from bouc_wen_id.diagnosis.limits import _Profile

    _, sx, plain, substeps = _case(58)
    profile = _Profile(sx, plain, substeps)
    rng = np.random.default_rng(58)
    vs = [float(v) for v in rng.uniform(0.01, 0.3, 3)]
    first = [profile("viscous", v) for v in vs]
    assert len(profile.seen) == len(vs)
    assert [profile("viscous", v) for v in vs] == first and len(profile.seen) == len(vs)
    assert first == [profile._sizes("viscous", v) for v in vs]  # what an uncached evaluation gives
    assert len({f[1] for f in first}) == len(vs)  # each value its own size
    assert profile("stiffness", vs[0]) == profile._sizes("stiffness", vs[0]) != first[0]  # keyed by term too


@pytest.mark.parametrize("term", ["viscous", "stiffness@x", "coulomb", "sensor_lag"])
def test_limits_profile_takes_a_linear_terms_trace_from_one_evaluation(
    term: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A linear term's trace is its value times its regressor (limits._Profile._trace): one core evaluation
    per experiment for the whole search instead of one per value, sizes as the model's output differences give
    them (the reference: the same profile with no term taken as linear). A nonlinear term (the sensor lag)
    is still evaluated at every value."""
    from bouc_wen_id.diagnosis import limits

    _, sx, plain, substeps = _case(61)
    rng = np.random.default_rng(61)
    vs = [float(v) for v in rng.uniform(0.001, 0.3, 4)]
    calls: list[str] = []

    def counted(real: Any) -> Any:
        def call(*a: Any, **k: Any) -> Any:
            calls.append(term)
            return real(*a, **k)

        return call

    for mod in (limits, fitting):
        monkeypatch.setattr(mod, "augmented_output", counted(mod.augmented_output))
    profile = limits._Profile(sx, plain, substeps)
    calls.clear()
    fast = [profile(term, v) for v in vs]
    linear = term in fitting.LINEAR_TERMS
    assert len(calls) == (len(sx) if linear else len(sx) * len(vs))
    monkeypatch.setattr(limits, "LINEAR_TERMS", (), raising=False)
    reference = limits._Profile(sx, plain, substeps)
    calls.clear()
    slow = [reference(term, v) for v in vs]
    assert len(calls) == len(sx) * len(vs)  # the reference evaluates the model at every value
    for (lam, raw), (lam_ref, raw_ref) in zip(fast, slow):
        assert raw == pytest.approx(raw_ref, rel=1e-9) and lam == pytest.approx(lam_ref, rel=1e-6)
    assert len({f[1] for f in fast}) == len(vs) and min(f[0] for f in fast) > 0.0


@pytest.mark.parametrize("ages", [(0.0, 2.5, 7.25), (1.0, 0.0, 3.75)])
def test_corrected_with_shared_leads_and_threads_equals_one_simulation_per_lead(
    ages: tuple[float, ...],
) -> None:
    """A fractional unrecorded age's two whole lead counts from one record (the shorter lead's record is the
    longer one's prefix), the simulations on threads: the corrected periods are bit for bit those of one
    simulation per lead in turn (speed.SHARE_AGE_LEADS, speed.THREAD_DRIFT_SIMS)."""
    from bouc_wen_id.diagnosis import speed

    exps, sx, plain, substeps = _case(23)
    aged = [replace(e, age_periods=a) for e, a in zip(exps, ages * len(exps))]
    out = {}
    for fast in (True, False):
        speed.SHARE_AGE_LEADS = speed.THREAD_DRIFT_SIMS = fast
        drift._mean_period.cache_clear()
        try:
            out[fast] = drift.corrected(aged, sx, plain, 0.04, 1.0, substeps)[1]
        finally:
            speed.SHARE_AGE_LEADS = speed.THREAD_DRIFT_SIMS = True
    assert any(e.blocks >= 2 and a % 1 for e, a in zip(aged, ages * len(exps)))  # a fractional age is used
    for a, b in zip(out[True], out[False]):
        assert np.array_equal(a.ybar, b.ybar)
    young = drift.corrected(exps, sx, plain, 0.04, 1.0, substeps)[1]
    assert not all(np.array_equal(a.ybar, b.ybar) for a, b in zip(young, out[True]))  # the ages matter

"""The refinement's stall rule (``fit_augmented``'s ``stall``; docs/diagnosis-speed.md, session 46).

The diagnosis's fits stop once a window of LM iterations lowers the cost by little; the rule runs inside
one refinement, whose damping carries on across the windows (until session 46 each window was a refinement
of its own, restarting the damping). Every random number comes from ``np.random.default_rng(seed)``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.augmented import AugExperiment, AugFit, AugParams, fit_augmented
from bouc_wen_id.diagnosis import fitting
from bouc_wen_id.errors import InvalidParameterError

Backend = Literal["rust", "numpy"]


def _misfit(seed: int) -> tuple[list[AugExperiment], AugParams]:
    """Loops with a dashpot that the fitted plain model lacks (a fit that crawls, as the MR damper's do),
    and a start away from the plain model's best."""
    rng = np.random.default_rng(seed)
    exps, gains, phases = [], [], []
    for om in (1.0, 3.0):
        psi = float(rng.uniform(0.0, 2.0 * np.pi))
        y, _, _ = _core.augmented_output(
            32, 1.0, om, psi, ["viscous"], np.array([0.8, 0.2, 1.6, 0.05]), 0.9, 0.3, 8
        )
        exps.append(AugExperiment(y + 1e-3 * rng.standard_normal(32), 1.0, om, psi, 1e6))
        gains.append(rng.uniform(0.7, 1.1))
        phases.append(rng.uniform(0.1, 0.5))
    return exps, AugParams(0.6, 0.1, 2.2, (), np.zeros(0), np.array(gains), np.array(phases))


def _same(a: AugFit, b: AugFit) -> None:
    np.testing.assert_array_equal(a.params.shared, b.params.shared)
    np.testing.assert_array_equal(a.params.gains, b.params.gains)
    assert a.cost == b.cost and a.iterations == b.iterations


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_a_window_that_gains_little_stops_the_fit_at_its_end(backend: Backend) -> None:
    exps, start = _misfit(3)
    # rtol 1: any window lowers the cost by less than all of it, so the fit stops at the second window's end
    fit = fit_augmented(exps, start, max_iter=40, substeps=4, backend=backend, stall=(4, 1.0))
    assert (fit.stop, fit.converged, fit.iterations) == ("stall", True, 8)
    # ... at the point one uninterrupted run of 8 iterations reaches: the damping carried across the windows
    whole = fit_augmented(exps, start, max_iter=8, substeps=4, backend=backend)
    assert whole.stop == "max_iter"
    np.testing.assert_array_equal(fit.params.shared, whole.params.shared)
    np.testing.assert_array_equal(fit.params.gains, whole.params.gains)
    assert fit.cost == whole.cost


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_a_window_that_gains_enough_does_not_stop_the_fit(backend: Backend) -> None:
    exps, start = _misfit(4)
    plain = fit_augmented(exps, start, max_iter=12, substeps=4, backend=backend)
    assert plain.stop == "max_iter"  # still moving at 12: the rule at rtol 0 must not end it
    fit = fit_augmented(exps, start, max_iter=12, substeps=4, backend=backend, stall=(4, 0.0))
    assert fit.stop == "max_iter" and fit.iterations == 12
    np.testing.assert_array_equal(fit.params.shared, plain.params.shared)
    assert fit.cost == plain.cost


def test_the_core_and_the_reference_stall_alike() -> None:
    exps, start = _misfit(5)
    free = fit_augmented(exps, start, max_iter=200, substeps=4)
    r = fit_augmented(exps, start, max_iter=200, substeps=4, stall=(3, 1e-3))
    n = fit_augmented(exps, start, max_iter=200, substeps=4, backend="numpy", stall=(3, 1e-3))
    # The rule ends the fit before the core's own (a relative decrease of 1e-12 per step), in both cores
    assert r.stop == n.stop == "stall" and r.iterations == n.iterations < free.iterations
    np.testing.assert_allclose(r.params.shared, n.params.shared, rtol=1e-7)
    np.testing.assert_allclose(r.cost, n.cost, rtol=1e-9)
    # ... and short of the minimum by less than the window's rtol of the cost
    assert free.cost <= r.cost <= free.cost * (1 + 1e-3)


@pytest.mark.parametrize("backend", ["rust", "numpy"])
@pytest.mark.parametrize("stall", [(-1, 0.1), (5, -0.1), (5, float("nan")), (0, 0.0, -1.0)])
def test_a_bad_stall_rule_is_a_named_error(backend: Backend, stall: tuple[float, ...]) -> None:
    exps, start = _misfit(6)
    with pytest.raises(InvalidParameterError, match="stall"):
        fit_augmented(exps, start, max_iter=5, substeps=4, backend=backend, stall=stall)


def test_the_diagnosis_fit_is_one_refinement_with_the_stall_rule() -> None:
    exps, start = _misfit(7)
    got = fitting._fit_from(exps, start, 4, 200)
    dof = sum(e.ybar.size for e in exps) - 3 - 2 * len(exps)
    want = fit_augmented(
        exps,
        start,
        max_iter=200,
        substeps=4,
        stall=(fitting.FIT_CHUNK, fitting.STALL_CHI2 / dof, fitting.STEP_CHI2 / dof),
    )
    assert got is not None
    _same(got, want)


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_a_step_that_gains_little_where_gauss_newton_predicts_little_stops_the_fit(backend: Backend) -> None:
    exps, start = _misfit(5)
    free = fit_augmented(exps, start, max_iter=200, substeps=4, backend=backend)
    # step_rtol 1: every accepted step and every prediction is below the whole cost: the first one stops it
    first = fit_augmented(exps, start, max_iter=200, substeps=4, backend=backend, stall=(0, 0.0, 1.0))
    assert first.stop == "stall" and first.iterations < free.iterations
    capped = fit_augmented(exps, start, max_iter=first.iterations, substeps=4, backend=backend)
    np.testing.assert_array_equal(first.params.shared, capped.params.shared)
    # a small one stops it short of the minimum by no more than that fraction of the cost
    fit = fit_augmented(exps, start, max_iter=200, substeps=4, backend=backend, stall=(0, 0.0, 1e-5))
    assert fit.stop == "stall" and first.iterations < fit.iterations < free.iterations
    assert free.cost <= fit.cost <= free.cost * (1 + 1e-5)


def test_the_core_and_the_reference_stop_a_step_alike() -> None:
    exps, start = _misfit(5)
    r = fit_augmented(exps, start, max_iter=200, substeps=4, stall=(0, 0.0, 1e-5))
    n = fit_augmented(exps, start, max_iter=200, substeps=4, backend="numpy", stall=(0, 0.0, 1e-5))
    assert r.stop == n.stop == "stall" and r.iterations == n.iterations
    np.testing.assert_allclose(r.params.shared, n.params.shared, rtol=1e-7)

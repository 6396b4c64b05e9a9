"""Session 48's cuts of the LM iterations (docs/diagnosis-speed.md): a wide restart's screen (a fit whose cost
only ranks its starts) stops under the looser per-step rule ``SCREEN_STEP_CHI2``, a finish under
``STEP_CHI2``; the dry friction's width refits start from the fit at the nearest width already tried."""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np
from bouc_wen_id.augmented import AugExperiment, AugParams, fit_augmented
from bouc_wen_id.diagnosis import coulomb_width, fit_share, fitting
from test_lm_stall import _misfit  # loops with a dashpot the plain model lacks, from a start off its best


def _rule(exps: list[AugExperiment], step_chi2: float) -> tuple[float, float, float]:
    dof = sum(e.ybar.size for e in exps) - 3 - 2 * len(exps)
    return (fitting.FIT_CHUNK, fitting.STALL_CHI2 / dof, step_chi2 / dof)


def test_a_screen_runs_under_the_screen_rule_and_a_finish_under_the_full_one() -> None:
    exps, start = _misfit(11)
    assert fitting.SCREEN_STEP_CHI2 > fitting.STEP_CHI2
    got = fitting.screen(exps, start, 4)
    want = fit_augmented(
        exps, start, max_iter=fitting.SCREEN_ITER, substeps=4, stall=_rule(exps, fitting.SCREEN_STEP_CHI2)
    )
    full = fitting.fit_from(exps, start, 4, max_iter=fitting.SCREEN_ITER)
    strict = fit_augmented(
        exps, start, max_iter=fitting.SCREEN_ITER, substeps=4, stall=_rule(exps, fitting.STEP_CHI2)
    )
    assert got is not None and full is not None
    assert (got.cost, got.iterations) == (want.cost, want.iterations)
    assert (full.cost, full.iterations) == (strict.cost, strict.iterations)


def test_a_screen_and_a_full_fit_of_one_start_are_two_entries_of_the_refit_store() -> None:
    """Within one diagnosis (a fit_share scope) a fit of the same start and cap under the other stop is
    fitted, not taken from the store: the screen's looser end is never handed out as a finished fit."""
    exps, start = _misfit(12)
    # a rule at the whole cost stops a fit at its first accepted step: the two ends must differ
    loose = fitting.fit_from(exps, start, 4, max_iter=fitting.SCREEN_ITER, step_chi2=1e9)
    with fit_share.scope():
        first = fitting.fit_from(exps, start, 4, max_iter=fitting.SCREEN_ITER, step_chi2=1e9)
        second = fitting.fit_from(exps, start, 4, max_iter=fitting.SCREEN_ITER)
        again = fitting.fit_from(exps, start, 4, max_iter=fitting.SCREEN_ITER)
    assert loose is not None and first is not None and second is not None
    assert first.iterations == loose.iterations < second.iterations
    assert second.cost < first.cost
    assert again is second  # the same stop: the stored fit


def test_each_width_refit_starts_from_the_fit_at_the_nearest_width_tried() -> None:
    """Each refit's start carries the values fitted at the nearest width already tried (on log eps), not
    the candidate's own estimate at its width."""

    class _Fit:
        def __init__(self, eps: float, value: float) -> None:
            self.params = AugParams(0.5, 0.1, 1.5, ("coulomb",), np.r_[value], np.ones(1), np.zeros(1), eps)
            self.cost = (math.log(eps) - math.log(0.003)) ** 2

    given = _Fit(0.01, 0.1)
    fitted: dict[float, float] = {0.01: 0.1}
    starts: list[tuple[float, float]] = []

    def refit(start: AugParams) -> Any:
        starts.append((start.smoothing, float(start.values[0])))
        value = 1.0 + len(starts)  # each width's own fitted value, told apart by the order of the refits
        fitted[start.smoothing] = value
        return _Fit(start.smoothing, value)

    coulomb_width.profile(cast(Any, given), refit)
    assert len(starts) >= len(coulomb_width.WIDTHS)
    known = {0.01: 0.1}
    for eps, value in starts:
        nearest = min(known, key=lambda w: abs(math.log(w / eps)))
        assert value == known[nearest], (eps, value, known)
        known[eps] = fitted[eps]
    assert any(value != 0.1 for _, value in starts)  # not every refit from the candidate's estimate

"""The degradation test's gate (drift.with_drift_gate): a drift at all, at alpha / 2, as a union of the
blocks' omnibus chi-square and the directed test, each at alpha / 4 (issue 18; blind
``degradation:30:0:clipped``: the directed test at p adj 1e-15 refused by an omnibus chi-square of 701 on
651 dof, p = 0.085, and inertia on x named "explained" in the truth's place).
"""

from __future__ import annotations

import math

import pytest
from bouc_wen_id.diagnosis import drift
from bouc_wen_id.diagnosis.drift import DegradationTest

ALPHA = 0.05


def _test(cost0: float, dof0: int, p_adjusted: float) -> DegradationTest:
    return DegradationTest(
        term=drift.DEGRADATION,
        d=1e-3,
        value=1e-3,
        standard_error=1e-4,
        cost0=cost0,
        cost1=cost0 - 70.0,
        dof0=dof0,
        statistic=70.0,
        p_value=p_adjusted / 9,
        p_adjusted=p_adjusted,
        share=0.6,
        held_out_before=(2.0,),
        held_out_after=(1.0,),
        experiments=(0, 1, 2),
        passed=p_adjusted < ALPHA,
    )


def test_a_directed_test_far_past_its_level_opens_the_gate_the_omnibus_keeps_shut() -> None:
    """The blind case's numbers: omnibus p = 0.085, directed p adj = 1e-15: a drift is there."""
    gated = drift.with_drift_gate(_test(701.0, 651, 1e-15), ALPHA)
    assert gated.drift_p_value == pytest.approx(0.085, abs=0.005)
    assert gated.drift_present and gated.named


@pytest.mark.parametrize(("cost0", "p_adjusted"), [(690.0, 0.023), (651.0, 0.02)])
def test_neither_half_rejecting_keeps_the_gate_shut(cost0: float, p_adjusted: float) -> None:
    """The demo plant's noise (directed p adj = 0.023, omnibus p ~ 0.06-0.5): no drift, nothing named."""
    gated = drift.with_drift_gate(_test(cost0, 651, p_adjusted), ALPHA)
    assert gated.drift_p_value > 0.25 * ALPHA
    assert not gated.drift_present and not gated.named


def test_the_omnibus_half_alone_still_opens_it() -> None:
    """A drift spread over the blocks' harmonics (omnibus p < alpha / 4) opens the gate whatever the
    directed test says; its own test then decides on naming."""
    gated = drift.with_drift_gate(_test(800.0, 651, 0.04), ALPHA)
    assert gated.drift_p_value < 0.25 * ALPHA and gated.drift_present
    assert math.isfinite(gated.drift_p_value)


def test_experiments_degradation_explains_are_not_left_out_when_the_verdict_is_unexplained(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A 30x degradation (the bench's generator) whose own test names it, while something else leaves the
    steady verdict "unexplained" (here the status forced so; on the blind lab measurements it was a clipped
    input's misfit): the degrading experiments are not left out as "not settled". Before, the degradation
    moved to the partial terms, six of nine experiments were left out, and inertia on x was named from the
    three left."""
    import importlib
    import sys
    import warnings
    from pathlib import Path
    from typing import Any

    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import run

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
    gen: Any = importlib.import_module("generator")
    case = gen.make_case("library", "degradation", "", 30.0, 3)
    plain_classify = run.classify
    monkeypatch.setattr(
        run, "classify", lambda *a: "unexplained" if plain_classify(*a) != "adequate" else "adequate"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
    assert d.degradation is not None and d.degradation.named
    assert "left out (not settled" not in d.verdict, d.verdict
    assert not any("left out of the diagnosis" in n for n in d.notes)


def test_a_drift_degradation_explains_counts_for_its_own_space_in_the_partial_verdict() -> None:
    """The share that decides "explained in part" is at least the drift space's share when degradation's own
    test names it (the blind lab case: 27 % of the pooled excess, all of the drift space's): a steady misfit
    elsewhere no longer turns a degradation its test names into "unexplained"."""
    from bouc_wen_id.diagnosis import run

    deg = _test(5706.0, 1953, 1e-30)
    deg = DegradationTest(**{**deg.__dict__, "cost1": 1600.0})
    assert run._naming_share(0.27, deg, True) == pytest.approx(1.0)
    assert run._naming_share(0.27, deg, False) == pytest.approx(0.27)
    assert run._naming_share(0.27, None, True) == pytest.approx(0.27)
    assert run.classify(False, True, False, run._naming_share(0.27, deg, True)) == "partly explained"

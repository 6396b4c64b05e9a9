"""A drift said as a fact only at a strong level (review 43: "the period record drifts, and an output gain
drifting over each record ... (adjusted p = 0.044)" on periodic data). drift_said.py.

The block records are made here by hand (a gain drifting over each record at the 5 % margin, or well above
it, and Gaussian noise from a seeded generator a little above the weights' level), not by the library's
simulator; the trend test's findings are written here too.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from bouc_wen_id.diagnosis import drift as D
from bouc_wen_id.diagnosis import drift_clause, drift_said, gain_drift
from bouc_wen_id.diagnosis.locate import DriftFinding, Localisation


def _blocks(gain: float, seed: int) -> list[D.DriftData]:
    """Three experiments' block deviations (5 blocks, harmonics 0..3): ``gain t_b`` times each loop (a
    sensor's gain drifting), plus complex Gaussian noise of 0.06 per part where the weights (400) expect
    0.05: a drift chi-square a little above its dof, as a record with more scatter than its noise floor."""
    rng = np.random.default_rng(seed)
    out = []
    for i, (energy, level) in enumerate(((3.0, 4.0), (2.0, 3.0), (1.0, 1.5))):
        t = np.arange(5.0) - 2.0
        loop = np.array([0.0, level, 0.3 * level, 0.1 * level], dtype=np.complex128)
        jac = -0.5 * loop + np.array([0.0, 0.0, 1.5j, 0.8], dtype=np.complex128)
        noise = rng.standard_normal((5, 4)) + 1j * rng.standard_normal((5, 4))
        noise[:, 0] = noise[:, 0].real
        dev = gain * t[:, None] * loop[None, :] + 0.06 * noise
        w = np.full(5, 400.0)
        out.append(D.DriftData(i, dev, t, w, energy, jac, np.zeros(8), math.nan, jac_eta=jac, level=loop))
    return out


def _tested(gain: float, seed: int) -> D.DegradationTest:
    data = _blocks(gain, seed)
    test = D.degradation_test(data, 1.0, 0.05, 10)
    assert test is not None
    got = gain_drift.checked(test, data, 0.05, 10)
    assert got is not None and got.gain_alternative  # a gain drift fits it as well: the clause is said
    return got


def test_a_drift_at_the_five_percent_margin_is_said_as_a_possibility_with_its_p() -> None:
    got = _tested(-0.015, 2)
    assert 0.01 < got.p_adjusted < 0.05, got.p_adjusted  # the margin review 43 saw (0.044, 0.046)
    said = gain_drift.text(got)
    assert "the period record drifts" not in said, said  # main said it as a fact
    assert f"the period record may drift (degradation's test: adjusted p = {got.p_adjusted:.2g})" in said


@pytest.mark.parametrize("seed", range(3))
def test_a_strong_drift_is_still_said_as_a_fact(seed: int) -> None:
    got = _tested(-0.05, seed)
    assert got.p_adjusted < drift_said.FIRM
    assert gain_drift.text(got).startswith("; the period record drifts, and an output gain drifting"), got


def _loc(p: float, detected: bool) -> Localisation:
    found = (DriftFinding("recording 0", 16, -0.001, -3.2, 0.0, 0.0, p, 1.0),)
    return Localisation(0.0, 1, 0.5, (), (), (), math.nan, math.nan, found, detected)


def test_the_trend_clause_says_may_drift_short_of_the_strong_level() -> None:
    # One experiment, its trend test at p = 0.006: past its level (0.025), short of FIRM.
    said = drift_clause.clause(_loc(0.006, True), _loc(0.006, True), ())
    assert said == (
        "; the loop may drift from period to period (trend test: adjusted p = 0.006) (not modelled)"
    )
    strong = drift_clause.clause(_loc(1e-6, True), _loc(1e-6, True), ())
    assert strong == "; the loop drifts from period to period (not modelled)"
    assert drift_clause.clause(_loc(0.3, False), _loc(0.3, False), ()) == ""

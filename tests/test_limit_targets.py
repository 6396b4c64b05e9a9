"""The detection limits' targets (diagnosis/limits.py, ``test_targets``) against the test they are about.

The candidate's own test (select.f_test) divides its cost drop by the residual variance per dof floored at
the noise floor. Under coloured noise the residual away from the low harmonics is far below that floor
(chi2/dof 0.07-0.11 under AR(1) 0.8 noise on reviewer 36's generator), and before session 37 the limits
used the unfloored value: their 90 % value then passed its test in 0 of 32 draws. Here the drop at the
stated 90 % size is drawn by Monte-Carlo (a seeded noncentral chi2 with one dof, the noise at the term's
harmonics at the floor) and put through select.f_test itself.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from bouc_wen_id.diagnosis import limits, select


def _pass_rate(t: float, level: float, one_sided: bool, dof: int, s2_fit: float, draws: int = 4000) -> float:
    """Share of seeded draws of the drop of a term of unabsorbed size ``t`` whose test passes; the noise at
    the term's harmonics at the floor, or at the residual scale above it."""
    rng = np.random.default_rng(37)
    r = max(s2_fit, select.NOISE_FLOOR)
    drop = r * (rng.standard_normal(draws) + math.sqrt(t / r)) ** 2
    c1 = s2_fit * dof
    passed = 0
    for d in drop:
        _, p = select.f_test(c1 + float(d), c1, dof, boundary=one_sided)
        passed += bool(p < level)
    return passed / draws


@pytest.mark.parametrize("s2_fit", [0.07, 0.5, 1.0, 1.3])
@pytest.mark.parametrize("one_sided", [True, False])
def test_the_90_value_passes_the_test_it_is_about(s2_fit: float, one_sided: bool) -> None:
    level, dof = 0.025 / 16, 700
    thr, t90, s2 = limits.test_targets(level, one_sided, dof, s2_fit)
    assert s2 >= select.NOISE_FLOOR
    at90 = _pass_rate(t90, level, one_sided, dof, s2_fit)
    at50 = _pass_rate(thr, level, one_sided, dof, s2_fit)
    assert 0.87 <= at90 <= 0.93, at90
    assert 0.45 <= at50 <= 0.55, at50


def test_a_residual_below_the_floor_does_not_lower_the_targets() -> None:
    low = limits.test_targets(0.001, True, 700, 0.07)
    floor = limits.test_targets(0.001, True, 700, select.NOISE_FLOOR)
    assert low == floor


def test_the_share_gate_still_binds() -> None:
    thr, t90, _ = limits.test_targets(0.001, True, 700, 1.0, share_gate=1e4)
    assert thr == 1e4 and t90 > thr

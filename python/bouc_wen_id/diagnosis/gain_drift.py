"""The drift's rival reading: the output's gain drifting over each record (a sensor's gain with temperature).

The drift stage (drift.py) fits a degradation term to the period blocks' deviations from the mean period.
A sensor whose gain drifts over the record (``y`` times ``1 + g t``: a load cell warming up, an amplifier's
gain with temperature) moves them too, by ``g t_b`` times the whole recorded loop, its elastic part and its
height alike at every amplitude; degradation changes the loop's shape with the energy it has dissipated
(strength: the saturation level; stiffness: the loop at the gain ``|G| / eta``). Below saturation the two
are the same (a linear loop scaled), past it they differ in shape only, so nothing in the library told them
apart: review 36 (problem 2) had a gain drifting by -3 % over each record named "explained by: stiffness
degradation delta_eta = 0.004326 +- 0.000728" (6 se) on one noise draw and "degradation delta_nu = 0.00067
+- 5.2e-05" (13 se) with an invented unrecorded age on another.

Here the named term must fit the drift beyond a gain drift of each record: the drift column of each
experiment is ``t_b`` times its own mean loop, its rate free per experiment (a gain that drifts at its own
rate in each record: the most general drifting gain, a temperature that does not follow the record's
clock), and the term's partial F-test given those rates (1 df, one-sided, Bonferroni over the family as the
term's own test) must pass. When it fails, the record cannot tell the term from a drifting output gain: the
term is not named (``DegradationTest.gain_alternative``), the verdict says both readings (:func:`text`), and
the ages of age.py (strength differences between records, which a gain that differs between records gives
alike) are not fitted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

import numpy as np

from .drift import DegradationTest, DriftData, _inner
from .result import TERM_LABELS, Diagnosis
from .select import f_test

#: Kill switch (tests compare with and without).
ENABLED = True


def _sums(dd: DriftData, term: str) -> tuple[float, float, float, float, float, float]:
    """``(c0, a, A, b, B, C)`` of one experiment: the deviations' chi-square, the gain column's and the
    term's inner products with the deviations and each other (:func:`.drift._inner`, block-weighted)."""
    assert dd.level is not None
    gain = dd.t[:, None] * dd.level[None, :]
    reg = dd.energy * dd.t[:, None] * dd.column(term)[None, :]

    def dot(x: np.ndarray, y: np.ndarray) -> float:
        return float(np.dot(dd.w, _inner(x, y, dd.hw)))

    return dot(dd.dev, dd.dev), dot(dd.dev, gain), dot(gain, gain), dot(dd.dev, reg), dot(reg, reg), dot(gain, reg)


def checked(deg: Optional[DegradationTest], data: Sequence[DriftData], alpha: float, family: int) -> Optional[
    DegradationTest
]:
    """``deg`` with its test against a drifting output gain (module docstring); as it is when it does not
    pass its own test, or the blocks' mean loops were not formed."""
    if not ENABLED or deg is None or not deg.passed or not data or any(dd.level is None for dd in data):
        return deg
    sums = [_sums(dd, deg.term) for dd in data]
    gain_cost, num, den, rates = 0.0, 0.0, 0.0, []
    for c0, a, big_a, b, big_b, c in sums:
        if big_a > 0:
            gain_cost += c0 - a * a / big_a
            num += b - a * c / big_a
            den += big_b - c * c / big_a
            rates.append(a / big_a)
        else:
            gain_cost += c0
            num += b
            den += big_b
            rates.append(0.0)
    d = num / den if den > 0 else 0.0
    joint = gain_cost - d * num
    dof = deg.dof0 - len(data) - 1
    p = f_test(gain_cost, joint, dof, boundary=True)[1] if d > 0 else 1.0
    padj = min(1.0, p * family) if math.isfinite(p) else math.nan
    alternative = not (math.isfinite(padj) and padj < alpha)
    return replace(
        deg, gain_p_adjusted=padj, gain_cost=gain_cost, gain_rates=tuple(rates), gain_alternative=alternative
    )


def carried(deg: Optional[DegradationTest], tested: Optional[DegradationTest]) -> Optional[DegradationTest]:
    """``deg`` (a retest, drift_passes.py) with ``tested``'s gain-rival fields."""
    if deg is None or tested is None:
        return deg
    return replace(
        deg,
        gain_p_adjusted=tested.gain_p_adjusted,
        gain_cost=tested.gain_cost,
        gain_rates=tested.gain_rates,
        gain_alternative=tested.gain_alternative,
    )


#: What tells a drifting gain from degradation.
SEPARATING = (
    "a check of the sensor's calibration at the start and the end of a record, or experiments both below "
    "and well past saturation (a drifting gain scales the loop at every amplitude alike; degradation "
    "changes its shape with the energy dissipated)"
)


def text(deg: Optional[DegradationTest]) -> str:
    """The verdict's clause when a drifting gain fits the drift as well as the degradation term ('' else)."""
    if deg is None or not deg.gain_alternative or not deg.gain_rates:
        return ""
    term = TERM_LABELS.get(deg.term, deg.term)
    rates = [100.0 * r for r in deg.gain_rates]
    span = f"{min(rates):+.2g} to {max(rates):+.2g}" if len(rates) > 1 else f"{rates[0]:+.2g}"
    return (
        f"; the period record drifts, and an output gain drifting over each record ({span} % per period: a "
        f"sensor's gain, e.g. with temperature) fits the drift as well as {term} does ({term}'s test given "
        f"the gain drift: adjusted p = {deg.gain_p_adjusted:.2g}): {term} or a drifting gain, neither named; "
        f"{SEPARATING} would tell"
    )


def with_clause(d: Diagnosis) -> Diagnosis:
    """``d`` with :func:`text`'s clause after its verdict (once: a verdict led by the drift says it)."""
    said = text(d.degradation)
    if not said or "output gain drifting over each record" in d.verdict:
        return d
    return replace(d, verdict=d.verdict + said)


__all__ = ["ENABLED", "SEPARATING", "carried", "checked", "text", "with_clause"]

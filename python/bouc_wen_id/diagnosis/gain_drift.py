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

Here the named term must fit the drift beyond a gain drift: one column ``t_b`` times each record's own mean
loop, with ONE rate shared by every record (a gain scales the loop at every amplitude alike), on two clocks:
per period (the same relative change per period in every record) and per second (a temperature on the lab's
clock: each record's rate per period is the rate per second times its period). A rate free per record was
tried first and refused true degradation (review 34's strength-and-stiffness record, two amplitudes): it
absorbs the energy dependence (the high-amplitude records' loops fell 6 times faster per period than the low
ones'), which is degradation's own evidence and which no sensor gain shows. The term's partial F-test
given the gain drift (1 df; with the other drift term beside it, 2 df, both values >= 0; one-sided,
Bonferroni over the family as the term's own test and over the two looks) must pass on both clocks. When it
fails, the record cannot tell the term from a drifting output gain: the term is not named
(``DegradationTest.gain_alternative``), the verdict says both readings (:func:`text`), and the ages of
age.py (strength differences between records, which a gain that differs between records gives alike) are
not fitted. In a design whose records all dissipate about the same energy per period (one amplitude) the
two are nearly the same drift, and the verdict says so rather than choose.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from .drift import DegradationTest, DriftData, _inner
from .drift_said import drifts
from .result import TERM_LABELS, Diagnosis
from .select import f_test

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Kill switch (tests compare with and without).
ENABLED = True


def _normal(
    data: Sequence[DriftData], terms: Sequence[str], clock: Sequence[float]
) -> tuple[float, FloatArray, FloatArray]:
    """``(c0, M, v)``: the deviations' chi-square and the normal equations of the shared gain column (first;
    record i's at ``clock[i]`` per period: 1 for a rate per period, its period in seconds for a rate per
    second) and ``terms``' shared columns (:func:`.drift._inner`, block-weighted)."""
    k = 1 + len(terms)
    c0, mat, vec = 0.0, np.zeros((k, k)), np.zeros(k)
    for dd, tick in zip(data, clock):
        assert dd.level is not None
        cols = [tick * dd.t[:, None] * dd.level[None, :]]
        cols += [dd.energy * dd.t[:, None] * dd.column(t)[None, :] for t in terms]

        def dot(x: ComplexArray, y: ComplexArray, dd: DriftData = dd) -> float:
            return float(np.dot(dd.w, _inner(x, y, dd.hw)))

        c0 += dot(dd.dev, dd.dev)
        vec += [dot(dd.dev, c) for c in cols]
        mat += [[dot(c, q) for q in cols] for c in cols]
    return c0, mat, vec


def _given_gain(
    data: Sequence[DriftData], terms: Sequence[str], clock: Sequence[float]
) -> tuple[float, float, FloatArray, float]:
    """``(gain cost, joint cost, terms' values, gain rate)``: the drift chi-square with the shared gain
    drift alone and with ``terms``' columns beside it; the rate alone, per period (or second) of ``clock``."""
    c0, mat, vec = _normal(data, terms, clock)
    if not mat[0, 0] > 0:
        return c0, c0, np.zeros(len(terms)), 0.0
    rate = float(vec[0] / mat[0, 0])
    gain_cost = float(c0 - rate * vec[0])
    try:
        both = np.linalg.solve(mat, vec)
    except np.linalg.LinAlgError:
        return gain_cost, gain_cost, np.zeros(len(terms)), rate
    values: FloatArray = np.asarray(both[1:], dtype=np.float64)
    return gain_cost, c0 - float(np.dot(both, vec)), values, rate


def checked(
    deg: Optional[DegradationTest],
    data: Sequence[DriftData],
    alpha: float,
    family: int,
    seconds: Sequence[float] = (),
) -> Optional[DegradationTest]:
    """``deg`` with its test against a drifting output gain (module docstring); as it is when it does not
    pass its own test, or the blocks' mean loops were not formed. ``seconds``: each record's period (by
    :attr:`DriftData.index`) for the gain's rate per second; without it, only the rate per period.

    For each clock of the gain (per period, per second), the named term alone given the gain drift (1 df)
    and, when the other drift term was formed (``deg.rival``), both drift terms together given it (2 df,
    both values >= 0: a record where both degrade, review 34's case, may fit neither alone beyond a gain
    drift); the smaller p, doubled for the two looks, Bonferroni over the family. The term is not named
    when it fails given either clock's gain drift (that gain drift fits the record as well).
    """
    if not ENABLED or deg is None or not deg.passed or not data or any(dd.level is None for dd in data):
        return deg
    sets = [(deg.term,)] + ([(deg.term, deg.rival.term)] if deg.rival is not None else [])
    clocks = [[1.0] * len(data)]
    if seconds:
        clocks.append([float(seconds[dd.index]) for dd in data])
    worst: tuple[float, float, float, list[float]] = (-1.0, math.nan, 0.0, clocks[0])
    for clock in clocks:
        ps = []
        for terms in sets:
            gain_cost, joint, values, rate = _given_gain(data, terms, clock)
            if np.all(values >= 0) and np.any(values > 0):
                ps.append(f_test(gain_cost, joint, deg.dof0 - 1 - len(terms), True, len(terms))[1])
        ps = [p for p in ps if math.isfinite(p)]
        padj = min(1.0, min(ps) * family * len(sets)) if ps else 1.0
        if padj > worst[0]:
            worst = (padj, gain_cost, rate, clock)
    padj, gain_cost, rate, clock = worst
    rates = tuple(rate * c for c in clock)  # per period of each record
    return replace(
        deg, gain_p_adjusted=padj, gain_cost=gain_cost, gain_rates=rates, gain_alternative=not padj < alpha
    )


def carried(deg: DegradationTest, tested: DegradationTest) -> DegradationTest:
    """``deg`` (a retest, drift_passes.py) with ``tested``'s gain-rival fields."""
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
    """The verdict's clause when a drifting gain fits the drift as well as the degradation term ('' else);
    the drift itself said as a fact only at :data:`.drift_said.FIRM` (drift_said.py)."""
    if deg is None or not deg.gain_alternative or not deg.gain_rates:
        return ""
    term = TERM_LABELS.get(deg.term, deg.term)
    rates = [100.0 * r for r in deg.gain_rates]
    span = f"{min(rates):+.2g} to {max(rates):+.2g}" if len(rates) > 1 else f"{rates[0]:+.2g}"
    said = drifts("the period record", deg.p_adjusted, f"{term}'s test")  # "may drift" at a marginal p
    return (
        f"; {said}, and an output gain drifting over each record ({span} % per period: a "
        f"sensor's gain, e.g. with temperature) fits it as well as {term} does ({term}'s test given "
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

"""Degradation from the period-by-period record: the first-order drift model and its test (design.md 10.6).

The averaged period cannot see a slow strength degradation: to first order the mean loop is the steady loop
at the mean strength, which the plain fit absorbs into beta and gamma. The blocks of consecutive periods can.
With ``nu = 1 + delta_nu e`` and ``e`` growing by ``E_i`` (the fitted loop's area ``oint w dx``) per period
of experiment i, block b (mean period index ``p_b``) sees the steady loop at
``nu_b = nu_bar (1 + d E_i t_b)``, ``t_b = p_b - p_bar``, ``d = delta_nu / nu_bar``, and so deviates from
the mean period by

    D_ib = d E_i t_b J_i,    J_i = dy/d ln nu = beta dy/dbeta + gamma dy/dgamma (+ delta dy/ddelta),

the steady model's own Jacobian columns. Stiffness degradation (``eta = 1 + delta_eta e`` dividing the whole
rate) is the loop at the gain ``|G| / eta`` (the rate over eta is the rate of x / eta), so its column is

    D_ib = d_eta E_i t_b K_i,    K_i = dy/d ln eta = -g_i dy/dg_i,

the experiment's own gain column: it shifts the loop's phase and, below saturation, its amplitude, where
J_i changes its saturation level. Each column is fitted and tested alone; when both pass, the better is
named; the other is reported as an alternative when it explains nearly as much and its partial F-test
given the first fails (the record cannot tell them apart), and in the notes when that partial test passes
(both act; only the first is modelled) (``compare``). One shared ``d``: a one-parameter weighted linear least
squares
on the block deviations' harmonics 0..K, each block weighted by ``samples / sigma^2`` (sigma^2 from
neighbouring periods, which a slow drift does not inflate). The fit is in *drift space*, apart from the
steady F-tests of the other terms: the block deviations are orthogonal to the mean period.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit, AugParams, augmented_output
from ..terms import TERMS, Asymmetry, Degradation, Play, StiffnessDegradation
from . import speed
from .data import DiagExperiment
from .select import f_test

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
TWO_PI = 2.0 * math.pi

#: The code name of the term fitted here.
DEGRADATION = Degradation.kind
#: The code name of the stiffness degradation, fitted here beside it.
STIFFNESS_DEGRADATION = StiffnessDegradation.kind
#: The terms fitted in drift space.
DRIFT_TERMS = (DEGRADATION, STIFFNESS_DEGRADATION)
#: The terms kept when the hysteresis output w alone is needed (for the loop's energy): those shaping the
#: steady loop of a pure-sine x; the output terms are left out.
_HYSTERESIS_TERMS = (Asymmetry.kind, Play.kind)


@dataclass(frozen=True)
class DriftData:
    """One experiment's block deviations and the model's drift regressor, in scaled units."""

    index: int
    dev: ComplexArray  # (B, K + 1): block harmonics less their weighted mean
    t: FloatArray  # (B,) block centre less the weighted mean centre (periods)
    w: FloatArray  # (B,) samples / sigma^2 of each block
    energy: float  # E_i: the fitted loop's area per period (scaled units)
    jac: ComplexArray  # (K + 1,) harmonics of dy/d ln nu
    jac_grid: FloatArray  # dy/d ln nu on the averaged grid
    mean_age: float  # periods from the record's start to the middle of the averaged stretch (NaN: unknown)
    dropped: int = 0  # blocks left out: partial periods (see :func:`whole_blocks`)
    jac_eta: Optional[ComplexArray] = None  # (K + 1,) harmonics of dy/d ln eta = -g dy/dg (None: not formed)
    hw: Optional[FloatArray] = None  # (K + 1,) per-harmonic weight relative to w (None: white noise)
    #: (K + 1,) the blocks' weighted mean harmonics (the loop as recorded, scaled): an output gain drifting
    #: over the record moves block b by ``g t_b`` times it (gain_drift.py; None: not formed)
    level: Optional[ComplexArray] = None

    def column(self, term: str) -> ComplexArray:
        """The harmonics of the drift regressor of ``term`` (J_i for degradation, K_i for stiffness)."""
        if term == STIFFNESS_DEGRADATION:
            if self.jac_eta is None:
                raise ValueError("the stiffness-degradation column was not formed")
            return self.jac_eta
        return self.jac

    @property
    def dof(self) -> int:
        """Independent real components of the deviations: (B - 1) blocks of (2K + 1) each (2K when the DC
        has no weight: the period means were taken out as a wandering baseline, baseline.py)."""
        spent = self.hw is not None and self.hw[0] == 0.0
        return int((self.dev.shape[0] - 1) * (2 * self.dev.shape[1] - 1 - spent))


def _inner(a: ComplexArray, b: ComplexArray, hw: Optional[FloatArray] = None) -> FloatArray:
    """Per-row weighted inner product of harmonic rows: ``Re a_0 b_0* + 1/2 sum_k Re a_k b_k*``, each
    harmonic k times ``hw[k]`` when given (its noise level relative to the block weight's).

    By Parseval it is ``||y_a . y_b|| / P`` on the grid, so with ``samples / sigma^2`` in front it is the
    chi-square of the block average (white noise; ``hw`` makes it one for a coloured noise too).
    """
    prod = (a * np.conj(b)).real
    if hw is not None:
        prod = prod * hw
    out: FloatArray = prod[..., 0] + 0.5 * prod[..., 1:].sum(axis=-1)
    return out


def harmonic_weights(e: DiagExperiment, k: int) -> Optional[FloatArray]:
    """``noise_var / sigma_k^2`` for harmonics 0..k of ``e`` (None when its noise is white: one level).

    A coloured noise is weighed at each harmonic by its own level (``DiagExperiment.harmonic_var``), not
    by the largest one: with an AR(1) of phi = 0.99 the DC's level (about 250 times the per-sample variance)
    weighed the fundamental, where degradation acts (8 times), and the block chi-square of a null record sat
    at 0.2 of its degrees of freedom.
    """
    hv = e.harmonic_var
    if hv.size < k + 1 or not (e.noise_var > 0 and np.all(hv[: k + 1] > 0)):
        return None
    finite = hv[np.isfinite(hv)]  # the DC is infinite when the period means were taken out (baseline.py)
    if finite.size and e.noise_var > 2.0 * float(np.max(finite)):  # a floor raised it above every level
        return None
    out: FloatArray = e.noise_var / hv[: k + 1]
    return out


def harmonics(y: FloatArray, k: int) -> ComplexArray:
    """Harmonics 0..k of a period on a uniform grid, in the block record's convention."""
    spec = np.fft.rfft(y) / y.size
    out = spec[: k + 1].astype(np.complex128)
    out[1:] *= 2.0
    out[0] = out[0].real
    return out


def _at_strength(fit: AugFit, nu: float) -> AugParams:
    """``fit``'s model at strength ``nu``: beta, gamma (and the asymmetry delta) times nu."""
    par = fit.params
    vals = np.array(par.values, dtype=np.float64)
    if Asymmetry.kind in par.terms:
        vals[par.terms.index(Asymmetry.kind)] *= nu
    return replace(par, beta=par.beta * nu, gamma=par.gamma * nu, values=vals)


def regressor(
    e: AugExperiment, fit: AugFit, i: int, substeps: int, nu: float = 1.0
) -> tuple[FloatArray, float]:
    """``(J_i on the grid, E_i)`` at strength ``nu``: ``dy/dnu`` (per unit of the virgin strength) from
    the core's Jacobian at beta, gamma, delta times nu, and the loop's area ``oint w dx`` there.

    ``E_i`` is the rectangle rule over the grid of ``w dx/dtheta``, ``x = A cos(theta - phi)``, with ``w``
    the hysteresis output alone (the fitted asymmetry and play kept, the output terms left out): exact for
    a band-limited loop, second order at the reversals' kinks.
    """
    j, _, energy = regressors(e, fit, i, substeps, nu)
    return j, energy


def regressors(
    e: AugExperiment, fit: AugFit, i: int, substeps: int, nu: float = 1.0, eta: float = 1.0
) -> tuple[FloatArray, FloatArray, float]:
    """``(J_i, K_i, E_i)`` on the grid: :func:`regressor`'s two and the stiffness column
    ``K_i = dy/d ln eta = -g_i dy/dg_i`` (the loop at the gain ``g_i / eta``).

    At stiffness ``eta`` (relative to ``fit``'s, which is then the virgin one) the loop is at the gain
    ``g_i / eta`` and ``K_i = -(g_i / eta^2) dy/dg`` there: per unit of ``delta_eta`` itself.
    """
    par = fit.params
    strong = _at_strength(fit, nu)
    if eta != 1.0:
        gains = np.array(par.gains, dtype=np.float64)
        gains[i] /= eta
        strong = replace(strong, gains=gains)
    p = e.ybar.size
    ph = float(par.phases[i])
    out = augmented_output(e, strong, i, substeps=substeps, jacobian=True)
    jac = out.jacobian
    k_eta = -float(par.gains[i]) / eta**2 * out.own_jacobian[:, 0]
    j = par.beta * jac[:, 0] + par.gamma * jac[:, 1]
    if Asymmetry.kind in par.terms:
        k = par.terms.index(Asymmetry.kind)
        j = j + float(par.values[k]) * jac[:, 3 + k]
    w = augmented_output(e, strong.only(_HYSTERESIS_TERMS), i, substeps=substeps)
    theta = TWO_PI * np.arange(p) / p
    # e = int w dx along x itself: eta slows the loop's response to x (the loop at the gain g / eta), not
    # x, so the energy per period is the softened loop's w over the full travel A g. Over x / eta it was
    # E / eta, and d came out eta times too large (stiffness degradation 11 % high at 30x on the bench).
    a = e.amplitude * float(par.gains[i])
    energy = float(np.dot(w, -a * np.sin(theta - ph))) * TWO_PI / p
    return np.asarray(j, dtype=np.float64), np.asarray(k_eta, dtype=np.float64), energy


def drift_data(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    y_scale: float,
    substeps: int,
    strength: Optional[Sequence[float]] = None,
    stiffness: Optional[Sequence[float]] = None,
) -> list[DriftData]:
    """The experiments with at least two blocks, reduced for the drift fit (scaled by ``y_scale``).

    ``strength`` (per experiment, default 1) is each averaged loop's strength relative to ``fit``'s,
    ``stiffness`` its eta (the loop at the gain ``g / eta``).
    """
    out = []
    for i, (e, a) in enumerate(zip(exps, sx)):
        keep = whole_blocks(e)
        if keep.size < 2:
            continue
        k = e.block_coef.shape[1] - 1
        wts = e.block_samples[keep] / max(e.noise_var, np.finfo(float).tiny) * y_scale**2
        coef = e.block_coef[keep] / y_scale
        centre = e.block_center[keep]
        mean = (wts[:, None] * coef).sum(axis=0) / wts.sum()
        t = centre - float(np.dot(wts, centre) / wts.sum())
        nu = 1.0 if strength is None else float(strength[i])
        eta = 1.0 if stiffness is None else float(stiffness[i])
        j, k_eta, energy = regressors(a, fit, i, substeps, nu, eta)
        age = e.lead_periods + e.age_periods + float(np.dot(wts, centre) / wts.sum()) + 0.5
        dropped = e.blocks - keep.size
        out.append(
            DriftData(
                i,
                coef - mean,
                t,
                wts,
                energy,
                harmonics(j, k),
                j,
                age,
                dropped=dropped,
                jac_eta=harmonics(k_eta, k),
                hw=harmonic_weights(e, k),
                level=mean.astype(np.complex128),
            )
        )
    return out


#: A block with fewer samples per period it spans than this fraction of the median covers part of a period.
WHOLE_BLOCK_FRACTION = 0.9


def whole_blocks(e: DiagExperiment) -> NDArray[np.int64]:
    """Indices of ``e``'s blocks that hold whole periods with finite harmonics.

    A lab record's first block can start mid-period (166 of 401 samples on the MR damper's 1 A files): its
    harmonics by least squares over part of the cycle are ill-posed (coefficients of 1e11-1e13 against a
    loop of 1.9e3) and gave a drift chi-square of 1.4e26. Such a block is no averaged period: left out.
    The test is on samples per period the block spans (``block_periods``, when known): 12 periods cut into
    8 runs give blocks of 2 and of 1 period, all whole, and comparing raw block sizes with their median
    left the four single-period blocks out of every experiment.
    """
    if e.blocks < 2:
        return np.zeros(0, dtype=np.int64)
    n = e.block_samples
    if e.block_periods.size == n.size and np.all(e.block_periods > 0):
        n = n / e.block_periods
    ok = (n >= WHOLE_BLOCK_FRACTION * float(np.median(n))) & np.all(np.isfinite(e.block_coef), axis=1)
    return np.flatnonzero(ok).astype(np.int64)


def _sums(dd: DriftData, term: str = DEGRADATION) -> tuple[float, float, float]:
    """``(C0, num, den)`` of one experiment: ``C(d) = C0 - 2 d num + d^2 den`` (``term``'s column)."""
    reg = dd.energy * dd.t[:, None] * dd.column(term)[None, :]
    c0 = float(np.dot(dd.w, _inner(dd.dev, dd.dev, dd.hw)))
    num = float(np.dot(dd.w, _inner(dd.dev, reg, dd.hw)))
    den = float(np.dot(dd.w, _inner(reg, reg, dd.hw)))
    return c0, num, den


@dataclass(frozen=True)
class DegradationTest:
    """The degradation candidate tested in drift space (design.md 10.6).

    ``d`` (scaled) and ``value``/``standard_error`` (physical, 1/[y]^2) are the first-order estimate of
    ``delta_nu / nu_bar``; ``cost0``/``cost1`` the drift chi-square without and with it, ``dof0`` its
    degrees of freedom; the held-out costs are leave-one-experiment-out (d from the others).
    """

    d: float
    value: float
    standard_error: float
    cost0: float
    cost1: float
    dof0: int
    statistic: float
    p_value: float
    p_adjusted: float
    share: float
    held_out_before: tuple[float, ...]
    held_out_after: tuple[float, ...]
    experiments: tuple[int, ...]
    passed: bool
    #: d E_i per experiment (relative strength change per period), for the predicted drift.
    rate: tuple[float, ...] = ()
    #: Harmonics 0..K of J_i (scaled), per experiment in ``experiments`` (K_i for stiffness degradation).
    jac: tuple[ComplexArray, ...] = ()
    #: P(chi2(dof0) > cost0): the block deviations against no drift at all (NaN when not computed).
    drift_p_value: float = math.nan
    #: Whether the record drifts at all (the gate; False: the test is not a candidate, as a steady term is
    #: not tried on a plain model at the noise floor).
    drift_present: bool = True
    #: The drift term tested: degradation (of strength, nu) or stiffness degradation (eta).
    term: str = DEGRADATION
    #: The other drift term's test, when both were formed (:func:`compare`).
    rival: Optional[DegradationTest] = None
    #: Partial F-test p-value (Bonferroni) of the rival given this term; the rival is named beside it below
    #: alpha, else reported as an alternative when it explains nearly as much (``rival_alternative``).
    rival_p_adjusted: float = math.nan
    rival_alternative: bool = False
    #: Correlation of the two drift columns' estimates (the 2x2 normal matrix).
    correlation: float = math.nan
    #: The two-column fit (this term, then the rival), in the output's units (``value``'s), with its
    #: standard errors; () when it was not formed or left the admissible range (drift_pair.py says it).
    joint: tuple[float, ...] = ()
    joint_se: tuple[float, ...] = ()
    #: The unrecorded age (age.py) when adopted: per experiment, periods of its own drive before its
    #: record beyond the youngest one's, and the energy e dissipated in them (1/[y]^2 units' inverse:
    #: [y]^2); empty when the records are taken to start as declared.
    age_periods: tuple[float, ...] = ()
    age_energy: tuple[float, ...] = ()
    #: Per experiment, whether its age is determined (its standard error within ``age.AGE_SE_MAX``).
    age_determined: tuple[bool, ...] = ()
    #: P-value of the ages' F-test on the steady fit (m - 1 parameters; NaN when not tried).
    age_p_value: float = math.nan
    #: The verdict's clause of the adopted ages ('' when none; age.py).
    age_clause: str = ""
    #: The rival reading of the drift: the output's gain drifting over each record (gain_drift.py). The
    #: term's partial F-test given a gain drift of each record (Bonferroni over the family; NaN: not
    #: formed), the drift chi-square with the gain drift alone, and its rate per experiment (relative
    #: change per period).
    gain_p_adjusted: float = math.nan
    gain_cost: float = math.nan
    gain_rates: tuple[float, ...] = ()
    #: True when that test fails: a drifting output gain fits the drift as well, and the term is not named.
    gain_alternative: bool = False

    @property
    def held_out_improves(self) -> bool:
        return bool(self.held_out_after) and sum(self.held_out_after) < sum(self.held_out_before)

    @property
    def named(self) -> bool:
        return self.passed and self.drift_present and self.held_out_improves and not self.gain_alternative

    def accepted(self, held_out_test: bool) -> bool:
        """Named (held-out test on), or passing its own test (off); never when a drifting output gain fits
        the drift as well (gain_drift.py)."""
        return bool(self.named if held_out_test else self.passed and not self.gain_alternative)

    @property
    def held_out_nrmse_ratio(self) -> float:
        """Block-resolved held-out NRMSE, drift model over none: ``sqrt(sum C_j(d_-j) / sum C_j(0))``."""
        b = sum(self.held_out_before)
        return math.sqrt(sum(self.held_out_after) / b) if b > 0 else math.nan

    def to_dict(self) -> dict[str, Any]:
        out = {
            "term": self.term,
            TERMS[self.term].symbol: self.value,
            "standard_error": self.standard_error,
            "drift_cost_before": self.cost0,
            "drift_cost_after": self.cost1,
            "drift_dof": self.dof0,
            "F": self.statistic,
            "p_value": self.p_value,
            "p_adjusted": self.p_adjusted,
            "share_of_drift_excess": self.share,
            "held_out_cost_before": list(self.held_out_before),
            "held_out_cost_after": list(self.held_out_after),
            "held_out_improves": self.held_out_improves,
            "held_out_nrmse_ratio": self.held_out_nrmse_ratio,
            "experiments": list(self.experiments),
            "passed_in_sample": self.passed,
            "drift_p_value": None if not math.isfinite(self.drift_p_value) else self.drift_p_value,
            "drift_present": self.drift_present,
            "named": self.named,
        }
        if math.isfinite(self.age_p_value):
            out["unrecorded_age_p_value"] = self.age_p_value
            out["unrecorded_age_periods"] = list(self.age_periods)
            out["unrecorded_age_energy"] = list(self.age_energy)
            out["unrecorded_age_determined"] = list(self.age_determined)
        if math.isfinite(self.gain_p_adjusted):
            out["gain_drift_p_adjusted"] = self.gain_p_adjusted
            out["gain_drift_cost"] = self.gain_cost
            out["gain_drift_rates"] = list(self.gain_rates)
            out["gain_drift_alternative"] = self.gain_alternative
        if self.rival is not None:
            rival = self.rival.to_dict()
            rival.pop("rival", None)
            out["rival"] = rival
            out["rival_partial_p_adjusted"] = self.rival_p_adjusted
            out["rival_is_alternative"] = self.rival_alternative
            out["correlation"] = self.correlation
            if self.joint:
                out["joint"] = {t: v for t, v in zip((self.term, self.rival.term), self.joint)}
                out["joint_standard_error"] = list(self.joint_se)
        return out


#: Smallest share of the drift excess ``C0 - dof0`` the term must explain (as MATERIAL_SHARE in select).
DRIFT_MATERIAL_SHARE = 0.1


def degradation_test(
    data: Sequence[DriftData], y_scale: float, alpha: float, family: int, term: str = DEGRADATION
) -> Optional[DegradationTest]:
    """Fit the shared ``d`` and test it: nested F (1 df, one-sided: ``d >= 0`` is a boundary, halved as for
    tau and b), Bonferroni over ``family`` candidates, the share of the drift excess, and the held-out
    check (d from the other experiments predicts each one's block deviations better than no drift).
    None when no experiment has a block record.
    """
    if not data:
        return None
    sums = [_sums(dd, term) for dd in data]
    c0 = sum(s[0] for s in sums)
    num = sum(s[1] for s in sums)
    den = sum(s[2] for s in sums)
    dof0 = sum(dd.dof for dd in data)
    d = num / den if den > 0 else 0.0
    c1 = c0 - d * num
    dof1 = dof0 - 1
    if d > 0:
        stat, p = f_test(c0, c1, dof1, boundary=True)
    else:  # a strengthening loop is not degradation: the one-sided test does not pass
        stat, p = 0.0, 1.0
    padj = min(1.0, p * family) if math.isfinite(p) else math.nan
    excess = c0 - dof0
    share = (c0 - c1) / excess if excess > 0 else 0.0
    passed = bool(math.isfinite(padj) and padj < alpha and share >= DRIFT_MATERIAL_SHARE)
    hb, ha = [], []
    if len(data) >= 2:
        for cj, nj, dj in sums:
            rest = den - dj
            dm = max((num - nj) / rest, 0.0) if rest > 0 else 0.0
            hb.append(cj)
            ha.append(cj - 2.0 * dm * nj + dm * dm * dj)
    scale = c1 / dof1 if dof1 > 0 else math.nan
    se = math.sqrt(scale / den) if den > 0 and scale > 0 else math.nan
    return DegradationTest(
        d=d,
        value=d / y_scale**2,
        standard_error=se / y_scale**2,
        cost0=c0,
        cost1=c1,
        dof0=dof0,
        statistic=stat,
        p_value=p,
        p_adjusted=padj,
        share=share,
        held_out_before=tuple(hb),
        held_out_after=tuple(ha),
        experiments=tuple(dd.index for dd in data),
        passed=passed,
        rate=tuple(d * dd.energy for dd in data),
        jac=tuple(dd.column(term) for dd in data),
        term=term,
    )


def with_drift_gate(test: DegradationTest, alpha: float) -> DegradationTest:
    """``test`` gated on a drift being there at all, at ``alpha / 2`` (the other half is the per-experiment
    drift test's, in locate), as a union of two tests at ``alpha / 4`` each: the blocks' chi-square against
    no drift (``cost0`` on ``dof0``, an omnibus test of every block's every harmonic), or the directed test
    itself (its Bonferroni-adjusted p).

    Without the gate the one-parameter F-test names a degradation in the noise of a record that does not
    drift (the demo plant, nothing hidden: delta_nu = 1.0e-05 at p adj = 0.023 with the block chi-square
    at p = 0.06 and the plain model at p = 0.93: neither half rejects). The omnibus test alone spreads its
    power over hundreds of dof: a 30x degradation on lab measurements (blind ``degradation:30:0:clipped``,
    the three settled experiments) passed the directed test at p adj 1e-15 while the omnibus chi-square was
    701 on 651 dof (p = 0.085), and the truth was not named (inertia on x was, "explained").
    """
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    p = float(chdtrc(test.dof0, test.cost0)) if test.dof0 > 0 and math.isfinite(test.cost0) else math.nan
    omnibus = math.isfinite(p) and p < 0.25 * alpha
    directed = math.isfinite(test.p_adjusted) and test.p_adjusted < 0.25 * alpha
    return replace(test, drift_p_value=p, drift_present=bool(omnibus or directed))


#: The rival explains at least this share of the chosen drift term's improvement to be its alternative.
RIVAL_SHARE = 0.9


def compare(
    data: Sequence[DriftData], y_scale: float, alpha: float, family: int
) -> Optional[DegradationTest]:
    """Both drift terms tested, the one to name first (the other attached as its ``rival``).

    The chosen one is the named (else passed) test with the lower cost, or strength degradation when
    neither passes. The rival's partial F-test given it (the two-column fit, 1 df, one-sided, Bonferroni
    over ``family``) says whether the record needs both; when it does not and the rival alone explains at
    least ``RIVAL_SHARE`` of the chosen one's improvement, the two are alternatives the record cannot tell
    apart (their columns are nearly parallel: ``correlation``).
    """
    if not data:
        return None
    tests = [degradation_test(data, y_scale, alpha, family, term) for term in DRIFT_TERMS]
    nu, eta = tests
    assert nu is not None and eta is not None

    def rank(t: DegradationTest) -> tuple[int, int, float]:
        return (0 if t.named else 1, 0 if t.passed else 1, t.cost1)

    best, other = (nu, eta) if rank(nu) <= rank(eta) else (eta, nu)
    # The two-column fit: the normal matrix of the two regressors over every experiment.
    a = np.zeros((2, 2))
    r = np.zeros(2)
    for dd in data:
        regs = [dd.energy * dd.t[:, None] * dd.column(t)[None, :] for t in (best.term, other.term)]
        for m in range(2):
            r[m] += float(np.dot(dd.w, _inner(dd.dev, regs[m], dd.hw)))
            for n in range(2):
                a[m, n] += float(np.dot(dd.w, _inner(regs[m], regs[n], dd.hw)))
    corr = float(a[0, 1] / math.sqrt(a[0, 0] * a[1, 1])) if a[0, 0] > 0 and a[1, 1] > 0 else math.nan
    padj = math.nan
    joint: tuple[float, ...] = ()
    joint_se: tuple[float, ...] = ()
    try:
        both = np.linalg.solve(a, r)
    except np.linalg.LinAlgError:
        both = None
    if both is not None and both[1] > 0 and both[0] >= 0:
        c2 = best.cost0 - float(np.dot(both, r))
        stat, p = f_test(best.cost1, c2, best.dof0 - 2, boundary=True)
        padj = min(1.0, p * family) if math.isfinite(p) else math.nan
        joint, joint_se = _joint(both, a, c2, best.dof0 - 2, y_scale)
    elif both is not None:
        padj = 1.0
    gain_best = best.cost0 - best.cost1
    alternative = bool(
        best.passed
        and other.passed
        and not (math.isfinite(padj) and padj < alpha)
        and gain_best > 0
        and (other.cost0 - other.cost1) >= RIVAL_SHARE * gain_best
    )
    return replace(
        best,
        rival=other,
        rival_p_adjusted=padj,
        rival_alternative=alternative,
        correlation=corr,
        joint=joint,
        joint_se=joint_se,
    )


def _joint(
    both: Any, a: Any, cost: float, dof: int, y_scale: float
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The two-column fit's values and standard errors in the output's units (``degradation_test``'s
    scaling: the residual variance per dof times the inverse normal matrix)."""
    scale = cost / dof if dof > 0 else math.nan
    try:
        cov = np.linalg.inv(a) * scale
    except np.linalg.LinAlgError:
        return (), ()
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return (
        tuple(float(v) / y_scale**2 for v in both),
        tuple(float(v) / y_scale**2 for v in se),
    )


def predicted_deviation(dd: DriftData, d: float, term: str = DEGRADATION) -> ComplexArray:
    """The first-order drift model's block deviations ``d E_i t_b J_i`` (scaled harmonics, (B, K + 1); K_i
    for stiffness degradation)."""
    out: ComplexArray = d * dd.energy * dd.t[:, None] * dd.column(term)[None, :]
    return out


def strengths(m: int, data: Sequence[DriftData], d: float) -> list[float]:
    """``nu_bar_i = 1 + d E_i a_i`` per experiment (1 where the age or the block record is unknown)."""
    out = [1.0] * m
    for dd in data:
        if math.isfinite(dd.mean_age):
            out[dd.index] = 1.0 + max(d, 0.0) * dd.energy * dd.mean_age
    return out


def corrected(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    d: float,
    y_scale: float,
    substeps: int,
    term: str = DEGRADATION,
) -> tuple[list[DiagExperiment], list[AugExperiment]]:
    """The averaged periods brought back to the virgin strength (design.md 10.6); ``term`` the drift term
    simulated (strength degradation, or stiffness degradation: the virgin stiffness).

    Each experiment's averaged loop is not the steady loop at one strength: the strength differs between
    experiments (each dissipates at its own rate from the virgin state at the start of its record, so
    different amplitudes see different mean strengths, which shared beta and gamma cannot follow), it
    spreads over the record, and it rises within each period (the two branches of a period see different
    strengths: even harmonics). All three are in the time-domain simulation of the fitted hysteresis at
    ``delta_nu = d`` (``simulate`` with the Degradation term, driven by the fitted latent
    ``x = A cos(omega t - phi)`` from rest through the record's settling periods), averaged over the
    recorded periods; its difference from the same simulation at ``d = 0`` is taken off the data.
    Experiments of unknown age (no record) are left as they are.
    """
    de, ds = list(exps), list(sx)
    par = fit.params
    hysteresis = (float(par.beta), float(par.gamma), float(par.mu))
    terms = tuple((t, float(v)) for t, v in zip(par.terms, par.values) if t in _HYSTERESIS_TERMS)
    sim = _mean_period if speed.CACHE_DRIFT_LOOPS else _mean_period.__wrapped__
    jobs: dict[int, list[tuple[Any, ...]]] = {}
    for i, (e, a) in enumerate(zip(exps, sx)):
        if e.blocks < 2 or not math.isfinite(e.lead_periods):
            continue
        om = a.frequency  # rad/s
        phi = float(np.mod(par.phases[i], TWO_PI))
        amp = float(a.amplitude * par.gains[i])
        plans = _plans(e, (om, 0, recorded_periods(e), a.ybar.size, max(substeps, SIM_SUBSTEPS)))
        jobs[i] = [
            (hysteresis, terms, amp, phi, plan, term, dv) for plan, _ in plans for dv in (max(d, 0.0), 0.0)
        ]
    means = _run_all(sim, [job for js in jobs.values() for job in js])
    for i, js in jobs.items():
        e, a = exps[i], sx[i]
        shift = np.zeros(a.ybar.size)
        for k, (_, shares) in enumerate(_plans(e, js[0][4])):
            with_d, without = means[js[2 * k]], means[js[2 * k + 1]]
            for row, share in enumerate(shares):
                shift = shift + share * (with_d[row] - without[row])
        de[i] = replace(e, ybar=e.ybar - shift * y_scale)
        ds[i] = replace(a, ybar=np.ascontiguousarray(a.ybar - shift))
    return de, ds


def _plans(
    e: DiagExperiment, plan: tuple[float, int, int, int, int]
) -> list[tuple[tuple[float, int, int, int, int, int], tuple[float, ...]]]:
    """The simulations :func:`corrected` runs for ``e`` (``plan`` with its lead set; only its lead is
    replaced), each with the shares of its consecutive leads: a fractional age's two whole counts differ by
    one period, and the record simulated from rest through the longer lead holds the shorter one's record
    as its prefix (the same drive on the same time grid), so one simulation with one extra period gives
    both (:data:`speed.SHARE_AGE_LEADS`; off, one simulation per lead)."""
    om, _, n, p, sub = plan[:5]
    leads = _leads(e)
    if speed.SHARE_AGE_LEADS and len(leads) == 2 and leads[1][0] == leads[0][0] + 1:
        return [((om, leads[0][0], n, p, sub, 1), (leads[0][1], leads[1][1]))]
    return [((om, lead, n, p, sub, 0), (share,)) for lead, share in leads]


def _run_all(sim: Any, jobs: list[tuple[Any, ...]]) -> dict[tuple[Any, ...], FloatArray]:
    """``sim(*job)`` for every distinct job, on up to one thread per core (each simulation runs in the Rust
    core with the interpreter's lock released; the results do not depend on the scheduling) when
    :data:`speed.THREAD_DRIFT_SIMS`."""
    todo = list(dict.fromkeys(jobs))
    workers = min(len(todo), os.cpu_count() or 1) if speed.THREAD_DRIFT_SIMS else 1
    if workers <= 1:
        return {job: sim(*job) for job in todo}
    pool = ThreadPoolExecutor(max_workers=workers)
    try:
        futures = [pool.submit(sim, *job) for job in todo]
        # Wait in short slices: the kernel may hand Ctrl-C to a worker thread, and then a main thread
        # blocked without a timeout would not run Python's handler until every simulation ended.
        while not all(f.done() for f in futures):
            wait(futures, timeout=0.05)
        out = {job: f.result() for job, f in zip(todo, futures)}
    except BaseException:
        # Ctrl-C (or an error) reaches the caller now: the queued simulations are dropped, and the ones
        # running (a signal does not reach a worker thread's core call) finish in the background, not
        # waited for here (the pool's exit used to wait for them: Ctrl-C took 1.6 s instead of 0.5 s).
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return out


def _leads(e: DiagExperiment) -> list[tuple[int, float]]:
    """Whole periods simulated before the record, with their shares: the declared settling
    (``lead_periods``, rounded) plus the unrecorded age (``age_periods``, fractional: the two whole
    counts around it, weighted linearly)."""
    base = max(int(round(e.lead_periods)), 0)
    age = max(float(e.age_periods), 0.0)
    whole = int(math.floor(age))
    frac = age - whole
    if frac < 1e-6:
        return [(base + whole, 1.0)]
    return [(base + whole, 1.0 - frac), (base + whole + 1, frac)]


def recorded_periods(e: DiagExperiment) -> int:
    """The periods the averaged period was taken over: a recording's ``periods``; a lab experiment's whole
    periods of its stretch (its per-period record, ``h1``), not its ``periods``, which is the averaging's
    weight (samples over the grid's points: 194 for 23 cycles of 89 points at 750 samples a cycle).

    :func:`corrected` simulated that weight as cycles: the lab correction aged each loop 2-9 times too long,
    fitted worse than the periods as recorded, and was dropped, so a lab degradation's averaged loops stayed
    at their own strengths and the steady fit left "unexplained structure" (blind bench, fixed-rate
    degradation: 19-23 % of the excess explained).
    """
    n = int(round(e.periods))
    if e.h1.size > 1:  # a recording's h1 has one entry per period: the same number
        n = min(n, int(e.h1.size)) if n > 0 else int(e.h1.size)
    return max(n, 1)


#: RK4 steps per sample, at least, of the record's simulation in :func:`corrected`.
SIM_SUBSTEPS = 4


def simulated_periods(
    hysteresis: tuple[float, float, float],
    terms: tuple[tuple[str, float], ...],
    amp: float,
    phi: float,
    plan: tuple[float, int, int, int, int],
    term: str,
    dv: float,
) -> FloatArray:
    """The recorded periods, one row each (``(periods, samples per period)``), of the fitted hysteresis
    (``(beta, gamma, mu)`` and ``terms``) at drift ``term = dv``, driven by ``x = amp cos(omega t - phi)``
    from rest; ``plan`` is ``(omega, settle periods, periods, samples per period, substeps)``."""
    from ..model import BoucWen, SinePlan, TransferFunction, WienerPlant
    from ..simulation import simulate
    from ..terms import term_from_dict

    om, lead, n, p, sub = plan
    # The fitted latent x = A cos(omega t - phi): a pure gain A and a delay phi / omega on a unit sine.
    linear = TransferFunction([amp], [1.0], phi / om)
    sine = SinePlan(
        [om], [1.0], settle_periods=lead, periods=n, samples_per_period=p, substeps=sub, noise_sd=0.0
    )
    own = tuple(term_from_dict({"kind": t, TERMS[t].symbol: v}) for t, v in terms)
    drift = term_from_dict({"kind": term, TERMS[term].symbol: dv})
    (rec,) = simulate(WienerPlant(linear, BoucWen(*hysteresis), terms=(*own, drift)), sine)
    assert rec.w is not None
    out: FloatArray = np.asarray(rec.w, dtype=np.float64)[lead * p :].reshape(n, p)
    return out


@lru_cache(maxsize=128)
def _mean_period(
    hysteresis: tuple[float, float, float],
    terms: tuple[tuple[str, float], ...],
    amp: float,
    phi: float,
    plan: tuple[float, int, int, int, int] | tuple[float, int, int, int, int, int],
    term: str,
    dv: float,
) -> FloatArray:
    """The recorded periods' mean of :func:`simulated_periods`; with a sixth entry ``extra`` in ``plan``,
    one row per lead ``lead, ..., lead + extra`` (shape ``(extra + 1, samples per period)``: the mean of the
    ``periods`` periods after each, from one simulation of ``extra`` more periods). Cached on these values
    (every input of the simulation, so a hit is the same simulation): :func:`corrected`'s d = 0 loop is
    the same at every d the refinement tries (docs/diagnosis-speed.md). Read-only."""
    om, lead, n, p, sub = plan[:5]
    if len(plan) == 5:
        out: FloatArray = simulated_periods(hysteresis, terms, amp, phi, plan[:5], term, dv).mean(axis=0)
    else:
        extra = int(plan[5])
        rows = simulated_periods(hysteresis, terms, amp, phi, (om, lead, n + extra, p, sub), term, dv)
        out = np.stack([rows[k : k + n].mean(axis=0) for k in range(extra + 1)])
    out.setflags(write=False)
    return out


def detrended(exps: Sequence[DiagExperiment], test: DegradationTest, y_scale: float) -> list[DiagExperiment]:
    """The experiments with the fitted drift taken out of their per-period DC and fundamental.

    For the "after" localisation: period p of experiment i moves by ``d E_i (p - p_bar) J_i``.
    """
    out = list(exps)
    for i, rate, jac in zip(test.experiments, test.rate, test.jac):
        e = exps[i]
        n = e.h1.size
        if n < 2:
            continue
        t = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
        shift = rate * t * y_scale
        out[i] = replace(e, dc=e.dc - shift * jac[0].real, h1=e.h1 - shift * jac[1])
    return out


__all__ = [
    "DEGRADATION",
    "STIFFNESS_DEGRADATION",
    "DRIFT_TERMS",
    "DegradationTest",
    "compare",
    "regressors",
    "DriftData",
    "drift_data",
    "detrended",
    "corrected",
    "recorded_periods",
    "simulated_periods",
    "strengths",
    "harmonics",
    "predicted_deviation",
    "regressor",
    "degradation_test",
]

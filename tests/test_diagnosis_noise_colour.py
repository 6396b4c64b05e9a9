"""The diagnosis under noise that is not white (benches/diagnosis_designs.py, issue 18: "test every claim on
data made another way ... other noise").

Every test of the diagnosis weighs the samples of an experiment with one variance, the per-sample variance
from neighbouring periods: valid for white noise. An AR(1) output noise (phi = 0.8) carries 8.6 times that
variance at the fundamental of a 128-sample period, where the terms act, so their F-tests named terms on
null records. ``data.noise_colour`` measures the noise at the low harmonics from the period-to-period spread
(about a quadratic trend, so a drift does not count) and the F-test never scales a cost difference by a
residual variance below the noise floor.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.data import (
    COLOUR_BAND,
    FEW_COLOUR_ALPHA,
    cross_period_inflation,
    noise_colour,
)
from bouc_wen_id.diagnosis.select import f_test

P = 128


def _ar1(rng: np.random.Generator, n: int, phi: float) -> Any:
    z = rng.normal(0.0, math.sqrt(1.0 - phi * phi), n)
    e = np.empty(n)
    e[0] = rng.normal()
    for k in range(1, n):
        e[k] = phi * e[k - 1] + z[k]
    return e


def _white_var(rows: Any) -> float:
    return float(np.mean(np.diff(rows, axis=0) ** 2)) / 2.0


@pytest.mark.parametrize("periods", [16, 64])
def test_white_noise_keeps_its_per_sample_variance(periods: int) -> None:
    rng = np.random.default_rng([periods, 1])
    for _ in range(20):
        rows = rng.normal(0.0, 0.3, (periods, P))
        v = _white_var(rows)
        assert noise_colour(rows, v, P * (periods - 1)) == (v, P * (periods - 1), (0, 0))


def _low_harmonic_level(phi: float) -> float:
    """AR(1)'s level at the fundamental of a P-sample period over its per-sample variance."""
    return float((1.0 - phi * phi) / abs(1.0 - phi * np.exp(-2j * np.pi / P)) ** 2)


@pytest.mark.parametrize("periods", [3, 4, 5])
def test_white_noise_at_few_periods_is_called_coloured_at_most_at_the_checks_level(periods: int) -> None:
    # With few periods the colour check errs towards colour (FEW_COLOUR_ALPHA), never more often than that.
    from scipy.stats import binom  # type: ignore[import-untyped]

    rng = np.random.default_rng([periods, 2])
    draws = 200
    coloured = 0
    for _ in range(draws):
        rows = rng.normal(0.0, 0.3, (periods, P))
        v = _white_var(rows)
        var, dof, band = noise_colour(rows, v, P * (periods - 1))
        coloured += (var, dof, band) != (v, P * (periods - 1), (0, 0))
    assert coloured <= binom.ppf(0.999, draws, FEW_COLOUR_ALPHA)


@pytest.mark.parametrize("periods", [3, 5])
def test_ar_noise_at_few_periods_sets_the_floor_at_its_low_harmonic_level(periods: int) -> None:
    # Review 34: 3 averaged periods under AR(0.5) noise (3 times the per-sample level at the low harmonics)
    # named terms on 4 of 20 null seeds: with 3 periods the floor was the per-sample level whatever the
    # colour, and with 5 the colour check (at 1e-3 on 4 dof per harmonic) missed the colour in 4 of 10.
    rng = np.random.default_rng([periods, 3])
    phi, draws = 0.5, 200
    level = _low_harmonic_level(phi)
    low = 0
    for _ in range(draws):
        rows = _ar1(rng, periods * P, phi).reshape(periods, P)
        v = _white_var(rows)
        var, dof, _ = noise_colour(rows, v, P * (periods - 1))
        low += var < 0.6 * level * v
        assert dof < P * (periods - 1) or var == v
    # A floor below 0.6 of the low harmonics' level (the gate's F-tests then read noise as a 1.7-fold
    # effect) in at most 5 % of the records.
    assert low <= 0.05 * draws


def test_ar1_noise_is_found_at_the_low_harmonics() -> None:
    rng = np.random.default_rng(7)
    rows = _ar1(rng, 16 * P, 0.8).reshape(16, P)
    v = _white_var(rows)
    var, dof, band = noise_colour(rows, v, P * 15)
    # phi = 0.8: (1 - phi^2) / |1 - phi e^{-i w}|^2 = 8.6 at the fundamental, 9 at DC.
    assert 5.0 < var / v < 13.0
    assert band[0] == 0 and band[1] - band[0] + 1 <= COLOUR_BAND
    assert dof < P * 15


def test_a_drift_is_no_colour() -> None:
    """A loop drifting by 20 noise sd over the record (a degradation, a drifting centre) is taken out by the
    quadratic trend: white noise stays white. A centre that settles faster (an exponential over 4 periods)
    is not a quadratic: it is measured at the DC, as a wander the record cannot tell from noise correlated
    across periods (the DC alone is a band since the phi = 0.99 nulls), and only there (the fundamental's
    drift still is no colour)."""
    rng = np.random.default_rng(11)
    n = 16
    th = 2 * math.pi * np.arange(P) / P
    k = np.arange(n)[:, None]
    drift = 0.2 * (k / n) * np.cos(th)[None, :] + 0.1 * (k / n) ** 2
    rows = drift + rng.normal(0.0, 0.01, (n, P))
    v = _white_var(rows)
    assert noise_colour(rows, v, P * (n - 1)) == (v, P * (n - 1), (0, 0))
    settling = rows + 0.05 * np.exp(-k / 4.0)
    var, _, band = noise_colour(settling, _white_var(settling), P * (n - 1))
    assert band == (0, 0) and var > 10 * _white_var(settling)


def _pink(rng: np.random.Generator, n: int) -> Any:
    """1/f noise of unit sd, shaped in the frequency domain (another way than an AR recursion)."""
    f = np.fft.rfftfreq(n)
    amp = np.zeros(f.size)
    amp[1:] = 1.0 / np.sqrt(f[1:])
    x = np.fft.irfft(amp * (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)), n)
    return x / x.std()


NOISES: dict[str, Any] = {
    "white": lambda rng, n: rng.normal(size=n),
    "ar1 0.99": lambda rng, n: _ar1(rng, n, 0.99),
    "ar1 0.8": lambda rng, n: _ar1(rng, n, 0.8),
    "pink": _pink,
    # an ADC of 0.5 noise sd (the MR damper's force is quantised)
    "quantised": lambda rng, n: np.round(rng.normal(size=n) / 0.5) * 0.5,
}


@pytest.mark.parametrize("kind", list(NOISES))
def test_the_mean_periods_dc_is_judged_against_its_own_variance(kind: str) -> None:
    """The DC of the averaged period (the loop's centre, where an offset acts) against the noise level the
    diagnosis takes: ``mean / sqrt(var / (N P))`` beyond 2.576 in about 1 % of noise-only records. With an
    AR(1) of phi = 0.99 (correlated across the 128-sample periods) the old level, the harmonics 0-2 pooled
    about a quadratic trend, was 10 times too small at the DC: 41 % of 200 records (now 4 %), and the nulls
    of benches/diagnosis_designs.py's "ar1 slow" were "unexplained" (an output offset whose law failed,
    loops "not settled")."""
    n = 16
    z = []
    for s in range(120):
        rng = np.random.default_rng([s, 5])
        y = NOISES[kind](rng, n * P)
        rows = y.reshape(n, P)
        v = _white_var(rows)
        var = noise_colour(rows, v, P * (n - 1))[0]
        z.append(float(np.mean(y)) / math.sqrt(var / (n * P)))
    assert np.mean(np.abs(z) > 2.576) <= 0.06, np.mean(np.abs(z) > 2.576)


def test_quantised_white_noise_stays_white() -> None:
    rng = np.random.default_rng(21)
    fired = 0
    for _ in range(60):
        rows = np.round(rng.normal(size=(16, P)) / 0.5) * 0.5
        v = _white_var(rows)
        fired += noise_colour(rows, v, P * 15)[0] != v
    assert fired <= 1


def test_cross_period_inflation_follows_the_lag_one_correlation() -> None:
    """Independent periods: about 1; an AR(1) across periods with r = 0.5: about (1 + r) / (1 - r) = 3."""
    rng = np.random.default_rng(4)
    ind = [cross_period_inflation(rng.normal(size=16)) for _ in range(400)]
    assert 1.0 <= float(np.median(ind)) < 1.4
    cor = [cross_period_inflation(_ar1(rng, 16, 0.5)) for _ in range(400)]
    assert 2.0 < float(np.median(cor)) < 4.5
    assert cross_period_inflation(np.ones(16)) == 1.0


def test_f_test_does_not_scale_by_a_residual_below_the_floor() -> None:
    """chi2/dof of 0.15 (a floor taken at the noise's low-harmonic level, larger than at the others): a cost
    drop of 4 is chi-square(1) at the floor (p ~ 0.045), not F = 27 (p = 3e-7)."""
    f, p = f_test(154.0, 150.0, 1000)
    assert f == pytest.approx(4.0)
    assert 0.04 < p < 0.05
    # At or above the floor the classical F is unchanged.
    f2, _ = f_test(2010.0, 2000.0, 1000)
    assert f2 == pytest.approx(10.0 / 2.0)


def test_ar1_null_names_nothing_and_says_the_noise_is_coloured(helpers: SimpleNamespace) -> None:
    """On the bench generator's plant (exact G, its own RK4 of the hysteresis) with AR(1) noise and nothing
    hidden, the targeted step named a parallel stiffness (F = 28.5, p = 1.6e-6: a cost drop of 4 scaled by
    chi2/dof 0.14); now nothing is named and the notes say the noise is coloured."""
    d = helpers.diagnose_quietly(helpers.designs_case("ar1", None, "", 0.0, 100001))
    assert d.named_terms == (), d.summary()
    assert d.status == "adequate", d.summary()
    assert any("coloured noise" in n for n in d.notes), d.notes
    # phi = 0.8 is not correlated from one 128-sample period to the next (0.8^128 ~ 4e-13).
    assert not any("correlated across periods" in n for n in d.notes), d.notes


def test_ar1_viscous_on_x_is_named(helpers: SimpleNamespace) -> None:
    """A 10x viscous damping on x under the same AR(1) noise is still named, at its place (its law test used
    to fail at p = 0.003 against the white floor: "unexplained")."""
    d = helpers.diagnose_quietly(helpers.designs_case("ar1", "viscous", "x", 10.0, 210001))
    assert d.status == "explained", d.summary()
    assert [t.term for t in d.named] == ["viscous@x"], d.summary()


def test_white_noise_gets_no_colour_note(helpers: SimpleNamespace) -> None:
    d = helpers.diagnose_quietly(helpers.designs_case("base", None, "", 0.0, 100000))
    assert not any("coloured noise" in n for n in d.notes), d.notes


def test_the_verdict_says_when_the_design_cannot_tell_the_places_apart(helpers: SimpleNamespace) -> None:
    """Three frequencies at one amplitude through a nearly flat G (x lags u by 0.01-0.05 rad): a 10x spring on
    x fits as well on u, and the summary listed the other place as an alternative, but the one-line verdict
    named the chosen place alone. It now names both."""
    from bouc_wen_id.terms import TERMS

    d = helpers.diagnose_quietly(helpers.designs_case("3f x 1A", "stiffness", "x", 10.0, 410001))
    assert d.status == "explained", d.summary()
    (chosen,) = d.named_terms
    rivals = [a.rival for a in d.alternatives if a.term == chosen]
    assert rivals, d.summary()
    assert {chosen, *rivals} >= {"stiffness", "stiffness@x"}, d.summary()
    for kind in (chosen, *rivals):
        assert TERMS[kind].place_label() in d.verdict, d.verdict
    assert "cannot tell apart" in d.verdict


def test_a_design_below_saturation_says_a_spring_on_x_could_not_show(helpers: SimpleNamespace) -> None:
    """Three frequencies, every latent amplitude at 0.3 of saturation: a 30x spring on x trades with |G| and
    the diagnosis says "adequate" (true of the plain model); the notes now say the design could not show a
    spring on x. A saturating design gets no such note."""
    dd = helpers.designs_bench()
    low = dd.Design("low", factors=(0.5, 1.0, 2.0), levels=(0.3,))
    p = dd.plant_for(low, 430000)
    y, _, _ = dd.outputs(p, low, "stiffness", "x", 30.0)
    d = helpers.diagnose_quietly(dd.recordings(p, low, y, 430000))
    assert "stiffness@x" not in d.named_terms, d.summary()
    assert any("below the hysteresis' saturation" in n for n in d.notes), d.notes
    base = helpers.diagnose_quietly(helpers.designs_case("3f x 1A", None, "", 0.0, 100000))
    assert not any("saturation" in n for n in base.notes), base.notes


@pytest.mark.parametrize("seed", [100002, 100005])
def test_noise_correlated_across_periods_is_no_unexplained_structure(
    seed: int, helpers: SimpleNamespace
) -> None:
    """AR(1) output noise with phi = 0.99 (the bench's "ar1 slow"), nothing hidden: the loop centres wander
    from experiment to experiment by more than the spread of their period DCs says. Seed 100002 left three
    experiments out as "not settled" and called the rest "unexplained" (centres of both signs); 100005 tested
    an output offset at p = 3.4e-11 whose law failed ("unexplained structure remains"). Judged against the
    DC's own level (correlated across periods) both are adequate, and the notes say the record cannot tell
    that wander from a drift."""
    d = helpers.diagnose_quietly(helpers.designs_case("ar1 slow", None, "", 0.0, seed))
    assert d.status == "adequate", d.summary()
    assert d.named_terms == ()
    assert any("correlated across periods" in n for n in d.notes), d.notes


def _block_chi2(phi: float, seed: int, per_harmonic: bool) -> float:
    """The drift test's chi-square of the block deviations over its degrees of freedom (drift.drift_data's
    weights), for a loop with AR(1) output noise and no drift."""
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.drift import _inner, harmonic_weights, whole_blocks

    rng = np.random.default_rng([seed, 9])
    n = 20 * P
    t = np.arange(n) * 2 * math.pi / P
    y = np.tanh(2.0 * np.cos(t - 0.3)) + 0.05 * _ar1(rng, n, phi)
    (e,) = prepare(bw.Recording(t, np.cos(t), y, 1.0, 1.0, settle_periods=4))
    keep = whole_blocks(e)
    k = e.block_coef.shape[1] - 1
    w = e.block_samples[keep] / e.noise_var
    c = e.block_coef[keep]
    dev = c - (w[:, None] * c).sum(axis=0) / w.sum()
    hw = harmonic_weights(e, k) if per_harmonic else None
    return float(np.dot(w, _inner(dev, dev, hw)) / ((keep.size - 1) * (2 * k + 1)))


@pytest.mark.parametrize("phi", [0.8, 0.99])
def test_the_drift_test_weighs_each_harmonic_by_its_own_noise(phi: float) -> None:
    """Weighed with one level (the largest, at the DC) the blocks of a record that does not drift sat at
    0.31 (phi = 0.8) and 0.026 (phi = 0.99) of their degrees of freedom: a degradation acting at the
    fundamental was judged against the DC's noise (not named in any of 5 'ar1' cases at 10x). Each
    harmonic weighed by its own level they sit near 1 (0.96 and 0.76: the harmonics of neighbouring periods
    are slightly anticorrelated, conservative), and never above it by much."""
    new = [_block_chi2(phi, s, True) for s in range(12)]
    old = [_block_chi2(phi, s, False) for s in range(12)]
    assert 0.6 < float(np.median(new)) < 1.3, new
    assert max(new) < 2.0, new
    assert float(np.median(old)) < 0.4, old

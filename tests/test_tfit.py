"""G(s) from the identified points (bouc_wen_id.tfit, issue #11 part 1): recovery, stability, order
selection, scipy cross-checks, warnings, interval coverage, and the end-to-end path identify -> fit."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import bouc_wen_id as bw
import numpy as np
import pytest
import scipy.signal  # type: ignore[import-untyped]
from bouc_wen_id.demo import design_amplitudes
from bouc_wen_id.errors import (
    IdentifiabilityWarning,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    PoorFitWarning,
)
from bouc_wen_id.tfit._points import _points
from bouc_wen_id.tfit._refine import _sk_start

#: Known transfer functions of orders 1-4 (two with a delay), the cases of the recovery tests.
KNOWN = {
    "first": bw.TransferFunction([2.0], [1.0, 3.0]),
    "second_delay": bw.TransferFunction([25.0], [1.0, 2.0, 25.0], delay=0.05),
    "third_zero": bw.TransferFunction([1.0, 4.0], [1.0, 3.0, 6.0, 4.0]),
    "fourth_delay": bw.TransferFunction([3.0, 1.0, 20.0], [1.0, 1.2, 30.0, 10.0, 50.0], delay=0.02),
}
#: Dense enough to pin every peak of KNOWN down (the half-power bands are covered).
OMEGA = np.geomspace(0.3, 20.0, 24)


def _noisy(
    tf: bw.TransferFunction, omega: np.ndarray, rel: float, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Points with relative gain error and absolute phase error ``rel`` (sd), and their covariance."""
    rng = np.random.default_rng(seed)
    g = tf.freqresp(omega)
    gain = np.abs(g) * (1.0 + rel * rng.standard_normal(omega.size))
    phase = -np.angle(g) + rel * rng.standard_normal(omega.size)
    cov = np.stack([np.diag([(rel * abs(x)) ** 2, rel**2]) for x in g])
    return gain * np.exp(-1j * phase), cov


def _orders(tf: bw.TransferFunction) -> tuple[int, int]:
    return tf.num.size - 1, tf.den.size - 1


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_exact_points_recover_the_coefficients(name: str) -> None:
    tf = KNOWN[name]
    cov = np.stack([np.diag([1e-6 * abs(x) ** 2, 1e-6]) for x in tf.freqresp(OMEGA)])
    fit = bw.fit_transfer_function(
        omega=OMEGA, response=tf.freqresp(OMEGA), covariance=cov, order=_orders(tf), delay=tf.delay > 0
    )
    got = fit.transfer_function
    # Exact data: only the optimiser's tolerance (1e-12 on the cost) is left, far below 1e-6.
    np.testing.assert_allclose(got.num, tf.num, rtol=1e-6)
    np.testing.assert_allclose(got.den, tf.den, rtol=1e-6)
    assert got.delay == pytest.approx(tf.delay, abs=1e-8)
    assert fit.chi2 < 1e-10
    w = np.array([0.13, 7.7, 45.0])  # untested, inside and outside the band
    np.testing.assert_allclose(got.freqresp(w), tf.freqresp(w), rtol=1e-6)


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_noisy_points_give_the_true_response_within_its_interval(name: str) -> None:
    tf = KNOWN[name]
    g, cov = _noisy(tf, OMEGA, 0.01, seed=11)
    fit = bw.fit_transfer_function(
        omega=OMEGA, response=g, covariance=cov, order=_orders(tf), delay=tf.delay > 0
    )
    w = np.array([0.45, 2.5, 9.0])
    p = fit.predict(w)
    err = np.abs(p.response - tf.freqresp(w))
    se = np.sqrt(np.trace(p.covariance, axis1=1, axis2=2))
    # One seeded draw: the error of a 2-D Gaussian exceeds 4 of its total sd with probability < 1e-3.
    assert np.all(err < 4.0 * se)
    # and the fit is consistent with the noise: chi2 of the model's own order within its 99.9 % range.
    assert fit.p_value is not None and fit.p_value > 1e-3


def test_order_selection_picks_the_true_order_on_clean_dense_points() -> None:
    for tf in (KNOWN["second_delay"], KNOWN["third_zero"]):
        g, cov = _noisy(tf, OMEGA, 1e-3, seed=3)
        fit = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=cov)
        assert (fit.m, fit.n) == _orders(tf)
        assert fit.delay_fitted == (tf.delay > 0)
        assert sum(c.chosen for c in fit.candidates) == 1
        assert "lowest AICC" in fit.selection
    fit_bic = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=cov, criterion="bic", max_order=3)
    assert (fit_bic.m, fit_bic.n) == (1, 3) and len(fit_bic.candidates) == 20


def test_an_unstable_best_fit_is_returned_stable() -> None:
    # 1/(s - 1) has the gain of 1/(s + 1) but not its phase: the unconstrained fit is unstable.
    omega = np.geomspace(0.1, 10.0, 12)
    g = 1.0 / (1j * omega - 1.0)
    cov = np.stack([np.diag([1e-4 * abs(x) ** 2, 1e-4]) for x in g])
    pts = _points(None, omega, g, cov)
    _, den = _sk_start(pts, 1j * omega / np.exp(np.mean(np.log(omega))), 0, 1, 0.0)
    assert np.roots(den)[0].real > 0.0  # the start really is unstable
    with pytest.warns(PoorFitWarning, match="unstable G"):
        fit = bw.fit_transfer_function(omega=omega, response=g, covariance=cov, order=(0, 1), delay=False)
    assert np.all(fit.poles().real < 0.0)
    assert any("reflected" in n for n in fit.notes)
    assert fit.p_value is not None and fit.p_value < 1e-6  # and the report says it does not fit
    assert any("unstable G" in w for w in fit.warnings)


def test_scipy_signal_crosscheck() -> None:
    tf = KNOWN["fourth_delay"]
    g, cov = _noisy(tf, OMEGA, 0.005, seed=5)
    fit = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=cov, order=(2, 4), delay=True)
    got = fit.transfer_function
    w = np.geomspace(0.1, 50.0, 17)
    _, h = scipy.signal.freqs(got.num, got.den, worN=w)
    np.testing.assert_allclose(h * np.exp(-1j * w * got.delay), got.freqresp(w), rtol=1e-10)
    np.testing.assert_allclose(fit.predict(w).response, got.freqresp(w), rtol=1e-9)
    # Poles: scipy's partial fractions of the fitted num/den against the fit's own poles.
    _, poles, _ = scipy.signal.residue(got.num, got.den)
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(fit.poles()), rtol=1e-6)
    # And the fitted poles are near the true ones (0.5 % noise, dense points).
    np.testing.assert_allclose(np.sort_complex(fit.poles()), np.sort_complex(np.roots(tf.den)), rtol=0.02)


def test_warnings_fire() -> None:
    tf = KNOWN["second_delay"]
    w2 = np.array([1.0, 3.0])
    with pytest.warns(IdentifiabilityWarning) as record:
        fit = bw.fit_transfer_function(omega=w2, response=tf.freqresp(w2), order=(2, 2), delay=False)
    assert fit.dof < 0 and any("real equations" in str(r.message) for r in record)
    # A light resonance (zeta 0.05 at 5 rad/s) with no point inside its half-power band [4.75, 5.25].
    sharp = bw.TransferFunction([25.0], [1.0, 0.5, 25.0])
    w = np.array([1.0, 2.0, 3.0, 4.0, 6.0, 7.0, 8.0, 10.0])
    g, cov = _noisy(sharp, w, 0.01, seed=2)
    with pytest.warns(IdentifiabilityWarning, match="between two tested frequencies"):
        fit = bw.fit_transfer_function(omega=w, response=g, covariance=cov, order=(0, 2), delay=False)
    assert any("not pinned down" in m for m in fit.warnings)
    # The same resonance with a point at its peak: no warning (filterwarnings=error would raise).
    w = np.append(w, 5.0)
    g, cov = _noisy(sharp, w, 0.01, seed=2)
    bw.fit_transfer_function(omega=w, response=g, covariance=cov, order=(0, 2), delay=False)


def test_interval_coverage_small_monte_carlo() -> None:
    tf = bw.TransferFunction([2.0], [1.0, 3.0], delay=0.1)
    omega = np.geomspace(0.5, 10.0, 8)
    w_new = np.array([20.0])  # untested, above the band: extrapolation is where the intervals matter
    hits_gain = hits_phase = 0
    reps = 200
    g_true = tf.freqresp(w_new)[0]
    for seed in range(reps):
        g, cov = _noisy(tf, omega, 0.02, seed=1000 + seed)
        p = bw.fit_transfer_function(
            omega=omega, response=g, covariance=cov, order=(0, 1), delay=True
        ).predict(w_new)
        lo, hi = p.gain_interval[0]
        hits_gain += lo <= abs(g_true) <= hi
        dphi = (p.phase[0] - (-np.angle(g_true)) + np.pi) % (2 * np.pi) - np.pi
        hits_phase += abs(dphi) <= 1.959964 * p.phase_se[0]
    # Nominal 0.95; a binomial rate over 200 has sd 0.015, and the delta method is first order, so the
    # band is [0.88, 0.99] (more than 4 sd below, 2.6 above).
    assert 0.88 <= hits_gain / reps <= 0.99
    assert 0.88 <= hits_phase / reps <= 0.99


@pytest.mark.parametrize(
    ("omega", "response", "error"),
    [
        ([1.0, np.nan, 3.0], [1.0, 1.0, 1.0], NonFiniteError),
        ([1.0, 2.0, 3.0], [1.0, np.inf, 1.0], NonFiniteError),
        ([0.0, 2.0, 3.0], [1.0, 1.0, 1.0], InvalidParameterError),
        ([-1.0, 2.0, 3.0], [1.0, 1.0, 1.0], InvalidParameterError),
        ([2.0, 2.0], [1.0, 1.0], InsufficientDataError),  # one frequency twice: one pooled point
        ([1.0], [1.0], InsufficientDataError),
        ([1.0, 2.0], [1.0, 1.0, 1.0], InvalidParameterError),
        ([1.0, 2.0, 3.0], [1.0, 0.0, 1.0], InvalidParameterError),
    ],
)
def test_bad_points_are_named_errors(omega: list[float], response: list[complex], error: type) -> None:
    with pytest.raises(error):
        bw.fit_transfer_function(omega=omega, response=response)


def test_points_of_one_frequency_are_pooled() -> None:
    """Two amplitudes of one frequency give two points of one G value: pooled by their information, the
    same point twice with twice the covariance is the point once (on main: refused as duplicates)."""
    tf = KNOWN["first"]
    g, cov = _noisy(tf, OMEGA, 0.02, 3)
    once = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=cov, order=(0, 1))
    twice = bw.fit_transfer_function(
        omega=np.concatenate([OMEGA, OMEGA[::-1]]),
        response=np.concatenate([g, g[::-1]]),
        covariance=np.concatenate([2.0 * cov, 2.0 * cov[::-1]]),
        order=(0, 1),
    )
    assert np.allclose(twice.transfer_function.num, once.transfer_function.num, rtol=1e-8)
    assert np.allclose(twice.transfer_function.den, once.transfer_function.den, rtol=1e-8)
    # two different points of one frequency: the pooled one lies between them, nearer the precise one
    w = np.array([1.0, 1.0, 2.0, 3.0])
    pts = np.array([1.0, 1.2, 0.8, 0.6], dtype=complex)
    c = np.stack([np.diag([v, 1e-4]) for v in (1e-4, 9e-4, 1e-4, 1e-4)])
    pooled = _points(None, w, pts, c)
    assert pooled.omega.size == 3 and 1.0 < pooled.g[0].real < 1.1


def test_bad_options_are_named_errors() -> None:
    w = np.array([1.0, 2.0, 3.0])
    g = KNOWN["first"].freqresp(w)
    for kw in (
        {"order": (3, 2)},
        {"order": -1},
        {"order": "2"},
        {"delay": -0.1},
        {"criterion": "aic"},
        {"max_order": 9},
        {"covariance": np.ones((2, 2, 2))},
        {"covariance": -np.ones((3, 2, 2))},
    ):
        with pytest.raises(InvalidParameterError):
            bw.fit_transfer_function(omega=w, response=g, **kw)
    with pytest.raises(InvalidParameterError):
        bw.fit_transfer_function()
    g_in = g.copy()
    bw.fit_transfer_function(omega=w, response=g_in, order=(0, 1), delay=False)
    np.testing.assert_array_equal(g_in, g)  # nothing the user passes is modified


def test_unweighted_points_and_a_known_delay() -> None:
    tf = KNOWN["second_delay"]
    g, _ = _noisy(tf, OMEGA, 0.01, seed=9)
    fit = bw.fit_transfer_function(omega=OMEGA, response=g, order=(0, 2), delay=0.05)
    assert not fit.weighted and fit.p_value is None and not fit.delay_fitted
    assert fit.transfer_function.delay == 0.05 and "delay" not in fit.parameter_names
    np.testing.assert_allclose(fit.transfer_function.den, tf.den, rtol=0.05)
    w = np.array([3.0])
    assert abs(fit.predict(w).gain[0] - abs(tf.freqresp(w)[0])) < 4.0 * fit.predict(w).gain_se[0]


@pytest.fixture(scope="module")
def identified() -> tuple[bw.WienerPlant, bw.IdentificationResult]:
    plant = bw.WienerPlant(bw.TransferFunction([6.0], [1.0, 1.2, 4.0]), bw.BoucWen(0.8, 0.2, 1.6))
    freqs = [float(f) for f in np.geomspace(0.5, 5.0, 10)]
    plan = bw.SinePlan(
        frequencies=tuple(freqs),
        amplitudes=design_amplitudes(plant, freqs),
        settle_periods=10,
        periods=10,
        samples_per_period=128,
        substeps=2,
        noise_sd=0.02,
        seed=7,
    )
    return plant, bw.identify(bw.simulate(plant, plan), method="refined")


def test_end_to_end_identify_then_fit(identified: tuple[bw.WienerPlant, bw.IdentificationResult]) -> None:
    plant, result = identified
    fit = result.fit_transfer_function()
    assert (fit.m, fit.n, fit.delay_fitted) == (0, 2, False)
    w = np.array([1.1, 3.3])  # between the tested frequencies
    p = fit.predict(w)
    true = plant.normalized().linear.freqresp(w)
    # Seeded: |G| within its 99.9 % interval (3.29 se) and the complex error within 4 total sd.
    assert np.all(np.abs(p.gain - np.abs(true)) < 3.29 * p.gain_se)
    assert np.all(np.abs(p.response - true) < 4.0 * np.sqrt(np.trace(p.covariance, axis1=1, axis2=2)))
    text = str(fit)
    assert "order selection (AICC)" in text and "<- chosen" in text
    d = json.loads(json.dumps(fit.to_dict()))
    assert d["format"] == "bouc_wen_id.tfit" and d["n"] == 2 and len(d["candidates"]) == 30
    # The fitted plant simulates.
    fitted_plant = bw.WienerPlant(fit.transfer_function, bw.BoucWen(result.beta, result.gamma, result.mu))
    plan = bw.SinePlan(
        frequencies=(1.0,), amplitudes=(0.5,), settle_periods=2, periods=2, samples_per_period=64
    )
    (rec,) = bw.simulate(fitted_plant, plan)
    assert np.all(np.isfinite(rec.y)) and np.ptp(rec.y) > 0.0


def test_import_does_not_load_scipy_optimize_or_control() -> None:
    code = "import sys, bouc_wen_id; print('scipy.optimize' in sys.modules, 'control' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_warnings_are_not_issued_for_a_well_posed_fit() -> None:
    tf = KNOWN["first"]
    g, cov = _noisy(tf, OMEGA, 0.01, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=cov, order=1)
    assert fit.warnings == () and fit.n == 1 and len(fit.candidates) == 4  # m in 0..1, delay or not


@pytest.mark.parametrize(
    ("kw", "error"),
    [
        (dict(omega=["a", "b"], response=[1.0, 2.0]), InvalidParameterError),
        (dict(response=["x"] * 4), InvalidParameterError),
        (dict(omega=[[1.0, 2.0], [3.0]]), InvalidParameterError),
        (dict(delay="x"), InvalidParameterError),
        (dict(delay=-1.0), InvalidParameterError),
        (dict(confidence="x"), InvalidParameterError),
        (dict(max_order=2.0), InvalidParameterError),
    ],
)
def test_misused_arguments_are_named_errors(kw: dict[str, object], error: type[Exception]) -> None:
    w = np.array([1.0, 2.0, 4.0, 8.0])
    args: dict[str, object] = {"omega": w, "response": 1.0 / (1j * w + 1.0), **kw}
    with pytest.raises(error):
        bw.fit_transfer_function(**args)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("omega", "error"),
    [
        ("a", InvalidParameterError),
        ([1.0, np.nan], NonFiniteError),
        ([[1.0, 2.0], [3.0]], InvalidParameterError),
        (1 + 2j, InvalidParameterError),
    ],
)
def test_predict_names_bad_frequencies(omega: object, error: type[Exception]) -> None:
    w = np.array([1.0, 2.0, 4.0, 8.0])
    fit = bw.fit_transfer_function(omega=w, response=1.0 / (1j * w + 1.0))
    with pytest.raises(error):
        fit.predict(omega)  # type: ignore[arg-type]

"""Parity of the Rust-backed harmonic least squares (the lab part of ``_backend``, ``rust/lab.rs``) with the
NumPy reference paths of ``signal._harmonic_ls`` (the QR of the harmonic basis and the NumPy moment loop)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id._backend import get_backend, selected
from bouc_wen_id.errors import InsufficientDataError, InvalidParameterError, NonFiniteError
from bouc_wen_id.signal import _harmonic_ls as hls
from numpy.testing import assert_allclose

#: The Rust lab kernels, as the signal modules get them.
_RUST_LAB = get_backend("rust").lab


def _record(seed: int, n: int, p: float) -> tuple[np.ndarray, np.ndarray]:
    """Phases of ``n`` samples at ``p`` (non-integer) samples per period, and a noisy distorted periodic y."""
    rng = np.random.default_rng(seed)
    theta = np.mod(2.0 * math.pi * (np.arange(n) / p + rng.uniform()), 2.0 * math.pi)
    y = 0.3 + np.cos(theta) + 0.2 * np.sin(3 * theta) ** 3 + 0.05 * rng.standard_normal(n)
    return theta, y


@pytest.mark.parametrize("seed", range(4))
def test_moment_kernels_match_the_numpy_recurrence(seed: int) -> None:
    theta, y = _record(seed, 3001 + 17 * seed, 97.3 + seed)
    k = 12
    mr, mi, rr, ri = _core.harmonic_moments(theta, y, k)
    z = np.exp(1j * theta)
    p = np.ones_like(z)
    for q in range(2 * k + 1):
        # Same per-sample powers, another summation order: n eps relative to the sum of |terms| = n.
        assert abs(complex(mr[q], mi[q]) - p.sum()) <= 1e-12 * theta.size
        if q <= k:
            assert abs(complex(rr[q], ri[q]) - np.dot(y, p.conj())) <= 1e-12 * float(np.sum(np.abs(y)))
        p = p * z
    coef = np.random.default_rng(seed).standard_normal(2 * k + 1)
    basis = hls.harmonic_basis(theta, k)
    assert_allclose(
        _core.harmonic_series(theta, coef), basis @ coef, rtol=0, atol=1e-11 * np.sum(np.abs(coef))
    )


@pytest.mark.parametrize("seed", range(4))
def test_moment_fit_matches_the_reference(seed: int) -> None:
    theta, y = _record(seed, 20_000, 317.3 - 0.2 * seed)
    k = 40 + 10 * seed
    fast = _RUST_LAB.moment_fit(theta, y, k)
    assert fast is not None
    r_ref, qty_ref, rss_ref = hls._moment_fit(theta, y, k)
    r, qty, rss = fast
    # Normal equations of a Gram matrix with condition ~1: the factors agree to the rounding of the
    # moments (n eps relative), far below the noise (5 %).
    assert_allclose(r, r_ref, rtol=1e-10, atol=1e-10 * float(np.max(np.abs(r_ref))))
    assert_allclose(qty, qty_ref, rtol=1e-9, atol=1e-10 * float(np.max(np.abs(qty_ref))))
    assert rss == pytest.approx(rss_ref, rel=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_harmonic_lsq_matches_the_qr_path(seed: int) -> None:
    theta, y = _record(seed, 20_000, 300.0 + 7.7 * seed)
    for k in (1, 4, 10):
        coef_ref, r_ref = hls.solve_qr(hls.harmonic_basis(theta, k), y)
        resid = y - hls.harmonic_basis(theta, k) @ coef_ref
        fast = _RUST_LAB.harmonic_lsq(theta, y, k)
        assert fast is not None
        coef, r, rss = fast
        assert_allclose(coef, coef_ref, rtol=1e-10, atol=1e-12)
        # R up to the signs of its rows: the variances (row norms of R^-1) agree.
        assert_allclose(np.abs(r), np.abs(r_ref), rtol=1e-9, atol=1e-9 * float(np.max(np.abs(r_ref))))
        assert rss == pytest.approx(float(resid @ resid), rel=1e-9)


def test_ill_conditioned_fits_are_left_to_the_qr_path() -> None:
    # A third of a period with 6 harmonics: the harmonics are far from orthogonal.
    theta = np.linspace(0.0, 2.0, 400)
    y = np.cos(theta)
    assert _RUST_LAB.moment_fit(theta, y, 6) is None
    assert _RUST_LAB.harmonic_lsq(theta, y, 6) is None
    # cond = 1.99999 / 1e-5 = 2e5 > 1e4; cond = 1.999 / 1e-3 = 1999 <= 1e4 (Gershgorin cannot certify it:
    # the eigenvalue path decides).
    assert not _RUST_LAB.well_conditioned(np.array([[1.0, 0.99999], [0.99999, 1.0]]))
    assert _RUST_LAB.well_conditioned(np.array([[1.0, 0.999], [0.999, 1.0]]))
    assert not _RUST_LAB.well_conditioned(np.array([[1.0, 0.0], [0.0, -1.0]]))


@pytest.mark.parametrize("seed", range(3))
def test_conditioning_decision_is_the_reference_eigenvalue_test(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(200):
        m = int(rng.integers(2, 8))
        a = rng.standard_normal((m, m)) * rng.uniform(0.01, 0.6)
        gram = np.eye(m) * rng.uniform(0.5, 4.0, m) + 0.5 * (a + a.T)
        scale = np.sqrt(np.abs(np.diag(gram)))
        eig = np.linalg.eigvalsh(gram / np.outer(scale, scale))
        expected = bool(np.all(np.diag(gram) > 0) and eig[0] > 0 and eig[-1] / eig[0] <= 1e4)
        assert _RUST_LAB.well_conditioned(gram) == expected


def test_kernels_refuse_bad_input() -> None:
    theta = np.linspace(0.0, 6.0, 50)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_moments(theta, theta[:10], 3)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_moments(theta, theta, 0)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_series(theta, np.ones(4))
    bad = theta.copy()
    bad[3] = np.nan
    with pytest.raises(NonFiniteError):
        _core.harmonic_moments(bad, theta, 2)


def _lab_record(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """20,000 samples, 317.3 (non-integer) samples per period: idle, ramps, offsets, noise, a distorted y."""
    rng = np.random.default_rng(seed)
    n, p = 20_000, 317.3 + 0.1 * seed
    omega = 2.0 * math.pi * 50.0 / p  # sampled at 50 Hz
    t = np.arange(n) / 50.0
    period = 2.0 * math.pi / omega
    env = np.clip((t - 3 * period) / (2 * period), 0.0, 1.0) * np.clip(
        (t[-1] - 3 * period - t) / (2 * period), 0, 1
    )
    u = 0.2 + env * 1.5 * np.cos(omega * t + rng.uniform(0, 6)) + 0.003 * rng.standard_normal(n)
    y = -0.1 + np.tanh(1.3 * (u - 0.2)) ** 3 + 0.01 * rng.standard_normal(n)
    return t, u, y, omega * 1.02


@pytest.mark.parametrize("seed", range(2))
def test_lab_pipeline_with_and_without_the_rust_kernels(seed: int) -> None:
    from bouc_wen_id import signal

    t, u, y, nominal = _lab_record(seed)

    def run() -> tuple[signal.SineFit, signal.SegmentReport, list[signal.AveragedPeriod]]:
        fit = signal.analyse_sine(t, u, nominal_frequency=nominal)
        rep = signal.find_steady_segments(t, u, y, nominal_frequency=nominal)
        avg = [
            signal.synchronous_average(t, y, f, start=s.start, stop=s.stop)
            for s, f in zip(rep.kept, rep.fits)
        ]
        return fit, rep, avg

    fast = run()
    with selected("numpy"):
        ref = run()
    # The frequency: Gauss-Newton stops at 1e-4 of its standard error, so two paths whose residuals differ by
    # rounding may stop one step apart: agreement to 1e-3 standard errors.
    assert abs(fast[0].frequency - ref[0].frequency) <= 1e-3 * ref[0].frequency_se
    assert fast[0].amplitude == pytest.approx(ref[0].amplitude, rel=1e-9)
    assert fast[1].kept == ref[1].kept and fast[1].dropped == ref[1].dropped
    assert len(fast[2]) == len(ref[2]) >= 1
    for a, b in zip(fast[2], ref[2]):
        assert a.harmonics == b.harmonics
        assert_allclose(a.ybar, b.ybar, rtol=0, atol=1e-8 * float(np.max(np.abs(b.ybar))))
        assert a.noise_var == pytest.approx(b.noise_var, rel=1e-7)


@pytest.mark.parametrize("seed", range(3))
def test_gauss_newton_kernel_matches_the_basis_reference(seed: int) -> None:
    from bouc_wen_id.signal import _sine

    rng = np.random.default_rng(seed)
    n, k = 5003 + 11 * seed, 1 + 3 * seed
    tau = (np.arange(n, dtype=np.float64) - n / 2) * 1e-3
    omega = 2.0 * math.pi * rng.uniform(3.0, 9.0)
    theta = hls.phase_angle(omega, tau)
    x = 0.2 + np.cos(theta + 0.4) + 0.05 * rng.standard_normal(n)
    coef = rng.standard_normal(2 * k + 1)
    rr, rd, dd, xtd = _core.harmonic_gauss_newton(theta, tau, x, coef)
    basis = hls.harmonic_basis(theta, k)
    d = _sine._omega_column(tau, coef, basis)
    r = x - basis @ coef
    # Same per-sample phasors as the basis recurrence, another summation order: n eps relative to the
    # sums of |terms|.
    assert rr == pytest.approx(float(r @ r), rel=1e-11)
    assert rd == pytest.approx(float(r @ d), abs=1e-11 * float(np.abs(r) @ np.abs(d)))
    assert dd == pytest.approx(float(d @ d), rel=1e-11)
    assert_allclose(xtd, basis.T @ d, rtol=0, atol=1e-11 * float(np.sum(np.abs(d))))
    with pytest.raises(InvalidParameterError):
        _core.harmonic_gauss_newton(theta, tau[:-1], x, coef)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_gauss_newton(theta, tau, x, coef[:1])


@pytest.mark.parametrize("seed", range(3))
def test_frequency_fit_matches_the_reference(seed: int) -> None:
    from bouc_wen_id.signal import _sine

    rng = np.random.default_rng(seed)
    n, dt, k = 20_000, 1e-3, 1 + seed
    tau = (np.arange(n, dtype=np.float64) - n // 2) * dt
    omega = 2.0 * math.pi * rng.uniform(2.0, 6.0)
    x = 0.1 + 1.3 * np.cos(omega * tau + 0.7) + 0.05 * np.cos(2 * omega * tau) + 0.02 * rng.standard_normal(n)
    start = omega * (1.0 + 2e-3 * rng.uniform(-1.0, 1.0))
    fast = _sine._nls(tau, x, start, dt, k)
    with selected("numpy"):
        ref = _sine._nls(tau, x, start, dt, k)
    # Gauss-Newton stops at 1e-4 of the standard error; residuals that differ by rounding may stop it one
    # step apart: the frequencies agree to 1e-3 standard errors, the rest to the rounding of the fits.
    assert abs(fast.omega - ref.omega) <= 1e-3 * ref.se
    assert fast.se == pytest.approx(ref.se, rel=1e-6)
    assert fast.rss == pytest.approx(ref.rss, rel=1e-9)
    assert_allclose(fast.coef, ref.coef, rtol=0, atol=1e-6 * float(np.max(np.abs(ref.coef))))


@pytest.mark.parametrize("seed", range(3))
def test_cholesky_and_rss_kernels_match_numpy(seed: int) -> None:
    theta, y = _record(seed, 4000 + seed, 61.7 + seed)
    k = 5 + 20 * seed
    mr, mi, rr, ri = _core.harmonic_moments(theta, y, k)
    gram, _ = hls.gram_from_moments(mr + 1j * mi, rr + 1j * ri, k)
    m = 2 * k + 1
    r = _core.cholesky_upper(np.ascontiguousarray(gram).ravel(), m).reshape(m, m)
    # Another order of the same dot products as LAPACK's blocked factor, on a Gram matrix of condition
    # ~1 (harmonics over 60+ periods): agreement to rounding, 1e-12 of the largest entry.
    assert_allclose(r, np.linalg.cholesky(gram).T, rtol=0, atol=1e-12 * float(np.max(np.abs(r))))
    coef = np.random.default_rng(seed).standard_normal(m)
    resid = y - hls.harmonic_basis(theta, k) @ coef
    assert _core.harmonic_rss(theta, y, coef) == pytest.approx(float(resid @ resid), rel=1e-11)
    indefinite = gram.copy()
    indefinite[0, 0] = -1.0
    with pytest.raises(InvalidParameterError):
        _core.cholesky_upper(indefinite.ravel(), m)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_rss(theta, y[:-1], coef)


@pytest.mark.parametrize("seed", range(3))
def test_unscaled_variances_match_the_triangular_inverse(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = int(rng.integers(3, 60))
    r = np.triu(rng.standard_normal((m, m))) + np.diag(rng.uniform(1.0, 3.0, m) * rng.choice([-1, 1], m))
    r_inv = hls.solve_triangular(r, np.eye(m))
    # Another order of the same back substitution: rounding of R^-1's entries (cond(R) eps).
    assert_allclose(_core.unscaled_variances(r.ravel(), m), np.sum(r_inv**2, axis=1), rtol=1e-12)
    singular = r.copy()
    singular[m // 2, m // 2] = 0.0
    with pytest.raises(InvalidParameterError):
        _core.unscaled_variances(singular.ravel(), m)
    with pytest.raises(InvalidParameterError):
        _core.unscaled_variances(r.ravel()[:-1], m)


def test_fused_fits_refuse_bad_input() -> None:
    tau = np.linspace(-1.0, 1.0, 200)
    x = np.cos(7.0 * tau)
    for bad in (
        (tau, x, -7.0, 0.01, 1),
        (tau, x, 7.0, 0.0, 1),
        (tau, x[:-1], 7.0, 0.01, 1),
        (tau, x, 7.0, 0.01, 0),
    ):
        with pytest.raises(InvalidParameterError):
            _core.harmonic_nls(*bad)
    nan = x.copy()
    nan[5] = np.nan
    with pytest.raises(NonFiniteError):
        _core.harmonic_nls(tau, nan, 7.0, 0.01, 1)
    with pytest.raises(NonFiniteError):
        _core.harmonic_fit(tau, nan, 2)
    with pytest.raises(InvalidParameterError):
        _core.gram_well_conditioned(np.eye(3).ravel(), 2)
    # More coefficients than samples (a Gram matrix beyond memory for a huge count): refused, not
    # an allocation failure; an empty record likewise.
    with pytest.raises(InsufficientDataError):
        _core.harmonic_fit(tau, x, 10**9)
    with pytest.raises(InsufficientDataError):
        _core.harmonic_fit(tau[:0], x[:0], 1)
    with pytest.raises(InsufficientDataError):
        _core.harmonic_nls(tau, x, 7.0, 0.01, 10**6)
    with pytest.raises(InsufficientDataError):
        _core.harmonic_moments(tau, x, 10**9)
    with pytest.raises(InsufficientDataError):
        _core.window_fits(tau, x, x, [0], [20], 10)
    with pytest.raises(InvalidParameterError):
        _core.padded_spectrum(x, 2**62)
    # Wrong types go through the module's converter: the library's error, not pyo3's TypeError.
    with pytest.raises(InvalidParameterError):
        _core.harmonic_fit(tau.astype(np.float32), x, 2)
    with pytest.raises(InvalidParameterError):
        _core.harmonic_moments(tau, x, 2**70)
    with pytest.raises(InvalidParameterError):
        _core.unscaled_variances(np.eye(2).ravel(), -1)


@pytest.mark.parametrize("seed", range(4))
def test_spectrum_and_peak_match_the_numpy_reference(seed: int) -> None:
    from bouc_wen_id.signal import _sine

    rng = np.random.default_rng(seed)
    n = int(rng.integers(50, 5000))
    t = np.arange(n) * 0.01
    x = 0.3 + 0.02 * t + np.cos(2 * math.pi * rng.uniform(1.0, 20.0) * t) + 0.1 * rng.standard_normal(n)
    x += 0.5 * np.cos(2 * math.pi * rng.uniform(1.0, 20.0) * t)  # a second tone: the band decides
    nfft = 1 << math.ceil(math.log2(4 * n))
    idx = np.arange(n) - 0.5 * (n - 1)
    xd = x - x.mean() - (idx @ x) / (idx @ idx) * idx
    ref = np.abs(np.fft.rfft(xd * np.hanning(n), nfft))
    # Another FFT and summation order: rounding of the largest bin.
    assert_allclose(_core.padded_spectrum(x, nfft), ref, rtol=0, atol=1e-12 * float(ref.max()))
    lo, hi = math.ceil(nfft / n), nfft // 2 - 1
    for b_lo, b_hi in ((-1, -1), (lo + 5, lo + 200), (hi - 300, hi)):
        k, *around = _core.spectral_peak(x, nfft, lo, hi, b_lo, b_hi, _sine.NOMINAL_PEAK_MIN)
        assert k == _sine._peak_bin(ref, lo, hi, b_lo, b_hi)
        assert_allclose(around, ref[k - 1 : k + 2], rtol=1e-10)
    for nominal in (None, 2 * math.pi * 5.0):
        fast = _sine.dft_peak(x, 0.01, nominal)
        with selected("numpy"):
            slow = _sine.dft_peak(x, 0.01, nominal)
        assert fast == pytest.approx(slow, rel=1e-9)
    with pytest.raises(InvalidParameterError):
        _core.spectral_peak(x, nfft, 0, hi, -1, -1, 0.1)
    with pytest.raises(InvalidParameterError):
        _core.padded_spectrum(x, n - 1)


@pytest.mark.parametrize("seed", range(3))
def test_window_fits_match_the_basis_reference(seed: int) -> None:
    from bouc_wen_id.signal import _windows

    rng = np.random.default_rng(seed)
    p, n = 63.7 + 10 * seed, 2000
    tau, omega = np.arange(n, dtype=np.float64), 2 * math.pi / p
    theta = hls.phase_angle(omega, tau)
    u = 0.1 + (1.0 + 0.001 * np.arange(n)) * np.cos(theta) + 0.01 * rng.standard_normal(n)
    y = np.tanh(2 * u) + 0.01 * rng.standard_normal(n)
    spans = [(math.floor(i * p), math.floor((i + 1) * p)) for i in range(int(n // p))]
    fast = _windows.block_windows(1, 100, tau, omega, u, y, spans, 5)
    with selected("numpy"):
        ref = _windows.block_windows(1, 100, tau, omega, u, y, spans, 5)
    assert len(fast) == len(ref) == len(spans)
    for a, b in zip(fast, ref):
        assert (a.block, a.start, a.stop) == (b.block, b.start, b.stop)
        # Normal equations (Cholesky of the moments' Gram matrix against LU of the basis's): rounding.
        for f in ("amp_u", "off_u", "phase_u", "off_y"):
            assert getattr(a, f) == pytest.approx(getattr(b, f), rel=1e-9, abs=1e-12)
        assert a.var_u == pytest.approx(b.var_u, rel=1e-6)
        assert a.var_y == pytest.approx(b.var_y, rel=1e-6)
        assert_allclose(a.harm_y, b.harm_y, rtol=0, atol=1e-10)
    with pytest.raises(InvalidParameterError):
        _core.window_fits(theta, u, y, [5], [5], 3)

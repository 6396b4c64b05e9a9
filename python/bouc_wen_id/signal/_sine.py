"""Sine analysis of the input: frequency, amplitude, phase, offset, distortion (design.md section 8.1).

A Hann-windowed, zero-padded DFT gives the spectral peak; Gauss-Newton least squares (variable projection)
on the frequency and the harmonic coefficients refines it over every sample and reaches the Cramer-Rao
bound for a sine in white noise.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import current_lab
from ..errors import (
    DistortedInputWarning,
    InsufficientDataError,
    InvalidParameterError,
    NotPeriodicError,
    UndersampledError,
    ZeroAmplitudeError,
)
from ..validation import HARMONIC_SNR, MIN_SAMPLES_PER_PERIOD, check_time_axis, finite_arrays
from ._harmonic_ls import fit_at, solve_triangular

__all__ = [
    "SineFit",
    "analyse_sine",
    "InputAnalysis",
    "analyse_input",
    "check_periodic",
    "check_sampling",
    "dft_peak",
    "warn_distortion",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: The input frequency must stay at least this fraction of Nyquist below Nyquist.
NYQUIST_MARGIN = 0.1
#: Fewest input periods :func:`analyse_sine` accepts.
MIN_PERIODS = 2.0
#: Total harmonic distortion of the input above which :class:`DistortedInputWarning` is issued.
THD_WARN = 0.1
#: Smallest fraction of the input's variance that its fundamental and harmonics must explain.
PERIODIC_MIN_FRACTION = 0.5
#: Harmonics of the input fitted for the periodicity check and the THD.
INPUT_HARMONICS = 10
#: Half-width of the band searched around ``nominal_frequency``, relative to it.
NOMINAL_BAND = 0.1
#: A peak in the nominal band is used only if at least this fraction of the global spectral peak.
NOMINAL_PEAK_MIN = 0.1


@dataclass(frozen=True)
class SineFit:
    """A sine fitted to the input: ``u ~ offset + amplitude cos(frequency t - phase)``.

    Attributes
    ----------
    frequency : float
        omega (rad/s), from the nonlinear least-squares fit over all the samples given.
    amplitude : float
        > 0.
    phase : float
        rad, in [0, 2 pi), relative to the absolute time axis ``t`` as given: ``phase / frequency`` is a
        time at which ``u`` peaks (the phase zero), modulo whole periods.
    offset : float
        The DC of ``u``.
    thd : float
        Total harmonic distortion of ``u``, ``sqrt(sum_{k>=2} |c_k|^2) / |c_1|`` over harmonics 2..10 (fewer
        when the sampling or the record does not allow 10), each ``|c_k|^2`` corrected for its expected noise
        power (so a clean sine in white noise gives about 0).
    residual_rms : float
        rms of ``u`` minus the fitted sine (noise plus harmonics).
    frequency_se : float
        Standard error of ``frequency`` from the least-squares covariance; for a sine in white noise it is
        the Cramer-Rao bound ``sqrt(12 sigma^2 / (A^2 dt^2 n (n^2 - 1)))``.
    """

    frequency: float
    amplitude: float
    phase: float
    offset: float
    thd: float
    residual_rms: float
    frequency_se: float

    @property
    def period(self) -> float:
        """``2 pi / frequency`` (s)."""
        return TWO_PI / self.frequency

    @property
    def time_origin(self) -> float:
        """``phase / frequency``: a time (s) at which ``u`` peaks, in ``[0, period)``."""
        return self.phase / self.frequency


def _dot(a: FloatArray, b: FloatArray) -> float:
    """``a . b`` of two long vectors by NumPy's own loops (einsum), not BLAS: a threaded OpenBLAS ``ddot``
    wakes its threads, which on a loaded 2-core machine cost milliseconds per call (issue #8), more than
    the sine analysis itself.  Only the summation order differs (rounding, n eps relative)."""
    return float(np.einsum("i,i->", a, b))


def _peak_bin(spec: FloatArray, lo: int, hi: int, b_lo: int, b_hi: int) -> int:
    """The largest bin of ``spec[lo..=hi]``, or the largest of the band ``[b_lo..=b_hi]`` when that one is a
    local maximum of at least ``NOMINAL_PEAK_MIN`` of it (``rust/lab/spectrum.rs`` chooses alike)."""
    k = lo + int(np.argmax(spec[lo : hi + 1]))
    if b_hi > b_lo:
        kb = b_lo + int(np.argmax(spec[b_lo : b_hi + 1]))
        if spec[kb - 1] < spec[kb] > spec[kb + 1] and spec[kb] >= NOMINAL_PEAK_MIN * spec[k]:
            k = kb
    return k


def dft_peak(x: FloatArray, dt: float, nominal: Optional[float]) -> float:
    """Frequency (rad/s) of the largest spectral peak: Hann window, 4x zero padding, parabolic
    interpolation of the log magnitude.  With ``nominal``, the peak within +-10 % of it wins when it is a
    genuine local maximum of at least 10 % of the global one."""
    n = x.size
    nfft = 1 << math.ceil(math.log2(4 * n))
    pad = nfft / n
    lo = math.ceil(pad)  # one cycle per record
    hi = nfft // 2 - 1  # keep a neighbour on each side for the interpolation
    if n < 2 or hi <= lo:
        raise InsufficientDataError(f"{n} samples are too few to estimate a frequency")
    b_lo = b_hi = -1  # no band
    if nominal is not None:
        centre = nominal * n * dt / TWO_PI * pad  # the nominal frequency in padded bins
        b_lo = max(lo, math.floor(centre * (1.0 - NOMINAL_BAND)))
        b_hi = min(hi, math.ceil(centre * (1.0 + NOMINAL_BAND)))
    # On Rust the same spectrum from a half-length complex FFT, and the same choice of bin, without
    # handing the spectrum back (issue #8).
    peak = current_lab().spectral_peak(x, nfft, lo, hi, b_lo, b_hi, NOMINAL_PEAK_MIN)
    if peak is not None:
        k, around = peak[0], [peak[1], peak[2], peak[3]]
    else:
        idx = np.arange(n, dtype=np.float64) - 0.5 * (n - 1)
        # Remove offset and linear drift: their leakage would otherwise mask a low-frequency tone.
        slope = _dot(idx, x) / _dot(idx, idx)
        xd = x - x.mean() - slope * idx
        spec = np.abs(np.fft.rfft(xd * np.hanning(n), nfft))
        k = _peak_bin(spec, lo, hi, b_lo, b_hi)
        around = [float(v) for v in spec[k - 1 : k + 2]]
    if around[1] <= 0.0:
        raise NotPeriodicError("the input has no spectral peak (it is a constant plus a linear drift)")
    tiny = np.finfo(np.float64).tiny
    l0, l1, l2 = (math.log(max(v, tiny)) for v in around)
    den = l0 - 2.0 * l1 + l2
    delta = 0.5 * (l0 - l2) / den if den < 0.0 else 0.0
    delta = min(max(delta, -0.5), 0.5)
    return float(TWO_PI * (k + delta) / (nfft * dt))


@dataclass
class _NLS:
    """A least-squares fit of ``c + sum_k a_k cos(k omega tau) + b_k sin(k omega tau)``, k = 1..K."""

    omega: float
    coef: FloatArray  # [c, a_1, b_1, a_2, b_2, ...]
    rss: float
    se: float  # standard error of omega


def _omega_column(tau: FloatArray, coef: FloatArray, basis: FloatArray) -> FloatArray:
    """d model / d omega = sum_k k tau (-a_k sin + b_k cos)."""
    k = np.arange(1, (coef.size - 1) // 2 + 1, dtype=np.float64)
    slope = basis[:, 2::2] @ (-k * coef[1::2]) + basis[:, 1::2] @ (k * coef[2::2])
    out: FloatArray = tau * slope
    return out


def _nls(tau: FloatArray, x: FloatArray, omega0: float, dt: float, k: int) -> _NLS:
    """Gauss-Newton on omega and the linear coefficients of a K-harmonic model (variable projection).

    At each omega the linear coefficients are the least-squares solution (QR), and the Gauss-Newton step
    of the full problem reduces to ``d_perp . r / |d_perp|^2``, with ``d = d model / d omega`` and
    ``d_perp`` its part orthogonal to the basis (``Q^T d = R^-T (X^T d)``); ``sigma^2 / |d_perp|^2`` is
    the variance of omega.  Steps are halved until the cost decreases, and the iteration stops when the
    step is below 1e-4 standard errors (or 1e-12 DFT bins, for noise-free data).  With K = 1 this is the
    4-parameter sine fit ``(omega, a, b, c)``.
    """
    # On Rust the same iteration in one call, without forming the basis (issue #8).
    fast = current_lab().nls(tau, x, omega0, dt, k)
    if fast is not None:
        return _NLS(*fast)
    n = x.size
    bin_width = TWO_PI / (n * dt)
    omega = omega0
    lin = fit_at(tau, x, omega, k)
    se = math.inf
    dof = max(n - lin.basis.shape[1] - 1, 1)
    for _ in range(60):
        d = _omega_column(tau, lin.coef, lin.basis)
        q_t_d = solve_triangular(lin.r_factor, lin.basis.T @ d, trans="T")
        d_perp2 = float(d @ d) - float(q_t_d @ q_t_d)
        if not d_perp2 > 0.0:
            break
        se = math.sqrt(lin.rss / dof / d_perp2)
        step = float((x - lin.basis @ lin.coef) @ d) / d_perp2
        step = min(max(step, -0.5 * bin_width), 0.5 * bin_width)
        if not math.isfinite(step) or abs(step) <= max(1e-12 * bin_width, 1e-4 * se):
            break
        # Step halving; a step that fails 10 halvings is below the resolution of the cost (converged).
        previous = lin.rss
        for _half in range(10):
            trial = omega + step
            if trial > 0.0:
                cand = fit_at(tau, x, trial, k)
                if cand.rss <= lin.rss:
                    omega, lin = trial, cand
                    break
            step *= 0.5
        if previous - lin.rss <= 1e-14 * previous:
            break
    return _NLS(omega, lin.coef, lin.rss, se)


@dataclass
class InputAnalysis:
    """What :func:`analyse_input` found: the sine, the share of u it explains, the sampling."""

    fit: SineFit
    explained: float
    samples_per_period: float
    periods: float
    dt: float


def analyse_input(
    t: FloatArray,
    u: FloatArray,
    nominal: Optional[float],
    harmonics: bool = True,
    omega_start: Optional[float] = None,
) -> InputAnalysis:
    """Everything :func:`analyse_sine` computes, without its sampling/period checks and warnings.

    DFT peak, then the 4-parameter sine fit, then a linear fit of harmonics 1..K_h at that frequency
    (K_h = 10, fewer when the sampling or the record does not allow them).  When harmonics stand above the
    noise (power over 16 times their noise power), the frequency is refined once more by the same
    Gauss-Newton on a model holding them: a distorted input's harmonics would otherwise leak into, and
    bias, the fundamental's frequency.  A clean sine skips this (fitting noise harmonics would only add
    variance) and its frequency reaches the Cramer-Rao bound.  Amplitude, phase and offset are those of
    the fundamental in the K_h-harmonic fit; with ``harmonics=False`` only the 4-parameter fit is done
    (and the THD is NaN).
    """
    n = u.size
    if n < 8:
        raise InsufficientDataError(f"at least 8 samples are needed to analyse a sine, got {n}")
    dt = check_time_axis(t)
    spread = float(np.ptp(u))
    if spread == 0.0 or spread <= 1e-12 * float(np.max(np.abs(u))):
        raise ZeroAmplitudeError(f"the input is constant ({u[0]:.6g}): there is no sine to analyse")
    if nominal is not None:
        nominal = float(nominal)
        if not math.isfinite(nominal) or nominal <= 0.0:
            raise InvalidParameterError(f"nominal_frequency = {nominal} rad/s must be finite and > 0")
    omega0 = dft_peak(u, dt, nominal) if omega_start is None else omega_start
    t_ref = float(t[n // 2])
    tau = t - t_ref
    nls = _nls(tau, u, omega0, dt, 1)
    if not (math.isfinite(nls.omega) and nls.omega > 0.0):
        raise NotPeriodicError("no sine could be fitted to the input")
    p = TWO_PI / (nls.omega * dt)
    k_h = max(1, min(INPUT_HARMONICS, int((p - 1.0) // 2), (n // 4 - 1) // 2))
    hf = fit_at(tau, u, nls.omega, k_h)
    coef, var = hf.coef, hf.variances()
    if harmonics and k_h > 1:
        # Refine omega with the harmonics that stand above the noise (none for a clean sine: fitting
        # noise harmonics would only add variance).
        power = (coef[1::2] ** 2 + coef[2::2] ** 2) / np.maximum(var[1::2] + var[2::2], 1e-300)
        significant = np.flatnonzero(power > HARMONIC_SNR)
        k_sig = int(significant[-1]) + 1 if significant.size else 1
        if k_sig > 1:
            nls = _nls(tau, u, nls.omega, dt, k_sig)
            hf = fit_at(tau, u, nls.omega, k_h)
            var = hf.variances()
    coef, rss = hf.coef, hf.rss
    omega = nls.omega
    a1, b1 = float(coef[1]), float(coef[2])
    amp = math.hypot(a1, b1)
    if not (math.isfinite(omega) and omega > 0.0 and amp > 0.0):
        raise NotPeriodicError("no sine could be fitted to the input")
    p = TWO_PI / (omega * dt)
    # How much of u do the fundamental and its harmonics explain (adjusted for their count)?
    centred = u - u.mean()
    ss = _dot(centred, centred)
    dof = n - coef.size
    if dof > 0 and ss > 0.0:
        explained = 1.0 - (rss / dof) / (ss / (n - 1))
    else:
        explained = 1.0 - rss / ss if ss > 0 else 0.0
    thd = math.nan
    if harmonics:
        # Power of harmonics 2..K_h less the noise power of their coefficients.
        excess = coef[3::2] ** 2 + coef[4::2] ** 2 - (var[3::2] + var[4::2])
        thd = math.sqrt(max(float(np.sum(excess)), 0.0)) / amp
    theta = math.atan2(b1, a1)
    fit = SineFit(
        frequency=omega,
        amplitude=amp,
        phase=float(np.mod(theta + omega * t_ref, TWO_PI)),
        offset=float(coef[0]),
        thd=thd,
        residual_rms=math.sqrt(hf.fundamental_rss(u) / n),
        frequency_se=nls.se,
    )
    return InputAnalysis(fit, explained, p, n * dt * omega / TWO_PI, dt)


def check_sampling(ana: InputAnalysis) -> None:
    p = ana.samples_per_period
    f_hz = ana.fit.frequency / TWO_PI
    nyquist = 0.5 / ana.dt
    if p < MIN_SAMPLES_PER_PERIOD or f_hz > (1.0 - NYQUIST_MARGIN) * nyquist:
        raise UndersampledError(
            f"the input's frequency {f_hz:.6g} Hz gives {p:.3g} samples per period at dt = {ana.dt:.6g} s "
            f"(Nyquist {nyquist:.6g} Hz); at least {MIN_SAMPLES_PER_PERIOD} are needed: sample faster"
        )


def check_periodic(ana: InputAnalysis) -> None:
    if ana.explained < PERIODIC_MIN_FRACTION:
        raise NotPeriodicError(
            f"the input is not a periodic excitation: its best sine ({ana.fit.frequency / TWO_PI:.6g} Hz) "
            f"and harmonics explain {max(ana.explained, 0.0):.0%} of its variance "
            f"(< {PERIODIC_MIN_FRACTION:.0%}); noise, a chirp or a sweep cannot be averaged"
        )


def analyse_sine(t: ArrayLike, u: ArrayLike, *, nominal_frequency: Optional[float] = None) -> SineFit:
    """Frequency, amplitude, phase and offset of a sampled sine, with its distortion and uncertainty.

    A Hann-windowed, 4x zero-padded DFT gives the peak (parabolic interpolation of the log magnitude), and
    Gauss-Newton least squares on ``(omega, a, b, offset)`` of ``offset + a cos(omega t) + b sin(omega t)``
    refines it over every sample; the frequency then reaches the Cramer-Rao bound for a sine in white noise.

    Parameters
    ----------
    t, u : array_like
        Uniformly sampled time (s) and input, equal lengths.
    nominal_frequency : float, optional
        A hint (rad/s), not the truth: the spectral peak within +-10 % of it is taken when there is one
        (at least 10 % of the global peak), otherwise the global peak.  The fitted frequency is returned as
        found, however far from the hint (lab generators run a few percent off nominal).

    Returns
    -------
    SineFit

    Raises
    ------
    InvalidParameterError
        Unequal lengths, a non-positive ``nominal_frequency``.
    NonFiniteError
        NaN or infinity in ``t`` or ``u``.
    TimeAxisError
        ``t`` not strictly increasing, or a step more than 1 % away from the median step.
    ZeroAmplitudeError
        ``u`` is constant.
    NotPeriodicError
        The fundamental and its harmonics explain less than half of the variance of ``u`` (noise, chirp).
    UndersampledError
        Fewer than 16 samples per period, or a frequency within 10 % of Nyquist.
    InsufficientDataError
        Fewer than 2 periods (or 8 samples).

    Warns
    -----
    DistortedInputWarning
        The total harmonic distortion of ``u`` exceeds 0.1.
    """
    tt, uu = finite_arrays(t=t, u=u)
    ana = analyse_input(tt, uu, nominal_frequency)
    check_periodic(ana)
    check_sampling(ana)
    # To the nearest sample: round(2 P) samples hold 2 periods.
    if ana.periods < MIN_PERIODS * (1.0 - 0.5 / (MIN_PERIODS * ana.samples_per_period)):
        raise InsufficientDataError(
            f"the input holds {ana.periods:.3g} periods of {ana.fit.frequency / TWO_PI:.6g} Hz; at least "
            f"{MIN_PERIODS:g} are needed"
        )
    warn_distortion(ana.fit, stacklevel=3)
    return ana.fit


def warn_distortion(fit: SineFit, stacklevel: int) -> None:
    if fit.thd > THD_WARN:
        warnings.warn(
            f"the input is far from a pure sine: total harmonic distortion {fit.thd:.3g} > {THD_WARN} "
            f"(at {fit.frequency / TWO_PI:.6g} Hz); the identification assumes u = U cos(omega t)",
            DistortedInputWarning,
            stacklevel=stacklevel,
        )


# ------------------------------------------------------------------------------------------------------
# Steady segments

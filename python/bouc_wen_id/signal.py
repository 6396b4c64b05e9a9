"""Preprocessing of lab recordings: sine analysis, steady-segment detection, synchronous averaging.

The identification (:mod:`bouc_wen_id.identification`) needs one averaged period ``ybar`` per experiment on a
grid whose time origin is the input's phase zero (``u = U cos(omega t)`` at ``t = 0``).  Simulated data give
that grid for free: a whole number of samples per period and ``u`` starting at its peak.  Lab recordings do
not: the true frequency is off nominal (DAQ clock against signal generator), so a period holds a non-integer
number of samples; the steady periods sit between idle stretches, amplitude ramps and pauses; offsets,
quantisation and raw DAQ units come on top.  This module turns ``(t, u, y)`` arrays into such averaged
periods in three steps.

1. :func:`analyse_sine` estimates frequency, amplitude, phase and offset of ``u`` (windowed-DFT peak, then
   nonlinear least squares, which reaches the Cramer-Rao bound; the input's own harmonics are fitted too
   when they stand above the noise, so that they do not bias it) and checks that ``u`` is a usable sine.
2. :func:`find_steady_segments` cuts a record into its steady stretches of whole periods (one experiment
   each) and says why everything else was dropped.
3. :func:`synchronous_average` fits ``y`` over a steady stretch by linear least squares on harmonics of the
   input frequency and evaluates one period on ``P = 2K + 1`` points from the input's phase zero.  With an
   integer number of samples per period, whole periods and all harmonics it is exactly the paper's periodic
   average (4a-b) (:func:`average_exact`).

Reasons given for dropped stretches (:class:`SegmentReport`)
-------------------------------------------------------------
``"idle"``
    The input's fundamental is below 5 % of the record's steady amplitude (or below its noise) at the start
    or the end of the record.
``"pause"``
    The same between two active stretches (a test, then a pause, then the next test), across gaps of the
    time axis (DAQ pauses) too.
``"amplitude ramp"``
    At least two consecutive periods whose input amplitude moves the same way, by more than 5 % each,
    next to rest or a steady level.
``"level change"``
    The unsteady stretch between two steady levels that differ (input amplitude or offset, output
    waveform or offset).
``"transient"``
    Any other unsteady stretch: a one-period start or stop, a glitch, a phase jump, an output settling,
    the end period of a steady stretch that stands out of it.
``"too short"``
    Steady, but fewer whole periods than ``min_periods``.
``"partial period"``
    Less than one period left over at the end of a contiguous block or next to a kept segment.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_triangular  # type: ignore[import-untyped]
from scipy.special import chdtri  # type: ignore[import-untyped]

from .errors import (
    DistortedInputWarning,
    InsufficientDataError,
    InvalidParameterError,
    NotPeriodicError,
    TimeAxisError,
    UndersampledError,
    ZeroAmplitudeError,
)
from .reference import _finite_array

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .measurement import Measurement

__all__ = [
    "SineFit",
    "analyse_sine",
    "Segment",
    "SegmentReport",
    "find_steady_segments",
    "AveragedPeriod",
    "synchronous_average",
    "average_exact",
    "average_measurement",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Largest deviation of one time step from the median step, relative to it (a uniform grid is assumed).
TIME_JITTER_RTOL = 0.01
#: A time step longer than this multiple of the median step is a gap (a DAQ pause) in
#: :func:`find_steady_segments`; everywhere else it is a :class:`TimeAxisError`.
TIME_GAP_FACTOR = 1.5
#: Fewest samples per period of the input accepted (and the frequency must stay this far below Nyquist).
MIN_SAMPLES_PER_PERIOD = 16
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
#: A harmonic of ``y`` is signal when its power exceeds this multiple of its noise power (as
#: ``identification.HARMONIC_SNR``: a false alarm has probability e^-16 per harmonic).
HARMONIC_SNR = 16.0
#: Default harmonic count: this many times the last significant harmonic (the Bouc-Wen loop's harmonics
#: decay like k^-3; beyond 4 K_sig the aliased tail is a small fraction of the per-point noise).
HARMONIC_SAFETY = 4
#: ... but at least this many harmonics (when the data allow them).
MIN_HARMONICS = 8
#: ... and never more than this many.
MAX_HARMONICS = 200
#: Harmonic fits costing more than this many flops (``n (2K+1)^2``) by QR use the moment path instead.
QR_WORK_MAX = 1e9
#: Rows per chunk of the blocked QR.
QR_CHUNK = 8192

# Steady-segment detection.
#: A window whose input fundamental is below this fraction of the record's steady amplitude is idle.
IDLE_FRACTION = 0.05
#: Relative tolerance of "steady" for the input amplitude and offset (relative to the amplitude).
STEADY_RTOL_U = 0.05
#: Relative tolerance of "steady" for the output's harmonics and offset (relative to their norm).
STEADY_RTOL_Y = 0.08
#: Tolerance (rad) on the change of the input's phase advance from one period to the next.
STEADY_PHASE_TOL = 0.05
#: Differences within this many noise standard deviations are always steady.
STEADY_NOISE_Z = 4.0
#: An end window of a steady run is dropped when further from the run's median than this many robust
#: standard deviations of the run's own period-to-period scatter ...
EDGE_Z = 4.0
#: ... and than these fractions of its median input amplitude and output harmonic norm (plus noise).
EDGE_RTOL_U = 0.01
EDGE_RTOL_Y = 0.02
#: A run's leading (trailing) windows are dropped while their mean output waveform differs from the mean
#: of the rest of the run at this significance (a chi-square test at the precision of the average, with
#: the per-period scatter from successive differences): an output still settling after the ramp, which
#: the per-window test above misses when it is small against one period's noise but not against N's.
SETTLE_ALPHA = 1e-3
#: ... but at most this fraction of a run is dropped from each end that way (slow drift is not settling).
SETTLE_MAX_FRACTION = 0.25
#: ... and only in runs of at least this many periods (the scatter of a shorter run is not known well).
SETTLE_MIN_WINDOWS = 8
#: Harmonics of ``y`` compared from period to period (the waveform).
WINDOW_HARMONICS = 8


# ------------------------------------------------------------------------------------------------------
# Validation helpers


# 1-D float64, finite: the same check as the NumPy reference's inputs.
_array = _finite_array


def _arrays(**named: ArrayLike) -> list[FloatArray]:
    out = [_array(name, v) for name, v in named.items()]
    sizes = {name: a.size for name, a in zip(named, out)}
    if len(set(sizes.values())) != 1:
        raise InvalidParameterError(f"{', '.join(named)} must have equal lengths, got {sizes}")
    return out


def _steps(t: FloatArray) -> tuple[FloatArray, float]:
    """Time steps and their median; refuses a time axis that is not strictly increasing."""
    if t.size < 2:
        raise InsufficientDataError(f"at least 2 samples are needed, got {t.size}")
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        bad = int(np.flatnonzero(steps <= 0.0)[0])
        raise TimeAxisError(
            f"the time axis is not strictly increasing: t[{bad + 1}] = {t[bad + 1]:.9g} s follows "
            f"t[{bad}] = {t[bad]:.9g} s"
        )
    return steps, float(np.median(steps))


def _uniform_step(t: FloatArray) -> float:
    """The sampling step of a uniform time axis; :class:`TimeAxisError` if it jitters or has gaps."""
    steps, dt = _steps(t)
    dev = float(np.max(np.abs(steps - dt)))
    if dev > TIME_JITTER_RTOL * dt:
        bad = int(np.argmax(np.abs(steps - dt)))
        raise TimeAxisError(
            f"the time step is not uniform: step {bad} is {steps[bad]:.6g} s against a median of {dt:.6g} s "
            f"(tolerance {TIME_JITTER_RTOL:.0%}); resample, or cut the record at its gaps"
        )
    return dt


# ------------------------------------------------------------------------------------------------------
# Sine analysis


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


def _harmonic_basis(theta: FloatArray, harmonics: int) -> FloatArray:
    """``[1, cos(theta), sin(theta), cos(2 theta), sin(2 theta), ...]`` up to ``harmonics``.

    The harmonics come from the angle-addition recurrence (rounding grows like k eps: 1e-13 at k = 200).
    """
    out = np.empty((theta.size, 2 * harmonics + 1), order="F")
    out[:, 0] = 1.0
    c1, s1 = np.cos(theta), np.sin(theta)
    out[:, 1], out[:, 2] = c1, s1
    for k in range(2, harmonics + 1):
        c, s = out[:, 2 * k - 3], out[:, 2 * k - 2]
        out[:, 2 * k - 1] = c * c1 - s * s1
        out[:, 2 * k] = s * c1 + c * s1
    return out


def _phase(omega: float, tau: FloatArray) -> FloatArray:
    out: FloatArray = np.mod(omega * tau, TWO_PI)
    return out


def _dft_peak(x: FloatArray, dt: float, nominal: Optional[float]) -> float:
    """Frequency (rad/s) of the largest spectral peak: Hann window, 4x zero padding, parabolic
    interpolation of the log magnitude.  With ``nominal``, the peak within +-10 % of it wins when it is a
    genuine local maximum of at least 10 % of the global one."""
    n = x.size
    idx = np.arange(n, dtype=np.float64) - 0.5 * (n - 1)
    # Remove offset and linear drift: their leakage would otherwise mask a low-frequency tone.
    slope = float(np.dot(idx, x) / np.dot(idx, idx))
    xd = x - x.mean() - slope * idx
    nfft = 1 << math.ceil(math.log2(4 * n))
    spec = np.abs(np.fft.rfft(xd * np.hanning(n), nfft))
    pad = nfft / n
    lo = math.ceil(pad)  # one cycle per record
    hi = spec.size - 2  # keep a neighbour on each side for the interpolation
    if hi <= lo:
        raise InsufficientDataError(f"{n} samples are too few to estimate a frequency")
    k = lo + int(np.argmax(spec[lo : hi + 1]))
    if nominal is not None:
        centre = nominal * n * dt / TWO_PI * pad  # the nominal frequency in padded bins
        b_lo = max(lo, math.floor(centre * (1.0 - NOMINAL_BAND)))
        b_hi = min(hi, math.ceil(centre * (1.0 + NOMINAL_BAND)))
        if b_hi > b_lo:
            kb = b_lo + int(np.argmax(spec[b_lo : b_hi + 1]))
            if spec[kb - 1] < spec[kb] > spec[kb + 1] and spec[kb] >= NOMINAL_PEAK_MIN * spec[k]:
                k = kb
    if spec[k] <= 0.0:
        raise NotPeriodicError("the input has no spectral peak (it is a constant plus a linear drift)")
    tiny = np.finfo(np.float64).tiny
    l0, l1, l2 = (math.log(max(float(v), tiny)) for v in spec[k - 1 : k + 2])
    den = l0 - 2.0 * l1 + l2
    delta = 0.5 * (l0 - l2) / den if den < 0.0 else 0.0
    delta = min(max(delta, -0.5), 0.5)
    return TWO_PI * (k + delta) / (nfft * dt)


@dataclass
class _NLS:
    """A least-squares fit of ``c + sum_k a_k cos(k omega tau) + b_k sin(k omega tau)``, k = 1..K."""

    omega: float
    coef: FloatArray  # [c, a_1, b_1, a_2, b_2, ...]
    rss: float
    se: float  # standard error of omega


def _solve_qr(matrix: FloatArray, rhs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Least squares by Householder QR of ``[A b]`` (no Q formed): ``(solution, R)``.

    A rank-deficient basis (a harmonic at Nyquist, a record shorter than the basis) falls back to the
    minimum-norm SVD solution, with a scaled identity standing in for R (the variances derived from it
    are then meaningless, but such inputs are refused as undersampled or too short anyway).
    """
    m = matrix.shape[1]
    r_aug = np.asarray(np.linalg.qr(np.column_stack([matrix, rhs]), mode="r"), dtype=np.float64)
    r = r_aug[:m, :m]
    diag = np.abs(np.diag(r)) if r.shape[0] == m else np.zeros(m)
    if diag.min() <= 1e-12 * max(float(diag.max()), np.finfo(np.float64).tiny):
        sol_ls = np.asarray(np.linalg.lstsq(matrix, rhs, rcond=None)[0], dtype=np.float64)
        return sol_ls, np.eye(m) * max(float(diag.max()), 1.0)
    sol: FloatArray = solve_triangular(r, r_aug[:m, m])
    return sol, r


@dataclass
class _LinearFit:
    coef: FloatArray
    rss: float
    basis: FloatArray
    r_factor: FloatArray


def _linear_fit(tau: FloatArray, x: FloatArray, omega: float, k: int) -> _LinearFit:
    basis = _harmonic_basis(_phase(omega, tau), k)
    coef, r_factor = _solve_qr(basis, x)
    r = x - basis @ coef
    return _LinearFit(coef, float(r @ r), basis, r_factor)


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
    n = x.size
    bin_width = TWO_PI / (n * dt)
    omega = omega0
    lin = _linear_fit(tau, x, omega, k)
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
                cand = _linear_fit(tau, x, trial, k)
                if cand.rss <= lin.rss:
                    omega, lin = trial, cand
                    break
            step *= 0.5
        if previous - lin.rss <= 1e-14 * previous:
            break
    return _NLS(omega, lin.coef, lin.rss, se)


@dataclass
class _InputAnalysis:
    fit: SineFit
    explained: float
    samples_per_period: float
    periods: float
    dt: float


def _analyse(
    t: FloatArray,
    u: FloatArray,
    nominal: Optional[float],
    harmonics: bool = True,
    omega_start: Optional[float] = None,
) -> _InputAnalysis:
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
    dt = _uniform_step(t)
    spread = float(np.ptp(u))
    if spread == 0.0 or spread <= 1e-12 * float(np.max(np.abs(u))):
        raise ZeroAmplitudeError(f"the input is constant ({u[0]:.6g}): there is no sine to analyse")
    if nominal is not None:
        nominal = float(nominal)
        if not math.isfinite(nominal) or nominal <= 0.0:
            raise InvalidParameterError(f"nominal_frequency = {nominal} rad/s must be finite and > 0")
    omega0 = _dft_peak(u, dt, nominal) if omega_start is None else omega_start
    t_ref = float(t[n // 2])
    tau = t - t_ref
    nls = _nls(tau, u, omega0, dt, 1)
    if not (math.isfinite(nls.omega) and nls.omega > 0.0):
        raise NotPeriodicError("no sine could be fitted to the input")
    p = TWO_PI / (nls.omega * dt)
    k_h = max(1, min(INPUT_HARMONICS, int((p - 1.0) // 2), (n // 4 - 1) // 2))
    coef, rss, var, basis = _harmonics_of(tau, u, nls.omega, k_h)
    if harmonics and k_h > 1:
        # Refine omega with the harmonics that stand above the noise (none for a clean sine: fitting
        # noise harmonics would only add variance).
        power = (coef[1::2] ** 2 + coef[2::2] ** 2) / np.maximum(var[1::2] + var[2::2], 1e-300)
        significant = np.flatnonzero(power > HARMONIC_SNR)
        k_sig = int(significant[-1]) + 1 if significant.size else 1
        if k_sig > 1:
            nls = _nls(tau, u, nls.omega, dt, k_sig)
            coef, rss, var, basis = _harmonics_of(tau, u, nls.omega, k_h)
    omega = nls.omega
    a1, b1 = float(coef[1]), float(coef[2])
    amp = math.hypot(a1, b1)
    if not (math.isfinite(omega) and omega > 0.0 and amp > 0.0):
        raise NotPeriodicError("no sine could be fitted to the input")
    p = TWO_PI / (omega * dt)
    # How much of u do the fundamental and its harmonics explain (adjusted for their count)?
    centred = u - u.mean()
    ss = float(centred @ centred)
    dof = n - basis.shape[1]
    if dof > 0 and ss > 0.0:
        explained = 1.0 - (rss / dof) / (ss / (n - 1))
    else:
        explained = 1.0 - rss / ss if ss > 0 else 0.0
    thd = math.nan
    if harmonics:
        # Power of harmonics 2..K_h less the noise power of their coefficients.
        excess = coef[3::2] ** 2 + coef[4::2] ** 2 - (var[3::2] + var[4::2])
        thd = math.sqrt(max(float(np.sum(excess)), 0.0)) / amp
    sine_only = u - coef[0] - a1 * basis[:, 1] - b1 * basis[:, 2]
    theta = math.atan2(b1, a1)
    fit = SineFit(
        frequency=omega,
        amplitude=amp,
        phase=float(np.mod(theta + omega * t_ref, TWO_PI)),
        offset=float(coef[0]),
        thd=thd,
        residual_rms=math.sqrt(float(sine_only @ sine_only) / n),
        frequency_se=nls.se,
    )
    return _InputAnalysis(fit, explained, p, n * dt * omega / TWO_PI, dt)


def _harmonics_of(
    tau: FloatArray, x: FloatArray, omega: float, k: int
) -> tuple[FloatArray, float, FloatArray, FloatArray]:
    """Linear fit on harmonics 1..k at a fixed omega: coefficients, residual, the noise variance of each
    coefficient (residual variance times the diagonal of ``(X^T X)^-1``), and the basis."""
    basis = _harmonic_basis(_phase(omega, tau), k)
    coef, r_factor = _solve_qr(basis, x)
    resid = x - basis @ coef
    rss = float(resid @ resid)
    dof = x.size - basis.shape[1]
    try:
        r_inv = solve_triangular(r_factor, np.eye(basis.shape[1]))
        var = np.sum(r_inv**2, axis=1) * (rss / dof if dof > 0 else 0.0)
    except np.linalg.LinAlgError:
        var = np.zeros(basis.shape[1])
    return coef, rss, var, basis


def _check_sampling(ana: _InputAnalysis) -> None:
    p = ana.samples_per_period
    f_hz = ana.fit.frequency / TWO_PI
    nyquist = 0.5 / ana.dt
    if p < MIN_SAMPLES_PER_PERIOD or f_hz > (1.0 - NYQUIST_MARGIN) * nyquist:
        raise UndersampledError(
            f"the input's frequency {f_hz:.6g} Hz gives {p:.3g} samples per period at dt = {ana.dt:.6g} s "
            f"(Nyquist {nyquist:.6g} Hz); at least {MIN_SAMPLES_PER_PERIOD} are needed: sample faster"
        )


def _check_periodic(ana: _InputAnalysis) -> None:
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
    tt, uu = _arrays(t=t, u=u)
    ana = _analyse(tt, uu, nominal_frequency)
    _check_periodic(ana)
    _check_sampling(ana)
    # To the nearest sample: round(2 P) samples hold 2 periods.
    if ana.periods < MIN_PERIODS * (1.0 - 0.5 / (MIN_PERIODS * ana.samples_per_period)):
        raise InsufficientDataError(
            f"the input holds {ana.periods:.3g} periods of {ana.fit.frequency / TWO_PI:.6g} Hz; at least "
            f"{MIN_PERIODS:g} are needed"
        )
    _warn_distortion(ana.fit, stacklevel=3)
    return ana.fit


def _warn_distortion(fit: SineFit, stacklevel: int) -> None:
    if fit.thd > THD_WARN:
        warnings.warn(
            f"the input is far from a pure sine: total harmonic distortion {fit.thd:.3g} > {THD_WARN} "
            f"(at {fit.frequency / TWO_PI:.6g} Hz); the identification assumes u = U cos(omega t)",
            DistortedInputWarning,
            stacklevel=stacklevel,
        )


# ------------------------------------------------------------------------------------------------------
# Steady segments


@dataclass(frozen=True)
class Segment:
    """A steady stretch ``[start, stop)`` of whole input periods (``periods`` of them, to rounding)."""

    start: int
    stop: int
    periods: float

    @property
    def slice(self) -> slice:
        """``slice(start, stop)``, to index the record's arrays."""
        return slice(self.start, self.stop)


@dataclass(frozen=True)
class SegmentReport:
    """What :func:`find_steady_segments` kept and dropped.

    ``dropped`` holds ``(start, stop, reason)`` for every stretch of samples not kept, in record order; the
    reasons are listed in the module documentation.  ``fits`` holds one :class:`SineFit` of the input per
    kept segment, fitted on that segment.
    """

    kept: tuple[Segment, ...]
    dropped: tuple[tuple[int, int, str], ...]
    fits: tuple[SineFit, ...]

    def summary(self) -> str:
        lines = [f"{len(self.kept)} steady segment(s):"]
        for seg, fit in zip(self.kept, self.fits):
            lines.append(
                f"  [{seg.start}, {seg.stop}): {seg.periods:.2f} periods at {fit.frequency / TWO_PI:.6g} Hz, "
                f"U = {fit.amplitude:.4g}, THD = {fit.thd:.3g}"
            )
        for start, stop, reason in self.dropped:
            lines.append(f"  dropped [{start}, {stop}): {reason}")
        return "\n".join(lines)


@dataclass
class _Window:
    block: int
    start: int
    stop: int
    amp_u: float
    off_u: float
    phase_u: float
    var_u: float
    harm_y: NDArray[np.complex128]
    off_y: float
    var_y: float
    idle: bool = False
    run: int = -1
    label: str = ""

    @property
    def size(self) -> int:
        return self.stop - self.start

    @property
    def norm_y(self) -> float:
        return float(np.linalg.norm(self.harm_y))


def _window_features(
    block: int, start: int, stop: int, basis: FloatArray, u: FloatArray, y: FloatArray
) -> _Window:
    k_w = (basis.shape[1] - 1) // 2
    rhs = np.column_stack([u, y])
    # Over one period the harmonics are orthogonal to within about 1/P (the Gram matrix is nearly
    # diagonal), so the small normal equations lose nothing here and are much cheaper than an SVD.
    try:
        coef = np.linalg.solve(basis.T @ basis, basis.T @ rhs)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(basis, rhs, rcond=None)[0]
    resid = rhs - basis @ coef
    dof = max(u.size - basis.shape[1], 1)
    var_u, var_y = (float(v) for v in np.sum(resid**2, axis=0) / dof)
    c_u = complex(coef[1, 0], -coef[2, 0])
    h_y = coef[1::2, 1] - 1j * coef[2::2, 1]
    ph = math.atan2(c_u.imag, c_u.real)
    # The output's harmonics relative to the input's phase: the waveform, whatever the window's start.
    h_rel = h_y * np.exp(-1j * np.arange(1, k_w + 1) * ph)
    return _Window(
        block, start, stop, abs(c_u), float(coef[0, 0]), ph, var_u, h_rel, float(coef[0, 1]), var_y
    )


def _wrap(x: float) -> float:
    return (x + math.pi) % TWO_PI - math.pi


@dataclass
class _Level:
    """Median features of a run of windows (or a single window)."""

    amp_u: float
    off_u: float
    harm_y: NDArray[np.complex128]
    off_y: float
    var_u: float
    var_y: float
    size: int

    @property
    def norm_y(self) -> float:
        return float(np.linalg.norm(self.harm_y))


def _level(ws: Sequence[_Window]) -> _Level:
    h = np.array([w.harm_y for w in ws])
    return _Level(
        float(np.median([w.amp_u for w in ws])),
        float(np.median([w.off_u for w in ws])),
        np.median(h.real, axis=0) + 1j * np.median(h.imag, axis=0),
        float(np.median([w.off_y for w in ws])),
        float(np.median([w.var_u for w in ws])),
        float(np.median([w.var_y for w in ws])),
        int(np.median([w.size for w in ws])),
    )


def _distance(a: _Level | _Window, b: _Level | _Window) -> float:
    """How far apart two periods (or levels) are, in units of the steadiness tolerance (> 1: not steady)."""
    size = min(a.size, b.size)
    noise_u = math.sqrt(2.0 * (a.var_u + b.var_u) / size)
    noise_y = math.sqrt(2.0 * (a.var_y + b.var_y) / size)
    k_w = a.harm_y.size
    amp = max(a.amp_u, b.amp_u)
    d_amp = abs(a.amp_u - b.amp_u) / (STEADY_RTOL_U * amp + STEADY_NOISE_Z * noise_u)
    d_off = abs(a.off_u - b.off_u) / (STEADY_RTOL_U * amp + STEADY_NOISE_Z * noise_u)
    norm_y = max(a.norm_y, b.norm_y)
    d_wave = float(np.linalg.norm(a.harm_y - b.harm_y)) / (
        STEADY_RTOL_Y * norm_y + STEADY_NOISE_Z * noise_y * math.sqrt(k_w) + 1e-300
    )
    d_off_y = abs(a.off_y - b.off_y) / (STEADY_RTOL_Y * norm_y + STEADY_NOISE_Z * noise_y + 1e-300)
    return max(d_amp, d_off, d_wave, d_off_y)


def _trim_edges(windows: Sequence[_Window], i: int, j: int) -> tuple[int, int]:
    """Drop the end windows of a run ``[i, j)`` that stand out from its interior: the last period of a
    ramp or the output still settling, within the general tolerance but beyond the run's own scatter."""
    while j - i >= 2:
        bad = _outliers(windows[i:j])
        if bad[0]:
            i += 1
        elif bad[-1]:
            j -= 1
        else:
            break
    return i, j


def _trim_settling(windows: Sequence[_Window], i: int, j: int) -> tuple[int, int]:
    """Drop the leading and trailing windows of a run ``[i, j)`` whose mean output waveform differs from
    the mean of the rest at the precision of the final average (see :data:`SETTLE_ALPHA`).

    Harmonic by harmonic (settling of the linear part shows mostly in the fundamental, and a test on all
    harmonics at once would dilute it), the mean of the first ``k`` windows is compared with the mean of
    the others for every split ``k`` up to half the run: a chi-square statistic on 2 degrees of freedom
    with the harmonic's per-window scatter from successive differences (noise and fast wander, not a slow
    trend), Bonferroni-corrected over the splits and harmonics scanned.
    """
    n0 = j - i
    if n0 < SETTLE_MIN_WINDOWS:
        return i, j
    cap = max(1, int(SETTLE_MAX_FRACTION * n0))
    h_all = np.array([w.harm_y for w in windows[i:j]])  # (n, K) complex
    # E|d|^2 of a successive difference is 2 * (2 s^2) per harmonic; the median of chi2_2 is 2 ln 2.
    # White noise has the same scatter at every harmonic (an orthogonal basis): the pooled estimate is the
    # stable one on a short run, the per-harmonic one keeps a harmonic's own wander.
    d2 = np.abs(np.diff(h_all, axis=0)) ** 2 / (4.0 * math.log(2.0))
    s2 = np.maximum(np.median(d2, axis=0), float(np.median(d2)))
    usable = s2 > 0.0
    if not np.any(usable):
        return i, j
    h_all, s2 = h_all[:, usable], s2[usable]

    def head_differs(h: NDArray[np.complex128]) -> bool:
        n = h.shape[0]
        if n < 4:
            return False
        m = n // 2
        csum = np.cumsum(h, axis=0)
        k = np.arange(1, m + 1)
        head = csum[:m] / k[:, None]
        tail = (csum[-1] - csum[:m]) / (n - k)[:, None]
        q = np.abs(head - tail) ** 2 / (s2[None, :] * (1.0 / k + 1.0 / (n - k))[:, None])
        return bool(np.max(q) > float(chdtri(2, SETTLE_ALPHA / q.size)))

    lo, hi = 0, n0
    while lo < cap and head_differs(h_all[lo:hi]):
        lo += 1
    while n0 - hi < cap and head_differs(h_all[lo:hi][::-1]):
        hi -= 1
    return i + lo, i + hi


def _outliers(run: Sequence[_Window]) -> NDArray[np.bool_]:
    """Windows of a run off its median by more than 4 robust standard deviations of the run's scatter
    (and more than 1 % of the input amplitude or 2 % of the output's harmonics, and their noise)."""
    amps = np.array([w.amp_u for w in run])
    med = float(np.median(amps))
    spread_u = 1.4826 * float(np.median(np.abs(amps - med)))
    harm = np.array([w.harm_y for w in run])
    h_med = np.median(harm.real, axis=0) + 1j * np.median(harm.imag, axis=0)
    dev_h = np.linalg.norm(harm - h_med, axis=1)
    spread_h = 1.4826 * float(np.median(dev_h))
    sizes = np.array([w.size for w in run], dtype=np.float64)
    noise_u = STEADY_NOISE_Z * np.sqrt(2.0 * np.array([w.var_u for w in run]) / sizes)
    noise_y = STEADY_NOISE_Z * np.sqrt(2.0 * h_med.size * np.array([w.var_y for w in run]) / sizes)
    bad_u = np.abs(amps - med) > max(EDGE_Z * spread_u, EDGE_RTOL_U * med) + noise_u
    bad_y = dev_h > max(EDGE_Z * spread_h, EDGE_RTOL_Y * float(np.linalg.norm(h_med))) + noise_y
    out: NDArray[np.bool_] = bad_u | bad_y
    return out


def _block_frequency(t: FloatArray, u: FloatArray, dt: float, nominal: Optional[float]) -> Optional[float]:
    """A rough frequency of one contiguous block (DFT peak), or None when it has none."""
    if u.size < 8 or np.ptp(u) == 0.0:
        return None
    try:
        return _dft_peak(u, dt, nominal)
    except (InsufficientDataError, NotPeriodicError):
        return None


def find_steady_segments(
    t: ArrayLike,
    u: ArrayLike,
    y: ArrayLike,
    *,
    nominal_frequency: Optional[float] = None,
    min_periods: float = 2.0,
) -> SegmentReport:
    """Cut a record into its steady stretches of whole input periods, one experiment each.

    The time axis may have gaps (a step longer than 1.5 times the median, e.g. a DAQ pause); the record is
    analysed block by block between them.  In each block the input frequency is estimated (DFT peak), the
    block is cut into period-long windows, and in each window the input's fundamental (amplitude, offset,
    phase) and the output's first 8 harmonics relative to the input's phase (its waveform) and offset are
    fitted by least squares, with the residual noise.

    - A window is *idle* when its input amplitude is below 5 % of the record's steady amplitude (the
      largest median of three consecutive windows) or below 4 noise standard deviations.
    - Two consecutive non-idle windows are *steady together* when their input amplitudes and offsets differ
      by less than 5 % of the amplitude, their output harmonic vectors and offsets by less than 8 % of the
      output's harmonic norm (plus 4 noise standard deviations in each case: what white noise explains),
      and the input's phase advance from one period to the next stays within 0.05 rad (plus noise) of the
      block's typical advance (a phase jump or a change of frequency breaks the run).  The relative
      tolerances absorb the period-to-period wander of real actuators (1-3 %), which white noise does not
      explain.
    - Maximal runs of windows steady together, whose every window also lies within the same tolerances of
      the run's median, are the steady stretches.  Their end windows are then dropped while they stand out
      of the run: further from its median than 4 robust standard deviations of the run's own scatter and
      than 1 % (input amplitude) or 2 % (output harmonics) of it, plus noise (the last period of a ramp, an
      output still settling).
    - Steady stretches of at least ``min_periods`` periods are kept (at least two periods are always
      needed to call a stretch steady).  Each starts at its first window and spans a whole number of
      periods of its own frequency, fitted on it as by :func:`analyse_sine`.

    Parameters
    ----------
    t, u, y : array_like
        Time (s), input and output, equal lengths.
    nominal_frequency : float, optional
        Hint for the input frequency (rad/s), see :func:`analyse_sine`.
    min_periods : float
        Fewest whole steady periods a kept segment must span (>= 1).

    Returns
    -------
    SegmentReport

    Raises
    ------
    InsufficientDataError
        Nothing steady of ``min_periods`` periods was found (the message says what the record holds).
    UndersampledError, NotPeriodicError, ZeroAmplitudeError, TimeAxisError, NonFiniteError,
    InvalidParameterError
        As :func:`analyse_sine`, for the record as a whole or for a kept segment.

    Warns
    -----
    DistortedInputWarning
        A kept segment's input has a total harmonic distortion above 0.1.
    """
    tt, uu, yy = _arrays(t=t, u=u, y=y)
    mp = float(min_periods)
    if not math.isfinite(mp) or mp < 1.0:
        raise InvalidParameterError(f"min_periods = {min_periods} must be a finite number >= 1")
    need = math.ceil(mp - 1e-9)
    n = tt.size
    if n < 8:
        raise InsufficientDataError(f"at least 8 samples are needed, got {n}")
    if nominal_frequency is not None and not (
        math.isfinite(float(nominal_frequency)) and float(nominal_frequency) > 0.0
    ):
        raise InvalidParameterError(f"nominal_frequency = {nominal_frequency} rad/s must be finite and > 0")
    steps, dt = _steps(tt)
    gap = steps > TIME_GAP_FACTOR * dt
    jitter = ~gap & (np.abs(steps - dt) > TIME_JITTER_RTOL * dt)
    if np.any(jitter):
        bad = int(np.flatnonzero(jitter)[0])
        raise TimeAxisError(
            f"the time step is not uniform: step {bad} is {steps[bad]:.6g} s against a median of {dt:.6g} s "
            f"(tolerance {TIME_JITTER_RTOL:.0%}; steps over {TIME_GAP_FACTOR}x the median count as gaps)"
        )
    spread = float(np.ptp(uu))
    if spread == 0.0 or spread <= 1e-12 * float(np.max(np.abs(uu))):
        raise ZeroAmplitudeError(f"the input is constant ({uu[0]:.6g}): there is no sine to find")
    edges = np.concatenate([[0], np.flatnonzero(gap) + 1, [n]])
    blocks = [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]
    # The record's frequency: the block holding most of the input's energy.
    energy = [float(np.sum((uu[a:b] - uu[a:b].mean()) ** 2)) for a, b in blocks]
    main = int(np.argmax(energy))
    a0, b0 = blocks[main]
    omega_main = _block_frequency(tt[a0:b0], uu[a0:b0], dt, nominal_frequency)
    if omega_main is None:
        raise NotPeriodicError("no periodic input found in the record")
    p_main = TWO_PI / (omega_main * dt)
    if p_main < MIN_SAMPLES_PER_PERIOD or omega_main * dt > (1.0 - NYQUIST_MARGIN) * math.pi:
        raise UndersampledError(
            f"the input's frequency {omega_main / TWO_PI:.6g} Hz gives {p_main:.3g} samples per period at "
            f"dt = {dt:.6g} s; at least {MIN_SAMPLES_PER_PERIOD} are needed: sample faster"
        )
    windows: list[_Window] = []
    block_omega: list[float] = []
    for bi, (a, b) in enumerate(blocks):
        omega = omega_main
        if bi != main and b - a >= 3 * p_main:
            cand = _block_frequency(tt[a:b], uu[a:b], dt, nominal_frequency)
            if cand is not None:
                p_c = TWO_PI / (cand * dt)
                if p_c >= MIN_SAMPLES_PER_PERIOD and (b - a) >= 2 * p_c:
                    omega = cand
        block_omega.append(omega)
        p = TWO_PI / (omega * dt)
        k_w = max(1, min(WINDOW_HARMONICS, int((p - 1.0) // 2) - 1))
        basis = _harmonic_basis(_phase(omega, tt[a:b] - tt[a]), k_w)
        # Whole periods; the last may be up to 5 % short (a record of exactly N periods at a frequency
        # estimated a hair low).
        count = math.floor((b - a) / p + 0.05)
        for i in range(count):
            s, e = math.floor(i * p), min(math.floor((i + 1) * p), b - a)
            windows.append(
                _window_features(bi, a + s, a + e, basis[s:e], uu[a + s : a + e], yy[a + s : a + e])
            )
    total_periods = float(sum((b - a) * dt * w / TWO_PI for (a, b), w in zip(blocks, block_omega)))
    if not windows:
        raise InsufficientDataError(
            f"the record holds {total_periods:.3g} periods of {omega_main / TWO_PI:.6g} Hz: not one whole "
            "period to analyse"
        )
    amps = np.array([w.amp_u for w in windows])
    smooth = np.array([np.median(amps[max(i - 1, 0) : i + 2]) for i in range(amps.size)])
    a_ref = float(np.max(smooth))
    for w in windows:
        noise = math.sqrt(2.0 * w.var_u / w.size)
        w.idle = w.amp_u < IDLE_FRACTION * a_ref or w.amp_u < STEADY_NOISE_Z * noise

    # Links between consecutive windows of a block: steady together?
    link = [False] * len(windows)  # link[i]: window i is steady together with window i - 1
    for bi in range(len(blocks)):
        pairs = [
            i
            for i, w in enumerate(windows)
            if w.block == bi and i > 0 and windows[i - 1].block == bi and not (w.idle or windows[i - 1].idle)
        ]
        close = {i: _distance(windows[i - 1], windows[i]) <= 1.0 for i in pairs}
        adv = {i: _wrap(windows[i].phase_u - windows[i - 1].phase_u) for i in pairs}
        # The phase advance per period of the block's steady parts (ramps shift the apparent phase).
        ref = [adv[i] for i in pairs if close[i]] or list(adv.values())
        adv_ref = float(np.median(ref)) if ref else 0.0
        for i in pairs:
            w0, w1 = windows[i - 1], windows[i]
            noise_ph = math.sqrt(2.0 * (w0.var_u + w1.var_u) / min(w0.size, w1.size)) / max(
                min(w0.amp_u, w1.amp_u), 1e-300
            )
            d_ph = abs(_wrap(adv[i] - adv_ref)) / (STEADY_PHASE_TOL + STEADY_NOISE_Z * noise_ph)
            link[i] = close[i] and d_ph <= 1.0

    # Runs of linked windows; windows off their run's median are cut out until nothing changes.
    excluded = [False] * len(windows)
    runs: list[tuple[int, int]] = []
    for _ in range(50):
        runs = []
        k0 = 0
        for k in range(1, len(windows) + 1):
            if not (k < len(windows) and link[k] and not excluded[k] and not excluded[k - 1]):
                if k - k0 >= 2:
                    runs.append((k0, k))
                k0 = k
        changed = False
        for i, j in runs:
            lev = _level(windows[i:j])
            for k in range(i, j):
                if _distance(lev, windows[k]) > 1.0:
                    excluded[k] = True
                    changed = True
        if not changed:
            break
    runs = [r for r in (_trim_edges(windows, i, j) for i, j in runs) if r[1] - r[0] >= 2]
    runs = [_trim_settling(windows, i, j) for i, j in runs]

    # Kept segments: whole periods of each segment's own frequency (its sine fitted on it), up to the
    # block's end or the next segment.  A run whose input the fit refuses is not steady after all.
    candidates = [(i, j) for i, j in runs if j - i >= need]
    kept_runs: list[tuple[int, int]] = []
    kept: list[Segment] = []
    fits: list[SineFit] = []
    for r, (i, j) in enumerate(candidates):
        limit = blocks[windows[i].block][1]
        if r + 1 < len(candidates):
            limit = min(limit, windows[candidates[r + 1][0]].start)
        start, stop0 = windows[i].start, windows[j - 1].stop
        try:
            sub = _analyse(tt[start:stop0], uu[start:stop0], nominal_frequency, harmonics=False)
            stop = min(start + round((j - i) * TWO_PI / (sub.fit.frequency * dt)), limit)
            ana = _analyse(tt[start:stop], uu[start:stop], nominal_frequency, omega_start=sub.fit.frequency)
            _check_periodic(ana)
            _check_sampling(ana)
        except (NotPeriodicError, UndersampledError, InsufficientDataError, ZeroAmplitudeError):
            runs.remove((i, j))
            continue
        kept_runs.append((i, j))
        kept.append(Segment(start, stop, (stop - start) * dt * ana.fit.frequency / TWO_PI))
        fits.append(ana.fit)
    for r, (i, j) in enumerate(runs):
        for k in range(i, j):
            windows[k].run = r

    _classify(windows, runs, kept_runs)
    dropped = _dropped_stretches(windows, blocks, kept, uu, a_ref)
    if not kept:
        tally: dict[str, float] = {}
        for s, e, why in dropped:
            tally[why] = tally.get(why, 0.0) + (e - s) * dt * omega_main / TWO_PI
        what = ", ".join(f"{why} {v:.1f}" for why, v in sorted(tally.items(), key=lambda kv: -kv[1]))
        raise InsufficientDataError(
            f"no stretch of >= {mp:g} steady periods found: the record holds {total_periods:.1f} periods "
            f"of {omega_main / TWO_PI:.6g} Hz, in periods: {what}"
        )
    for fit in fits:
        _warn_distortion(fit, stacklevel=3)
    return SegmentReport(tuple(kept), tuple(dropped), tuple(fits))


def _classify(windows: list[_Window], runs: list[tuple[int, int]], kept_runs: list[tuple[int, int]]) -> None:
    """Label every window: "idle", "too short", "amplitude ramp", "level change", "transient", and the
    windows of kept segments ``_LEFTOVER`` (for the sample or two of them a segment may leave out)."""
    kept_set = set(kept_runs)
    labels = [""] * len(windows)
    for i, j in runs:
        for k in range(i, j):
            labels[k] = "kept" if (i, j) in kept_set else "too short"
    for k, w in enumerate(windows):
        if w.idle:
            labels[k] = "idle"
    levels = {r: _level(windows[i:j]) for r, (i, j) in enumerate(runs)}
    # Unsteady stretches: consecutive unlabelled windows of one block.
    k = 0
    while k < len(windows):
        if labels[k]:
            k += 1
            continue
        e = k
        while e < len(windows) and not labels[e] and windows[e].block == windows[k].block:
            e += 1
        left = windows[k - 1] if k > 0 and windows[k - 1].block == windows[k].block else None
        right = windows[e] if e < len(windows) and windows[e].block == windows[k].block else None

        def side(w: Optional[_Window]) -> Optional[float | _Level]:
            if w is None:
                return None
            if w.idle:
                return 0.0
            return levels[w.run] if w.run >= 0 else w.amp_u

        lft, rgt = side(left), side(right)
        if isinstance(lft, _Level) and isinstance(rgt, _Level):
            why = "level change" if _distance(lft, rgt) > 1.0 else "transient"
            labels[k:e] = [why] * (e - k)
        else:
            lv = lft.amp_u if isinstance(lft, _Level) else lft
            rv = rgt.amp_u if isinstance(rgt, _Level) else rgt
            labels[k:e] = _ramp_labels([w.amp_u for w in windows[k:e]], lv, rv)
        k = e
    for w, lab in zip(windows, labels):
        w.label = lab if lab != "kept" else _LEFTOVER


def _ramp_labels(amps: Sequence[float], left: Optional[float], right: Optional[float]) -> list[str]:
    """Unsteady windows next to rest or a steady level: "amplitude ramp" where at least two consecutive
    windows move the input amplitude the same way (each step more than the steadiness tolerance), from
    the neighbour before to the one after; "transient" otherwise (a one-period start or stop, a peak)."""
    ext = [left, *amps, right]
    tol = STEADY_RTOL_U * max(v for v in ext if v is not None)

    def step(i: int) -> int:  # direction of the step from ext[i] to ext[i + 1]; 0: none or too small
        a, b = ext[i], ext[i + 1]
        if a is None or b is None or abs(b - a) <= tol:
            return 0
        return 1 if b > a else -1

    direction = []
    for q in range(len(amps)):
        before, after = step(q), step(q + 1)
        sides = [d for d, v in ((before, ext[q]), (after, ext[q + 2])) if v is not None]
        direction.append(sides[0] if sides and all(d == sides[0] != 0 for d in sides) else 0)
    labels = ["transient"] * len(amps)
    q = 0
    while q < len(amps):
        e = q + 1
        while e < len(amps) and direction[e] == direction[q]:
            e += 1
        if direction[q] != 0 and e - q >= 2:
            labels[q:e] = ["amplitude ramp"] * (e - q)
        q = e
    return labels


#: Placeholder label of the samples of a kept window left outside its segment.
_LEFTOVER = "~"


def _dropped_stretches(
    windows: list[_Window], blocks: list[tuple[int, int]], kept: list[Segment], u: FloatArray, a_ref: float
) -> list[tuple[int, int, str]]:
    """Everything outside the kept segments as ``(start, stop, reason)`` stretches, in record order."""
    pieces: list[tuple[int, int, str]] = []
    for bi, (a, b) in enumerate(blocks):
        ws = [w for w in windows if w.block == bi]
        pieces += [(w.start, w.stop, w.label) for w in ws]
        tail = ws[-1].stop if ws else a
        if tail < b:
            if ws:
                why = ws[-1].label  # less than a period left at the block's end
            else:  # a block shorter than one period: idle unless its input moves
                why = "idle" if 0.5 * float(np.ptp(u[a:b])) < IDLE_FRACTION * a_ref else "transient"
            pieces.append((tail, b, why))
    # Idle between two active stretches (gaps of the time axis included) is a pause.
    active = [w for w in windows if not w.idle]
    if active:
        first, last = active[0].start, active[-1].stop
        pieces = [
            (s, e, "pause" if why == "idle" and first <= s and e <= last else why) for s, e, why in pieces
        ]
    # Cut the kept segments out.
    cut: list[tuple[int, int, str]] = []
    for s, e, why in pieces:
        cur = s
        for seg in kept:
            if seg.stop <= cur or seg.start >= e:
                continue
            if seg.start > cur:
                cut.append((cur, seg.start, why))
            cur = max(cur, seg.stop)
        if cur < e:
            cut.append((cur, e, why))
    # What a segment left of its own windows takes the reason of the dropped stretch next to it.
    labels = [why for _, _, why in cut]
    for i, (s, e, why) in enumerate(cut):
        if why != _LEFTOVER:
            continue
        after = labels[i + 1] if i + 1 < len(cut) and cut[i + 1][0] == e else _LEFTOVER
        before = labels[i - 1] if i > 0 and cut[i - 1][1] == s else _LEFTOVER
        labels[i] = after if after != _LEFTOVER else before if before != _LEFTOVER else "partial period"
    out: list[tuple[int, int, str]] = []
    for (s, e, _), why in zip(cut, labels):
        if out and out[-1][1] == s and out[-1][2] == why:
            out[-1] = (out[-1][0], e, why)
        else:
            out.append((s, e, why))
    return out


# ------------------------------------------------------------------------------------------------------
# Synchronous averaging


@dataclass(frozen=True, eq=False)
class AveragedPeriod:
    """One averaged output period on a grid starting at the input's phase zero (any sampling rate).

    ``ybar[j]`` is the output at ``t_j = time_origin + j T / P`` (modulo whole periods), ``P = 2K + 1``,
    where ``u = amplitude cos(frequency (t - time_origin))``; its DC (``offset_y``) is removed.  Each point
    has noise variance about ``noise_var / periods``.

    Attributes
    ----------
    frequency : float
        omega (rad/s) of the input.
    amplitude : float
        U (> 0) of the input.
    ybar : ndarray
        One period of the output, ``P = 2 harmonics + 1`` points.
    noise_var : float
        Variance of one raw output sample: ``RSS / (n - 2K - 1)`` of the harmonic fit (unbiased for white
        noise); NaN when no degree of freedom is left.
    periods : float
        Effective number of averaged periods, ``n / P``.
    noise_dof : int
        ``n - (2K + 1)``.
    harmonics : int
        K.
    offset_y, offset_u : float
        DC of the output (removed from ``ybar``) and of the input.
    start, stop : int
        Sample range ``[start, stop)`` used.
    time_origin : float
        Absolute time (s) of the first phase zero of the input at or after ``t[start]``.
    source : str
        Free text: file name, segment number.
    """

    frequency: float
    amplitude: float
    ybar: FloatArray = field(repr=False)
    noise_var: float
    periods: float
    noise_dof: int
    harmonics: int
    offset_y: float
    offset_u: float
    start: int
    stop: int
    time_origin: float
    source: str = ""

    @property
    def samples_per_period(self) -> int:
        """P = 2K + 1, the points of ``ybar``."""
        return int(self.ybar.size)

    def times(self) -> FloatArray:
        """``t_j - time_origin = j T / P`` (s)."""
        out: FloatArray = np.arange(self.ybar.size, dtype=np.float64) * (
            TWO_PI / self.frequency / self.ybar.size
        )
        return out

    def input_grid(self) -> FloatArray:
        """``u - offset_u = U cos(omega t_j)`` on the grid of ``ybar``."""
        out: FloatArray = self.amplitude * np.cos(TWO_PI * np.arange(self.ybar.size) / self.ybar.size)
        return out


class _HarmonicLS:
    """Least-squares fit of ``y`` on ``[1, cos k theta, sin k theta]``, k <= K_max, and its nested sub-fits.

    From the R factor of the basis and ``Q^T y``: the fit with the first ``2k + 1`` columns is
    ``R[:m, :m]^-1 (Q^T y)[:m]`` and its residual is the full one plus ``|(Q^T y)[m:]|^2``.
    """

    def __init__(self, r: FloatArray, qty: FloatArray, rss: float) -> None:
        self.r, self.qty, self.rss_full = r, qty, rss

    def coef(self, k: int) -> FloatArray:
        m = 2 * k + 1
        out: FloatArray = solve_triangular(self.r[:m, :m], self.qty[:m])
        return out

    def rss(self, k: int) -> float:
        m = 2 * k + 1
        return self.rss_full + float(self.qty[m:] @ self.qty[m:])

    def unscaled_variance(self, k: int) -> FloatArray:
        """Diagonal of ``(X^T X)^-1`` for the first ``2k + 1`` columns."""
        m = 2 * k + 1
        r_inv = np.linalg.inv(self.r[:m, :m])
        out: FloatArray = np.sum(r_inv**2, axis=1)
        return out


def _qr_fit(theta: FloatArray, y: FloatArray, kmax: int) -> tuple[FloatArray, FloatArray, float]:
    """Blocked Householder QR of ``[X y]`` (X the harmonic basis): ``(R, Q^T y, residual^2)``.

    Row blocks of ``QR_CHUNK`` samples are reduced one after the other, each on top of the previous ``R``,
    so memory stays ``O(QR_CHUNK m)`` whatever the record's length.
    """
    m = 2 * kmax + 1
    acc: Optional[FloatArray] = None
    for s in range(0, y.size, QR_CHUNK):
        block = np.column_stack([_harmonic_basis(theta[s : s + QR_CHUNK], kmax), y[s : s + QR_CHUNK]])
        if acc is not None:
            block = np.vstack([acc, block])
        acc = np.asarray(np.linalg.qr(block, mode="r"), dtype=np.float64)
    assert acc is not None
    rr = np.zeros((m + 1, m + 1))
    rows = min(acc.shape[0], m + 1)
    rr[:rows] = acc[:rows]
    return rr[:m, :m], rr[:m, m], float(rr[m, m] ** 2)


def _moment_fit(theta: FloatArray, y: FloatArray, kmax: int) -> tuple[FloatArray, FloatArray, float]:
    """Same result as :func:`_qr_fit` for long records, in O(n K) instead of O(n K^2).

    In complex form the Gram matrix of ``e^{i k theta}``, k = -K..K, is Toeplitz: ``G[k, l] = mu[l - k]``
    with the moments ``mu[m] = sum_n e^{i m theta_n}``, m = 0..2K, and the right-hand side is
    ``sum_n y_n e^{-i k theta_n}``; both come from one pass of the phasor recurrence.  Over two or more
    periods the harmonics are nearly orthogonal (the Gram matrix is ``n I`` to within a few percent), so
    its condition number is close to 1 and the normal equations lose nothing; it is checked (<= 1e4, else
    the QR path is used).  The fit is returned as the R factor and ``Q^T y`` of the real basis so that the
    nested sub-fits work as for the QR path; the residual is recomputed explicitly.
    """
    n = y.size
    m = 2 * kmax + 1
    z = np.exp(1j * theta)
    p = np.ones(n, dtype=np.complex128)
    mom = np.empty(2 * kmax + 1, dtype=np.complex128)
    rhs = np.empty(kmax + 1, dtype=np.complex128)
    for q in range(2 * kmax + 1):
        mom[q] = p.sum()
        if q <= kmax:
            rhs[q] = np.dot(y, p.conj())
        p *= z

    # Real Gram of [1, c1, s1, c2, s2, ...] from the complex moments mu[d], d = -2K..2K (mu[-d] is the
    # conjugate): cos a cos b = (cos(a-b) + cos(a+b))/2, sin a sin b = (cos(a-b) - cos(a+b))/2,
    # cos a sin b = (sin(a+b) - sin(a-b))/2; the constant column is the k = 0 cosine.
    mu = np.concatenate([np.conj(mom[:0:-1]), mom])
    ks = np.concatenate([[0], np.repeat(np.arange(1, kmax + 1), 2)])
    is_sin = np.concatenate([[False], np.tile([False, True], kmax)])
    lo = mu[ks[:, None] - ks[None, :] + 2 * kmax]
    hi = mu[ks[:, None] + ks[None, :] + 2 * kmax]
    si, sj = is_sin[:, None], is_sin[None, :]
    gram = np.where(
        si & sj,
        0.5 * (lo.real - hi.real),
        np.where(
            si, 0.5 * (hi.imag + lo.imag), np.where(sj, 0.5 * (hi.imag - lo.imag), 0.5 * (lo.real + hi.real))
        ),
    )
    gram = np.asarray(0.5 * (gram + gram.T), dtype=np.float64)  # symmetric to the last bit
    xty = np.empty(m)
    xty[0] = rhs[0].real
    xty[1::2] = rhs[1:].real
    xty[2::2] = -rhs[1:].imag
    scale = np.sqrt(np.diag(gram))
    eig = np.linalg.eigvalsh(gram / np.outer(scale, scale))
    if eig[0] <= 0.0 or eig[-1] / eig[0] > 1e4:
        return _qr_fit(theta, y, kmax)
    r = np.linalg.cholesky(gram).T
    qty: FloatArray = solve_triangular(r, xty, trans="T")
    coef = solve_triangular(r, qty)
    # Explicit residual (no cancellation): y - X coef by the same recurrence.
    fitted = np.full(n, coef[0])
    p = z.copy()
    for k in range(1, kmax + 1):
        fitted += coef[2 * k - 1] * p.real + coef[2 * k] * p.imag
        p *= z
    resid = y - fitted
    return r, qty, float(resid @ resid)


def _harmonic_fit(theta: FloatArray, y: FloatArray, kmax: int) -> _HarmonicLS:
    n, m = y.size, 2 * kmax + 1
    fitter = _qr_fit if n * m * m <= QR_WORK_MAX else _moment_fit
    return _HarmonicLS(*fitter(theta, y, kmax))


def synchronous_average(
    t: ArrayLike,
    y: ArrayLike,
    fit: SineFit,
    *,
    start: int = 0,
    stop: Optional[int] = None,
    harmonics: Optional[int] = None,
    source: str = "",
) -> AveragedPeriod:
    """One averaged output period from any sampling rate, on a grid starting at the input's phase zero.

    ``y`` is fitted over every sample of ``[start, stop)`` by linear least squares on
    ``[1, cos(k omega tau), sin(k omega tau)]``, k = 1..K, with ``omega = fit.frequency`` and ``tau = t -
    time_origin`` (so that ``u = U cos(omega tau)``); the fitted periodic signal without its constant is
    evaluated at ``tau_j = j T / P``, ``P = 2K + 1``.  With an integer number of samples per period, whole
    periods and ``K = (P - 1) / 2`` (odd P) this is the plain periodic average (4a-b) minus its mean.

    The least squares use a blocked Householder QR of the basis (O(n K^2)); for very long records the
    Toeplitz Gram matrix of the near-orthogonal harmonics is formed from its moments in O(n K) and solved
    by Cholesky after a check of its conditioning.

    Parameters
    ----------
    t, y : array_like
        The whole record's time (s) and output; only ``[start, stop)`` is used and must be uniformly sampled.
    fit : SineFit
        The input's sine (from :func:`analyse_sine`, or a :class:`SegmentReport`'s fits).
    start, stop : int
        The sample range (``stop`` defaults to the end).
    harmonics : int, optional
        K.  Default: from the data.  A first fit with ``K_max = min(200, floor(P_s/2 - 1), floor((n/2 -
        1)/2))`` (``P_s`` samples per period) gives the noise variance and each harmonic's power against its
        noise power; ``K_sig`` is the last harmonic more than 16 times above it (all of them when the data
        are noise-free), and ``K = min(K_max, max(8, 4 K_sig))``: the Bouc-Wen loop's harmonics decay like
        ``k^-3``, so the truncated tail beyond ``4 K_sig`` is a small fraction of the noise of ``ybar``.
        An explicit K must stay below Nyquist (``K omega dt < pi``) and leave ``2K + 1 <= n``.
    source : str
        Stored in the result.

    Raises
    ------
    InvalidParameterError, NonFiniteError, TimeAxisError, InsufficientDataError, UndersampledError
    """
    tt, yy = _arrays(t=t, y=y)
    n_all = tt.size
    stop_ = n_all if stop is None else int(stop)
    start_ = int(start)
    if not 0 <= start_ < stop_ <= n_all:
        raise InvalidParameterError(f"the sample range [{start}, {stop}) is not inside [0, {n_all})")
    ts, ys = tt[start_:stop_], yy[start_:stop_]
    n = ys.size
    if n < 4:
        raise InsufficientDataError(f"the range [{start_}, {stop_}) holds {n} samples; at least 4 are needed")
    dt = _uniform_step(ts)
    omega = float(fit.frequency)
    if not (math.isfinite(omega) and omega > 0.0):
        raise InvalidParameterError(f"fit.frequency = {omega} rad/s must be finite and > 0")
    if not (math.isfinite(fit.amplitude) and fit.amplitude > 0.0 and math.isfinite(fit.phase)):
        raise InvalidParameterError("fit.amplitude must be > 0 and fit.phase finite")
    period = TWO_PI / omega
    p_s = period / dt
    if p_s < MIN_SAMPLES_PER_PERIOD:
        raise UndersampledError(
            f"omega = {omega:.6g} rad/s gives {p_s:.3g} samples per period at dt = {dt:.6g} s; at least "
            f"{MIN_SAMPLES_PER_PERIOD} are needed"
        )
    span = n * dt / period
    if span < 1.0 - 1e-9:
        raise InsufficientDataError(
            f"the range [{start_}, {stop_}) spans {span:.3g} periods; at least one is needed to average"
        )
    base = fit.phase / omega
    origin = base + period * math.ceil((float(ts[0]) - base) / period - 1e-9)
    theta = _phase(omega, ts - origin)
    if harmonics is None:
        kmax = max(1, min(MAX_HARMONICS, math.floor(p_s / 2.0 - 1.0), (n // 2 - 1) // 2))
    else:
        if isinstance(harmonics, bool) or int(harmonics) != harmonics or harmonics < 1:
            raise InvalidParameterError(f"harmonics = {harmonics!r} must be an integer >= 1")
        kmax = int(harmonics)
        if kmax * omega * dt >= math.pi:
            raise InvalidParameterError(
                f"harmonic {kmax} of {omega / TWO_PI:.6g} Hz is at or above Nyquist ({0.5 / dt:.6g} Hz)"
            )
        if 2 * kmax + 1 > n:
            raise InsufficientDataError(f"{kmax} harmonics need {2 * kmax + 1} samples, the range holds {n}")
    ls = _harmonic_fit(theta, ys, kmax)
    k = kmax
    if harmonics is None:
        dof_max = n - (2 * kmax + 1)
        var_max = ls.rss(kmax) / dof_max if dof_max > 0 else 0.0
        scale = max(float(np.max(np.abs(ys - ys.mean()))), np.finfo(float).tiny)
        if var_max > (1e-12 * scale) ** 2:
            coef = ls.coef(kmax)
            var = ls.unscaled_variance(kmax) * var_max
            z = coef[1::2] ** 2 / var[1::2] + coef[2::2] ** 2 / var[2::2]
            sig = np.flatnonzero(z > 2.0 * HARMONIC_SNR)
            k_sig = int(sig[-1]) + 1 if sig.size else 1
            k = min(kmax, max(MIN_HARMONICS, HARMONIC_SAFETY * k_sig))
    coef = ls.coef(k)
    dof = n - (2 * k + 1)
    noise_var = ls.rss(k) / dof if dof > 0 else math.nan
    p_out = 2 * k + 1
    grid = TWO_PI * np.arange(p_out) / p_out
    basis = _harmonic_basis(grid, k)
    ybar = np.asarray(basis[:, 1:] @ coef[1:], dtype=np.float64)
    ybar.setflags(write=False)
    return AveragedPeriod(
        frequency=omega,
        amplitude=float(fit.amplitude),
        ybar=ybar,
        noise_var=float(noise_var),
        periods=n / p_out,
        noise_dof=int(dof),
        harmonics=int(k),
        offset_y=float(coef[0]),
        offset_u=float(fit.offset),
        start=start_,
        stop=stop_,
        time_origin=float(origin),
        source=str(source),
    )


def average_exact(y: ArrayLike, samples_per_period: int, settle_periods: int, periods: int) -> FloatArray:
    """The paper's periodic average (4a-b): ``ybar[j] = mean_k y[(S + k) P + j]``, j < P, k < N."""
    yy = _array("y", y)
    p, s, n = samples_per_period, settle_periods, periods
    for name, v, low in (("samples_per_period", p, 1), ("settle_periods", s, 0), ("periods", n, 1)):
        if isinstance(v, bool) or int(v) != v or v < low:
            raise InvalidParameterError(f"{name} = {v!r} must be an integer >= {low}")
    p, s, n = int(p), int(s), int(n)
    if yy.size < (s + n) * p:
        raise InsufficientDataError(
            f"{yy.size} samples hold {yy.size // p} whole periods of {p} samples; {s} settling + {n} "
            "averaged periods do not fit"
        )
    out: FloatArray = yy[s * p : (s + n) * p].reshape(n, p).mean(axis=0)
    return out


def average_measurement(
    measurement: Measurement, *, min_periods: float = 2.0, harmonics: Optional[int] = None
) -> list[AveragedPeriod]:
    """Every steady segment of a :class:`~bouc_wen_id.measurement.Measurement`, averaged.

    :func:`find_steady_segments` with the measurement's nominal frequency as the hint, then
    :func:`synchronous_average` of each kept segment on its own input fit; ``source`` is
    ``"<name> segment <i>"``.
    """
    report = find_steady_segments(
        measurement.t,
        measurement.u,
        measurement.y,
        nominal_frequency=measurement.nominal_frequency,
        min_periods=min_periods,
    )
    name = measurement.name or "measurement"
    return [
        synchronous_average(
            measurement.t,
            measurement.y,
            fit,
            start=seg.start,
            stop=seg.stop,
            harmonics=harmonics,
            source=f"{name} segment {i}",
        )
        for i, (seg, fit) in enumerate(zip(report.kept, report.fits))
    ]

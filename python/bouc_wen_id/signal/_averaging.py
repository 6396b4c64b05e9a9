"""Synchronous averaging: one output period from any sampling rate, on the input's phase grid (design.md 8.3).

:func:`synchronous_average` fits the output over a steady stretch on harmonics of the input frequency and
evaluates one period; :func:`average_segments` is the one path from a measurement to its averaged periods,
with the segment report of what was kept and dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError, UndersampledError
from ..validation import HARMONIC_SNR, MIN_SAMPLES_PER_PERIOD, check_time_axis, finite_arrays
from ._harmonic_ls import HarmonicLS, harmonic_basis, nested_fit
from ._segments import SegmentReport, find_steady_segments
from ._sine import SineFit

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..measurement import Measurement

__all__ = [
    "AveragedPeriod",
    "SegmentedMeasurement",
    "synchronous_average",
    "average_segments",
    "average_measurement",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Default harmonic count: this many times the last significant harmonic (the Bouc-Wen loop's harmonics
#: decay like k^-3; beyond 4 K_sig the aliased tail is a small fraction of the per-point noise).
HARMONIC_SAFETY = 4
#: ... but at least this many harmonics (when the data allow them).
MIN_HARMONICS = 8
#: ... and never more than this many.
MAX_HARMONICS = 200


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


def _max_harmonics(harmonics: Optional[int], omega: float, dt: float, n: int, p_s: float) -> int:
    """K of the first fit: the caller's (checked against Nyquist and the range's length), else the most the
    record supports (:func:`synchronous_average`)."""
    if harmonics is None:
        return max(1, min(MAX_HARMONICS, math.floor(p_s / 2.0 - 1.0), (n // 2 - 1) // 2))
    if isinstance(harmonics, bool) or int(harmonics) != harmonics or harmonics < 1:
        raise InvalidParameterError(f"harmonics = {harmonics!r} must be an integer >= 1")
    kmax = int(harmonics)
    if kmax * omega * dt >= math.pi:
        raise InvalidParameterError(
            f"harmonic {kmax} of {omega / TWO_PI:.6g} Hz is at or above Nyquist ({0.5 / dt:.6g} Hz)"
        )
    if 2 * kmax + 1 > n:
        raise InsufficientDataError(f"{kmax} harmonics need {2 * kmax + 1} samples, the range holds {n}")
    return kmax


def _kept_harmonics(ls: HarmonicLS, kmax: int, ys: FloatArray) -> int:
    """K from the data: ``min(K_max, max(8, 4 K_sig))``, ``K_sig`` the last harmonic 16 times above its
    noise power in the fit on ``kmax`` harmonics (all of them when the data are noise-free)."""
    n = ys.size
    dof_max = n - (2 * kmax + 1)
    var_max = ls.rss(kmax) / dof_max if dof_max > 0 else 0.0
    scale = max(float(np.max(np.abs(ys - ys.mean()))), np.finfo(float).tiny)
    if not var_max > (1e-12 * scale) ** 2:
        return kmax
    coef = ls.coef(kmax)
    var = ls.unscaled_variance(kmax) * var_max
    z = coef[1::2] ** 2 / var[1::2] + coef[2::2] ** 2 / var[2::2]
    sig = np.flatnonzero(z > 2.0 * HARMONIC_SNR)
    k_sig = int(sig[-1]) + 1 if sig.size else 1
    return min(kmax, max(MIN_HARMONICS, HARMONIC_SAFETY * k_sig))


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

    The least squares: the lab kernels' O(n K) moment fit, else a blocked Householder QR of the basis
    (O(n K^2)), or for very long records the moments' Gram matrix once its conditioning is checked.

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
    tt, yy = finite_arrays(t=t, y=y)
    n_all = tt.size
    stop_ = n_all if stop is None else int(stop)
    start_ = int(start)
    if not 0 <= start_ < stop_ <= n_all:
        raise InvalidParameterError(f"the sample range [{start}, {stop}) is not inside [0, {n_all})")
    ts, ys = tt[start_:stop_], yy[start_:stop_]
    n = ys.size
    if n < 4:
        raise InsufficientDataError(f"the range [{start_}, {stop_}) holds {n} samples; at least 4 are needed")
    dt = check_time_axis(ts)
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
    kmax = _max_harmonics(harmonics, omega, dt, n, p_s)
    # The phases omega (t - origin), wrapped on the NumPy path, formed in Rust on the fast one.
    ls = nested_fit(ts - origin, ys, kmax, omega)
    k = kmax if harmonics is not None else _kept_harmonics(ls, kmax, ys)
    coef = ls.coef(k)
    dof = n - (2 * k + 1)
    noise_var = ls.rss(k) / dof if dof > 0 else math.nan
    p_out = 2 * k + 1
    grid = TWO_PI * np.arange(p_out) / p_out
    basis = harmonic_basis(grid, k)
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


@dataclass(frozen=True, eq=False)
class SegmentedMeasurement:
    """A measurement's steady segments (what was kept and dropped) and their averaged periods.

    ``periods[i]`` is the average of ``report.kept[i]``, on ``report.fits[i]``; its ``source`` is
    ``"<name> segment <i>"``.
    """

    name: str
    report: SegmentReport
    periods: tuple[AveragedPeriod, ...]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready description of what was kept (with each segment's input and noise) and dropped."""
        return {
            "measurement": self.name,
            "kept": [
                {
                    "start": seg.start,
                    "stop": seg.stop,
                    "periods": seg.periods,
                    "frequency_hz": fit.frequency / TWO_PI,
                    "amplitude": fit.amplitude,
                    "thd": fit.thd,
                    "noise_sd": math.sqrt(ap.noise_var) if math.isfinite(ap.noise_var) else None,
                }
                for seg, fit, ap in zip(self.report.kept, self.report.fits, self.periods)
            ],
            "dropped": [{"start": a, "stop": b, "reason": why} for a, b, why in self.report.dropped],
        }


def average_segments(
    measurement: Measurement,
    *,
    min_periods: float = 2.0,
    harmonics: Optional[int] = None,
    name: Optional[str] = None,
) -> SegmentedMeasurement:
    """Every steady segment of a :class:`~bouc_wen_id.measurement.Measurement`, averaged, with the report.

    :func:`find_steady_segments` with the measurement's nominal frequency as the hint, then
    :func:`synchronous_average` of each kept segment on its own input fit.  ``name`` (default: the
    measurement's name, or ``"measurement"``) labels the averaged periods' ``source``.
    """
    report = find_steady_segments(
        measurement.t,
        measurement.u,
        measurement.y,
        nominal_frequency=measurement.nominal_frequency,
        min_periods=min_periods,
    )
    label = name or measurement.name or "measurement"
    if measurement.nominal_frequency is not None and report.fits:
        from ..timeunits import check_frequency

        found = float(np.median([f.frequency for f in report.fits]))
        check_frequency(label, measurement.nominal_frequency, found, "the nominal frequency")
    periods = tuple(
        synchronous_average(
            measurement.t,
            measurement.y,
            fit,
            start=seg.start,
            stop=seg.stop,
            harmonics=harmonics,
            source=f"{label} segment {i}",
        )
        for i, (seg, fit) in enumerate(zip(report.kept, report.fits))
    )
    return SegmentedMeasurement(label, report, periods)


def average_measurement(
    measurement: Measurement, *, min_periods: float = 2.0, harmonics: Optional[int] = None
) -> list[AveragedPeriod]:
    """Every steady segment of a :class:`~bouc_wen_id.measurement.Measurement`, averaged.

    The averaged periods of :func:`average_segments` (which also returns the segment report).
    """
    return list(average_segments(measurement, min_periods=min_periods, harmonics=harmonics).periods)

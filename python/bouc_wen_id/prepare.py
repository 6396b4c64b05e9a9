"""Experiment preparation: from recordings, measurements or averaged periods to what the estimators need.

Each experiment becomes one :class:`Prepared` record: its averaged period ``ybar`` (the paper's periodic
average (4a-b) for a :class:`~bouc_wen_id.model.Recording`, the synchronous average of every steady segment
for a :class:`~bouc_wen_id.measurement.Measurement`), the spectral derivative, the noise variance from the
period-to-period spread, and the harmonics kept.  :func:`scale` then expresses them in units of order one.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import NDArray

from ._backend import Paper
from ._text import item_label
from ._timehint import hint
from .errors import (
    FrequencyMismatchError,
    InsufficientDataError,
    InvalidParameterError,
    NoisyInputError,
    TransientWarning,
    ZeroAmplitudeError,
)
from .model import Recording, WienerPlant
from .validation import HARMONIC_SNR

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .signal import AveragedPeriod

__all__ = [
    "Prepared",
    "Scales",
    "prepare",
    "scale",
    "check_input",
    "check_fundamental",
    "input_fundamental",
    "noise_variance",
    "auto_harmonics",
]

FloatArray = NDArray[np.float64]

#: Largest relative misfit of ``u`` to ``U cos(omega t)`` before the stated frequency is called wrong.
INPUT_MISFIT_MAX = 0.05
#: An input's deviation whose neighbouring samples correlate below this is noise, not a wrong frequency.
NOISE_LAG1_MAX = 0.5
#: Largest phase (rad) of the recorded input relative to ``cos(omega t)`` on the given time axis.
INPUT_PHASE_MAX = 0.02
#: Range of output and input scales identify accepts: beyond it, squares of the data leave the
#: floating-point range (s^2 underflows below 1e-154) and s^mu with mu up to 10 overflows past 1e30.
SCALE_MIN, SCALE_MAX = 1e-30, 1e30


def check_sizes(rec: Recording, start: int, stop: int) -> None:
    """Refuse a recording whose input amplitude or output lies outside ``[SCALE_MIN, SCALE_MAX]``.

    Every later step squares the data (the input's projections, the noise variance, the chi-square), and
    a square of 1e300 is no float: such data are refused here, by name, before any arithmetic on them.
    """
    y = np.asarray(rec.y[start:stop], dtype=np.float64)
    peak_y = float(np.max(np.abs(y))) if y.size else 0.0
    for what, size, low in (
        ("input amplitude", abs(float(rec.amplitude)), SCALE_MIN),
        ("output", peak_y, 0.0),
    ):
        if not low <= size <= SCALE_MAX:
            raise ZeroAmplitudeError(
                f"the {what} is of size {size:.3e}, outside [{low:g}, {SCALE_MAX:g}]: squares of it leave "
                "the floating-point range; express the data in units that keep it there (e.g. mm, not km)"
            )


def input_fundamental(rec: Recording, start: int, stop: int) -> tuple[float, float]:
    """``(a_cos, a_sin)``: the recorded input's fundamental at the stated omega over ``start:stop`` (whole
    periods), as the least-squares coefficients of ``cos(omega t)`` and ``sin(omega t)``.

    Over whole periods, cos, sin, the constant and the harmonics are orthogonal on the sample grid, so the
    least-squares coefficients are plain projections (no linear solve needed)."""
    t = rec.t[start:stop]
    u = rec.u[start:stop]
    c, s = np.cos(rec.frequency * t), np.sin(rec.frequency * t)
    return 2.0 * float(np.dot(u, c)) / u.size, 2.0 * float(np.dot(u, s)) / u.size


def _sine_misfit(v: FloatArray, a_cos: float, a_sin: float) -> float:
    """Relative RMS of ``v`` (whole periods, centred) outside its fundamental ``(a_cos, a_sin)``."""
    centred = v - v.mean()
    spread = float(np.dot(centred, centred))
    fitted = 0.5 * v.size * (a_cos**2 + a_sin**2)
    return math.sqrt(max(spread - fitted, 0.0) / spread) if spread > 0 else math.inf


def noisy_input(dev: FloatArray, misfit: float, omega: float, what: str) -> Optional[NoisyInputError]:
    """The error for an input refused by its ``misfit`` when its deviation ``dev`` (from ``what``) is noise
    rather than a wrong frequency: neighbouring samples of noise hardly correlate, while a misaligned period
    (or a distortion) leaves a smooth deviation whose lag-1 correlation is near ``cos(omega dt)`` ~ 1
    (review 34: 8 % input noise was refused with "check the stated frequency").  ``None`` otherwise."""
    d = np.asarray(dev, dtype=np.float64).ravel()
    ss = float(np.dot(d, d))
    if d.size < 3 or not ss > 0.0:
        return None
    r1 = float(np.dot(d[:-1], d[1:])) / ss
    if r1 >= NOISE_LAG1_MAX:
        return None
    return NoisyInputError(
        f"the recorded input repeats at omega = {omega:.6g} rad/s but carries noise: it differs from {what} "
        f"by a relative {misfit:.2g} > {INPUT_MISFIT_MAX}, and the difference is noise (neighbouring "
        f"samples correlate {r1:.2f}; a wrong frequency or a distortion leaves a smooth difference). The "
        f"input must repeat to within {INPUT_MISFIT_MAX:g} of its RMS: filter the input channel with a "
        "zero-phase low-pass well above omega (the output is not affected), or measure it with less noise"
    )


def swapped_hint(rec: Recording, window: Optional[tuple[int, int]]) -> str:
    """A clause for an input refused as no ``U cos(omega t)``: when the *output* over ``window`` (whole
    periods) is the sine the input should be (its fundamental of amplitude ``|U|`` peaking at ``t = 0``,
    nothing else beyond the input's tolerance), the columns look swapped (review 32: u and y exchanged
    gave only "shift the time column"). '' otherwise."""
    if window is None:
        return ""
    y = np.asarray(rec.y[window[0] : window[1]], dtype=np.float64)
    if y.size == 0 or not np.all(np.isfinite(y)):
        return ""
    t = rec.t[window[0] : window[1]]
    b_cos = 2.0 * float(np.dot(y, np.cos(rec.frequency * t))) / y.size
    b_sin = 2.0 * float(np.dot(y, np.sin(rec.frequency * t))) / y.size
    phase = math.atan2(b_sin, b_cos * np.sign(rec.amplitude))
    close = abs(math.hypot(b_cos, b_sin) - abs(rec.amplitude)) <= INPUT_MISFIT_MAX * abs(rec.amplitude)
    if close and abs(phase) <= INPUT_PHASE_MAX and _sine_misfit(y, b_cos, b_sin) <= INPUT_MISFIT_MAX:
        return (
            f"; the recorded output y is the sine the input should be (amplitude "
            f"{math.hypot(b_cos, b_sin):.4g}, "
            "peaking at t = 0): check the channels, the input and output columns look swapped"
        )
    return ""


def check_fundamental(
    rec: Recording, a_cos: float, a_sin: float, window: Optional[tuple[int, int]] = None
) -> None:
    """Refuse a stated amplitude the input's fundamental does not have, or a fundamental that does not peak
    at ``t = 0`` (identify's checks; ``diagnose`` makes them too, on an input that may carry harmonics).
    ``window``: the samples the fundamental was taken over, for :func:`swapped_hint`."""
    amp = math.hypot(a_cos, a_sin)
    if abs(amp - abs(rec.amplitude)) > INPUT_MISFIT_MAX * abs(rec.amplitude):
        raise InvalidParameterError(
            f"the stated amplitude U = {rec.amplitude:.6g} does not match the recorded input's {amp:.6g}"
            + swapped_hint(rec, window)
        )
    phase = math.atan2(a_sin, a_cos * np.sign(rec.amplitude))
    if abs(phase) > INPUT_PHASE_MAX:
        sign = "-" if phase >= 0 else "+"
        swapped = swapped_hint(rec, window)
        advice = swapped or "; shift the time column so that the input peaks at t = 0"
        raise InvalidParameterError(
            f"the recorded input is U cos(omega t {sign} {abs(phase):.3g}) rather than U cos(omega t) on its "
            f"time axis{advice}"
        )


def check_input(rec: Recording, start: int, stop: int) -> None:
    """Refuse a recording whose ``u`` is not ``U cos(omega t)`` on its own time axis."""
    u = rec.u[start:stop]
    check_sizes(rec, start, stop)
    a_cos, a_sin = input_fundamental(rec, start, stop)
    misfit = _sine_misfit(u, a_cos, a_sin)
    if misfit > INPUT_MISFIT_MAX:
        t = rec.t[start:stop]
        sine = u.mean() + a_cos * np.cos(rec.frequency * t) + a_sin * np.sin(rec.frequency * t)
        noisy = noisy_input(u - sine, misfit, rec.frequency, "its sine")
        if noisy is not None:
            raise noisy
        raise hint(
            FrequencyMismatchError(
                f"the recorded input is not a sine at omega = {rec.frequency:.6g} rad/s "
                f"(relative misfit {misfit:.2g} > {INPUT_MISFIT_MAX}); check the stated frequency and its "
                "units" + swapped_hint(rec, (start, stop))
            ),
            rec.t[start:stop],
            u,
            rec.frequency,
        )
    check_fundamental(rec, a_cos, a_sin, (start, stop))


def noise_variance(y: FloatArray, samples_per_period: int, settle_periods: int, periods: int) -> float:
    """Noise variance from the period-to-period spread of the raw samples (needs >= 2 periods).

    ``sum_j sum_k (y_kj - ybar_j)^2 / (P (N - 1))``: unbiased for white noise, free of the signal.
    """
    if periods < 2:
        return math.nan
    p = samples_per_period
    seg = np.asarray(y[settle_periods * p : (settle_periods + periods) * p]).reshape(periods, p)
    return float(np.mean(np.var(seg, axis=0, ddof=1)))


def auto_harmonics(ybar: FloatArray, noise_var: float, periods: float) -> int:
    """Highest harmonic of ``ybar`` standing above the noise floor (all of them when noise-free)."""
    p = ybar.size
    k_max = (p - 1) // 2
    if not math.isfinite(noise_var) or noise_var <= 0.0:
        return k_max
    power = np.abs(np.fft.rfft(ybar)[1 : k_max + 1] / p) ** 2
    above = np.flatnonzero(power > HARMONIC_SNR * noise_var / (periods * p))
    return int(above[-1]) + 1 if above.size else 1


@dataclass(frozen=True)
class Prepared:
    """One experiment reduced to its averaged period and what the estimators need of it."""

    amplitude: float
    frequency: float
    #: Added to the local phase (that of the averaged window's first sample) to give the phase of G.
    phase_shift: float
    #: Points of the averaged period.
    p: int
    #: Settling periods dropped (0 for lab data, whose steady stretch is detected).
    s: int
    #: Periods averaged (effective, for lab data).
    n: float
    #: Harmonics kept in the spectral derivative.
    k: int
    ybar: FloatArray
    ydot: FloatArray
    noise_var: float
    noise_dof: int
    plant: Optional[WienerPlant]
    source: str
    #: The output's mean over the averaged window, removed from ``ybar`` (the model's steady loop has
    #: none): a sensor or conditioning offset, as ``AveragedPeriod.offset_y`` on the measurement path.
    offset: float = 0.0


#: A steady period's mean-square deviation from the steady average stays below ``noise (1 + 1/N_tail)``
#: times this factor ``1 + TRANSIENT_CHI2_SD / sqrt(P)`` (about 4 standard deviations of a chi-square
#: with P degrees of freedom over its mean); noise-free, below ``TRANSIENT_RTOL^2`` of the loop's power.
TRANSIENT_CHI2_SD = 6.0
TRANSIENT_RTOL = 1e-6
#: Fewest periods a recording needs for its transient to be checked (half of them form the reference).
TRANSIENT_MIN_PERIODS = 4
#: A peak-to-peak swing of ybar within this many ulps of its level is a constant output.
CONSTANT_ULPS = 64.0


def transient_periods(y: FloatArray, p: int, s: int, n: int) -> int:
    """Leading periods of ``y[s p : (s + n) p]`` still in transient (at most ``n // 2``).

    Each period is compared with the average of the last half of the window (the steady reference, whose
    period-to-period spread gives the noise level): the recording path's counterpart of the measurement
    path's steady-segment detection.
    """
    if n < TRANSIENT_MIN_PERIODS:
        return 0
    seg = np.asarray(y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p)
    tail = seg[n // 2 :]
    ref = tail.mean(axis=0)
    noise = float(np.mean(np.var(tail, axis=0, ddof=1)))
    centred_power = float(np.mean((ref - ref.mean()) ** 2))
    tol = noise * (1.0 + 1.0 / tail.shape[0]) * (1.0 + TRANSIENT_CHI2_SD / math.sqrt(p))
    tol += TRANSIENT_RTOL**2 * centred_power
    dev = np.mean((seg[: n // 2] - ref) ** 2, axis=1)
    k = 0
    while k < dev.size and dev[k] > tol:
        k += 1
    return k


def _check_response(ybar: FloatArray, level: float, noise_var: float, n: float, source: str) -> None:
    """Refuse an output with no response at the excitation: constant, or nowhere above the noise floor."""
    swing = float(np.ptp(ybar))
    constant = swing <= CONSTANT_ULPS * np.finfo(np.float64).eps * max(level, float(np.max(np.abs(ybar))))
    buried = False
    if not constant and math.isfinite(noise_var) and noise_var > 0.0 and n > 0:
        p = ybar.size
        power = np.abs(np.fft.rfft(ybar - ybar.mean())[1:] / p) ** 2
        buried = not bool(np.any(power > HARMONIC_SNR * noise_var / (n * p)))
    if constant or buried:
        what = "is constant" if constant else "holds no harmonic above the noise floor"
        raise ZeroAmplitudeError(
            f"{source}: the averaged output {what} (peak-to-peak {swing:.3g} at level {level:.3g}): the "
            "system shows no response to this excitation, so nothing can be identified; check the output "
            "channel and its range"
        )


def _harmonics(harmonics: int | str, ybar: FloatArray, noise_var: float, n: float) -> int:
    p = ybar.size
    if harmonics == "auto":
        return auto_harmonics(ybar, noise_var, n)
    if harmonics == "all":
        return (p - 1) // 2
    if isinstance(harmonics, (int, np.integer)) and not isinstance(harmonics, bool):
        return int(harmonics)
    raise InvalidParameterError(f"harmonics must be 'auto', 'all' or an int, got {harmonics!r}")


def _prepare_recording(
    i: int,
    rec: Recording,
    core: Paper,
    settle_periods: Optional[int],
    periods: Optional[int],
    harmonics: int | str,
) -> Prepared:
    """The paper's path: a whole number of samples per period and the periodic average (4a-b)."""
    p = rec.samples_per_period
    s = rec.settle_periods if settle_periods is None else int(settle_periods)
    if s < 0:
        raise InvalidParameterError(f"settle_periods = {s} must be >= 0")
    n = rec.whole_periods - s if periods is None else int(periods)
    if n < 1 or s + n > rec.whole_periods:
        raise InsufficientDataError(
            f"{item_label(i, rec, 'recording')} holds {rec.whole_periods} whole periods; {s} settling + "
            f"{max(n, 1)} averaged periods do not fit. Record longer or lower settle_periods/periods"
        )
    source = rec.metadata.get("name", f"recording {i}")
    # The input first: a wrong frequency misaligns the periods, which is no transient.
    check_input(rec, s * p, (s + n) * p)
    if periods is None:
        # A transient left in would inflate the noise floor and bias the loop: trim it, as the measurement
        # path keeps only steady stretches, and say so.
        extra = transient_periods(rec.y, p, s, n)
        if extra:
            warnings.warn(
                f"{source}: the first {extra} of the {n} periods after {s} settling ones are still "
                f"transient (they differ from the steady periods beyond the noise); they were dropped, "
                f"settle_periods = {s + extra} is used. Pass settle_periods to choose",
                TransientWarning,
                stacklevel=4,
            )
            s, n = s + extra, n - extra
    averaged = np.asarray(core.periodic_average(np.ascontiguousarray(rec.y), p, s, n))
    noise_var = noise_variance(rec.y, p, s, n)
    # The model's steady loop has no mean: the output's mean is an offset (sensor, conditioning), removed
    # and reported as the measurement path does.
    offset = float(np.mean(averaged))
    _check_response(averaged, abs(offset), noise_var, n, source)
    ybar = averaged - offset
    k = _harmonics(harmonics, ybar, noise_var, n)
    ydot = np.asarray(core.spectral_derivative(ybar, rec.frequency, k))
    # The averaged window starts at t[0] + s whole periods: the local phase is shifted by omega t[0].
    return Prepared(
        amplitude=rec.amplitude,
        frequency=rec.frequency,
        phase_shift=rec.frequency * float(rec.t[0]),
        p=p,
        s=s,
        n=n,
        k=k,
        ybar=ybar,
        ydot=ydot,
        noise_var=noise_var,
        noise_dof=p * (n - 1),
        plant=rec.plant,
        source=source,
        offset=offset,
    )


def _prepare_averaged(ap: AveragedPeriod, core: Paper, harmonics: int | str) -> Prepared:
    """A period averaged from lab data (any sampling rate): its grid starts at the input's phase zero."""
    ybar = np.ascontiguousarray(ap.ybar, dtype=np.float64)
    _check_response(ybar, abs(float(ap.offset_y)), float(ap.noise_var), float(ap.periods), str(ap.source))
    k = _harmonics(harmonics, ybar, ap.noise_var, ap.periods)
    ydot = np.asarray(core.spectral_derivative(ybar, ap.frequency, k))
    return Prepared(
        amplitude=ap.amplitude,
        frequency=ap.frequency,
        phase_shift=0.0,
        p=ybar.size,
        s=0,
        n=float(ap.periods),
        k=k,
        ybar=ybar,
        ydot=ydot,
        noise_var=float(ap.noise_var),
        noise_dof=int(ap.noise_dof),
        plant=None,
        source=str(ap.source),
        offset=float(ap.offset_y),
    )


def prepare(
    items: Sequence[Any],
    core: Paper,
    settle_periods: Optional[int],
    periods: Optional[int],
    harmonics: int | str,
) -> list[Prepared]:
    """One :class:`Prepared` per recording or averaged period, and per steady segment of a measurement.

    Raises
    ------
    InvalidParameterError
        An item of another type, or ``settle_periods``/``periods`` given for lab data.
    InsufficientDataError
        Nothing gave an averaged period.
    """
    out: list[Prepared] = []
    for i, item in enumerate(items):
        if isinstance(item, Recording):
            out.append(_prepare_recording(i, item, core, settle_periods, periods, harmonics))
            continue
        # Lab data: imported here so that the paper's path does not pay for the preprocessing modules.
        from .measurement import Measurement
        from .signal import AveragedPeriod, average_measurement

        if isinstance(item, (Measurement, AveragedPeriod)) and (settle_periods, periods) != (None, None):
            raise InvalidParameterError(
                f"item {i}: settle_periods and periods apply to Recordings only; the steady stretch of a "
                "Measurement is detected from the data. To average a chosen stretch, call "
                "signal.find_steady_segments and signal.synchronous_average(..., start=, stop=)"
            )

        if isinstance(item, AveragedPeriod):
            out.append(_prepare_averaged(item, core, harmonics))
        elif isinstance(item, Measurement):
            out.extend(_prepare_averaged(ap, core, harmonics) for ap in average_measurement(item))
        else:
            raise InvalidParameterError(
                f"item {i} is a {type(item).__name__}; identify takes Recording, Measurement or "
                "AveragedPeriod objects"
            )
    if not out:
        raise InsufficientDataError("nothing to identify: no recording gave an averaged period")
    return out


@dataclass(frozen=True)
class Scales:
    """Units in which the output and the input are of order one: ``y = y_scale y'``, ``u = u_scale u'``.

    Forces of 1500 N and strokes of 5 mm then fit as well as unit-scale data; the estimates map back by
    ``|G| = |G'| y_scale / u_scale``, ``beta = beta' / y_scale^mu``, ``gamma = gamma' / y_scale^mu``.
    """

    y: float
    u: float


def scale(prepared: Sequence[Prepared]) -> tuple[list[Prepared], Scales]:
    """The experiments in units of order one, and those units.

    Raises
    ------
    ZeroAmplitudeError
        An output or input scale outside ``[SCALE_MIN, SCALE_MAX]``, where squares and powers of the data
        leave the floating-point range.
    """
    s_y = max(float(np.max(np.abs(e.ybar))) for e in prepared) or 1.0
    s_u = max(abs(e.amplitude) for e in prepared)
    for what, size in (("output", s_y), ("input amplitude", s_u)):
        if not SCALE_MIN <= size <= SCALE_MAX:
            raise ZeroAmplitudeError(
                f"the {what} is of size {size:.3e}, outside [{SCALE_MIN:g}, {SCALE_MAX:g}]: "
                "express the data in units that keep it there (e.g. mm instead of km)"
            )
    scaled = [
        dataclasses.replace(
            e,
            amplitude=e.amplitude / s_u,
            ybar=e.ybar / s_y,
            ydot=e.ydot / s_y,
            noise_var=e.noise_var / s_y**2,
        )
        for e in prepared
    ]
    return scaled, Scales(s_y, s_u)

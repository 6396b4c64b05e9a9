"""What the library accepts: the checks and thresholds shared by every layer.

The value types (:mod:`~bouc_wen_id.model`, :mod:`~bouc_wen_id.measurement`), the lab pipeline
(:mod:`~bouc_wen_id.signal`), the readers (:mod:`~bouc_wen_id.io`), the identification and the NumPy
reference (:mod:`~bouc_wen_id.reference`) all validate through this module, so that a threshold is named
once and changing the oracle never changes what the library accepts.  It imports nothing of the package but
its errors.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import (
    ImproperTransferFunctionError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    TimeAxisError,
    UnstableSystemError,
)

__all__ = [
    "HARMONIC_SNR",
    "MIN_SAMPLES_PER_PERIOD",
    "MIN_AVERAGE_SAMPLES",
    "TIME_JITTER_RTOL",
    "EXACT_GRID_RTOL",
    "z_value",
    "finite_array",
    "finite_arrays",
    "finite_scalar",
    "real_number",
    "positive_number",
    "nonnegative_number",
    "count",
    "frozen_array",
    "check_bouc_wen",
    "routh_hurwitz_stable",
    "check_transfer_function",
    "check_time_axis",
]

FloatArray = NDArray[np.float64]

#: A harmonic is signal when its power exceeds this multiple of its noise power: the noise power of one
#: harmonic is exponential (chi-square on 2 degrees of freedom), so a false alarm has probability
#: e^-16 ~ 1e-7 per harmonic.
HARMONIC_SNR = 16.0
#: Fewest samples per period of an input whose sine is estimated from lab data (and the frequency must
#: stay below Nyquist by a margin): fewer leave the harmonic fits of the loop too little to stand on.
MIN_SAMPLES_PER_PERIOD = 16
#: Fewest samples per period of the exact periodic average (4a-b) and the phase estimator (9), as
#: ``MIN_SAMPLES_PER_PERIOD`` of ``rust/average.rs``: formulas on a given grid, not estimates.
MIN_AVERAGE_SAMPLES = 4
#: Largest deviation of a time step of lab data from the median step, relative to it.
TIME_JITTER_RTOL = 0.01
#: The same for data that state an exact grid (a :class:`~bouc_wen_id.model.Recording`, an input
#: simulated on its time axis): the paper's averaging (4a-b) needs a whole number of samples per period.
EXACT_GRID_RTOL = 1e-5
#: Rounding allowance of a time step, relative to the largest time: differences of large times lose digits.
TIME_ROUNDING_RTOL = 1e-12
#: A time column printed with few digits is taken as uniform when its rounding unit is at most this share of
#: the step (coarser printing leaves the step itself uncertain) and explains the uneven steps.
PRINTED_QUANTUM_SHARE = 1e-3


def z_value(confidence: float) -> float:
    """Two-sided standard normal quantile of a confidence level (1.96 for 0.95)."""
    from statistics import NormalDist

    return NormalDist().inv_cdf(0.5 + confidence / 2.0)


def finite_array(name: str, values: ArrayLike) -> FloatArray:
    """``values`` as a 1-D float64 array; :class:`NonFiniteError` on NaN or infinity."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 1:
        raise InvalidParameterError(f"{name} must be a 1-D array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise NonFiniteError(f"{name} holds a non-finite value at index {bad}; clean or drop it first")
    return arr


def finite_arrays(**named: ArrayLike) -> list[FloatArray]:
    """:func:`finite_array` of each keyword argument; :class:`InvalidParameterError` on unequal lengths."""
    out = [finite_array(name, v) for name, v in named.items()]
    sizes = {name: a.size for name, a in zip(named, out)}
    if len(set(sizes.values())) != 1:
        raise InvalidParameterError(f"{', '.join(named)} must have equal lengths, got {sizes}")
    return out


def finite_scalar(name: str, value: float) -> float:
    """``float(value)``; :class:`NonFiniteError` on NaN or infinity."""
    v = float(value)
    if not np.isfinite(v):
        raise NonFiniteError(f"{name} = {v} is not finite")
    return v


def real_number(name: str, value: object) -> float:
    """A user-given real number: refuses complex values and strings, then NaN and infinity."""
    if isinstance(value, (complex, np.complexfloating, str, bytes)):
        raise InvalidParameterError(f"{name} = {value!r} must be a real number")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError) as exc:
        raise InvalidParameterError(f"{name} = {value!r} is not a real number: {exc}") from None
    if not math.isfinite(v):
        raise NonFiniteError(f"{name} = {v} is not finite")
    return v


def positive_number(name: str, value: object) -> float:
    """:func:`real_number`, and > 0."""
    v = real_number(name, value)
    if not v > 0.0:
        raise InvalidParameterError(f"{name} = {v} must be > 0")
    return v


def nonnegative_number(name: str, value: object) -> float:
    """:func:`real_number`, and >= 0."""
    v = real_number(name, value)
    if not v >= 0.0:
        raise InvalidParameterError(f"{name} = {v} must be >= 0")
    return v


def count(name: str, value: object, low: int, high: Optional[int] = None) -> int:
    """A user-given integer in ``low..high`` (``high`` None: no upper end); refuses bools and floats."""
    n = int(value) if isinstance(value, (int, np.integer)) and not isinstance(value, bool) else None
    if n is None or n < low or (high is not None and n > high):
        span = f">= {low}" if high is None else f"in {low}..{high}"
        raise InvalidParameterError(f"{name} = {value!r} must be an integer {span}")
    return n


def frozen_array(name: str, values: ArrayLike, ndim: int = 1, at_least_1d: bool = False) -> FloatArray:
    """A read-only float64 copy of user data: real, ``ndim``-D and finite (the user's array is not kept).

    ``at_least_1d``: a scalar is taken as one value. A ragged list is a named error (NumPy's own
    ValueError said nothing of which argument)."""
    try:
        raw = np.atleast_1d(np.asarray(values)) if at_least_1d else np.asarray(values)
    except ValueError as exc:
        raise InvalidParameterError(
            f"{name}: expected numbers in a regular (not ragged) array, got {values!r} ({exc})"
        ) from None
    if raw.dtype.kind not in "biuf":
        raise InvalidParameterError(
            f"{name} must hold real numbers, got dtype {raw.dtype}; take the real part or convert it first"
        )
    arr = np.array(raw, dtype=np.float64, copy=True)
    if arr.ndim != ndim:
        raise InvalidParameterError(f"{name} must be {ndim}-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr.ravel()))[0])
        raise NonFiniteError(f"{name} holds a non-finite value at index {bad}; clean or drop it first")
    arr.setflags(write=False)
    return arr


def check_bouc_wen(alpha: float, beta: float, gamma: float, mu: float, w0: float) -> None:
    """The conditions of (2a) and Proposition 1: alpha > 0, beta + gamma > 0, beta >= gamma, mu >= 1."""
    for name, v in (("alpha", alpha), ("beta", beta), ("gamma", gamma), ("mu", mu), ("w0", w0)):
        finite_scalar(name, v)
    if alpha <= 0.0:
        raise InvalidParameterError(f"alpha = {alpha} must be > 0")
    if beta + gamma <= 0.0:
        raise InvalidParameterError(
            f"beta + gamma = {beta + gamma} must be > 0 for a bounded Bouc-Wen output (Proposition 1)"
        )
    if beta - gamma < 0.0:
        raise InvalidParameterError(f"beta - gamma = {beta - gamma} must be >= 0 (eq. 2a conditions)")
    if mu < 1.0:
        raise InvalidParameterError(f"mu = {mu} must be >= 1")


def routh_hurwitz_stable(den: ArrayLike) -> bool:
    """True when every root of ``den`` (highest power first) has a strictly negative real part."""
    a = np.asarray(den, dtype=np.float64)
    a = a / a[0]
    n = a.size - 1
    if n == 0:
        return True
    # Build the Routh array row by row; stability <=> every first-column entry is > 0.
    row_prev = a[0::2].copy()
    row_cur = a[1::2].copy()
    width = row_prev.size
    row_prev = np.pad(row_prev, (0, width - row_prev.size))
    row_cur = np.pad(row_cur, (0, width - row_cur.size))
    firsts = [row_prev[0], row_cur[0]]
    for _ in range(n - 1):
        if row_cur[0] <= 0.0:
            return False
        nxt = np.zeros(width)
        for j in range(width - 1):
            nxt[j] = (row_cur[0] * row_prev[j + 1] - row_prev[0] * row_cur[j + 1]) / row_cur[0]
        row_prev, row_cur = row_cur, nxt
        firsts.append(row_cur[0])
    return all(f > 0.0 for f in firsts)


def check_transfer_function(
    num: ArrayLike, den: ArrayLike, delay: float
) -> tuple[FloatArray, FloatArray, float]:
    """``G(s) = exp(-delay s) num/den`` proper, asymptotically stable, finite, with ``delay >= 0``.

    Returns ``(num, den, delay)`` with the numerator's leading zeros dropped.
    """
    b = finite_array("num", num)
    a = finite_array("den", den)
    delay = finite_scalar("delay", delay)
    if delay < 0.0:
        raise InvalidParameterError(f"delay = {delay} s is negative; a pure delay must be >= 0")
    if a.size == 0 or a[0] == 0.0:
        raise ImproperTransferFunctionError(
            "den must start with a non-zero coefficient (highest power of s first)"
        )
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        monic = a / a[0]
    if not np.all(np.isfinite(monic)):
        raise ImproperTransferFunctionError(
            f"den = {a.tolist()}: its leading coefficient {a[0]:g} is so small against the others that "
            "the monic denominator overflows (a pole beyond 1e308 rad/s); drop it or rescale den"
        )
    nz = np.flatnonzero(b)
    b = b[nz[0] :] if nz.size else np.zeros(1)
    if b.size > a.size:
        raise ImproperTransferFunctionError(
            f"G(s) is improper: numerator degree {b.size - 1} > denominator degree {a.size - 1}; "
            "a physical linear part must be proper"
        )
    if not routh_hurwitz_stable(a):
        raise UnstableSystemError(
            f"G(s) is not asymptotically stable: den = {a.tolist()} has a root with Re >= 0 "
            "(Routh-Hurwitz); the sine steady state the method relies on does not exist"
        )
    return b, a, delay


def printed_quantum(t: FloatArray) -> float:
    """The rounding unit of the largest time when every time holds few significant digits (a time column
    printed with ``%.9g``: a uniform grid then steps unevenly by up to one unit of its last digit); ``inf``
    when the times hold all of a double's digits (nothing to forgive)."""
    x = np.abs(np.asarray(t, dtype=np.float64))
    x = x[x > 0]
    if not x.size:
        return math.inf
    expo = np.floor(np.log10(x))
    for digits in range(1, 16):
        scale = 10.0 ** (digits - 1 - expo)
        back = np.round(x * scale) / scale
        if np.all(np.abs(back - x) <= 4.0 * np.spacing(x)):
            return float(10.0 ** (float(np.max(expo)) - digits + 1))
    return math.inf


def check_time_axis(
    t: FloatArray, name: str = "t", *, rtol: float = TIME_JITTER_RTOL, gap_factor: Optional[float] = None
) -> float:
    """Refuse a time axis that is not strictly increasing or whose step jitters; return the median step.

    Every step must lie within ``rtol`` of the median step (plus the rounding of the times themselves).
    With ``gap_factor``, steps longer than that multiple of the median are gaps (DAQ pauses), allowed.

    Raises
    ------
    InsufficientDataError
        Fewer than 2 samples.
    TimeAxisError
        Not strictly increasing, overflowing, or a step off the median beyond tolerance.
    """
    if t.size < 2:
        raise InsufficientDataError(f"{name} needs at least 2 samples, got {t.size}")
    with np.errstate(over="ignore", invalid="ignore"):
        steps = np.diff(t)
        span = float(t[-1]) - float(t[0])
    if not (np.all(np.isfinite(steps)) and math.isfinite(span)):
        raise TimeAxisError(f"the steps of {name} overflow: its values are too large ({t[0]:g} .. {t[-1]:g})")
    down = np.flatnonzero(steps <= 0)
    if down.size:
        i = int(down[0])
        raise TimeAxisError(
            f"{name} is not strictly increasing: {name}[{i}] = {t[i]!r}, {name}[{i + 1}] = {t[i + 1]!r}"
        )
    dt = float(np.median(steps))
    if not math.isfinite(1.0 / dt):
        raise TimeAxisError(f"the step of {name} ({dt:g} s) is too small: its sample rate overflows")
    dev = np.abs(steps - dt)
    if gap_factor is not None:
        dev[steps > gap_factor * dt] = 0.0
    worst = int(np.argmax(dev))
    top = max(abs(float(t[0])), abs(float(t[-1])))
    if dev[worst] > rtol * dt + TIME_ROUNDING_RTOL * top:
        quantum = printed_quantum(t)
        if quantum <= PRINTED_QUANTUM_SHARE * dt and dev[worst] <= rtol * dt + quantum:
            return dt  # a uniform grid whose times were printed with few digits (review 34: 9 digits)
        gaps = "" if gap_factor is None else f"; steps over {gap_factor:.6g}x the median count as gaps"
        route = (
            "resample"
            if gap_factor is not None or steps[worst] < dt
            else "bouc_wen_id.split_at_gaps(t, u, y) cuts the record at its gaps (dropped samples, pauses) "
            "into uniformly sampled Measurements, which diagnose and identify take (the pieces of one "
            "experiment at its nominal frequency), or resample"
        )
        raise TimeAxisError(
            f"{name} is not uniformly sampled: step {worst} is {steps[worst]:.9g} s against a median step of "
            f"{dt:.9g} s (more than {rtol * 100:.3g} % apart{gaps}); a constant step is needed: {route}"
        )
    return dt

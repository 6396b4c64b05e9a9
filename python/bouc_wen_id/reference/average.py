"""NumPy reference of ``rust/average.rs``: the periodic average (4a-b) of the seed paper."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
)
from ..validation import MIN_AVERAGE_SAMPLES
from ..validation import finite_array as _finite_array

__all__ = ["periodic_average"]

FloatArray = NDArray[np.float64]


def periodic_average(y: ArrayLike, samples_per_period: int, settle_periods: int, periods: int) -> FloatArray:
    """Periodic average (4a-b) over ``periods`` whole periods after ``settle_periods`` dropped ones."""
    yy = _finite_array("y", y)
    p, s, n = int(samples_per_period), int(settle_periods), int(periods)
    if p < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(
            f"samples_per_period = {p}: at least {MIN_AVERAGE_SAMPLES} samples per period are needed"
        )
    if n < 1:
        raise InsufficientDataError(f"periods = {n}: at least one period must be averaged")
    if s < 0:
        raise InvalidParameterError(f"settle_periods = {s} must be >= 0")
    need = (s + n) * p
    if yy.size < need:
        raise InsufficientDataError(
            f"the recording has {yy.size} samples = {yy.size / p:.2f} periods, but {s} settling + {n} "
            f"averaged periods need {need}; record longer or ask for fewer periods"
        )
    out: FloatArray = yy[s * p : need].reshape(n, p).mean(axis=0)
    return out

"""NumPy reference of ``rust/linear.rs``: the validated linear part G(s) and its controllable canonical
realisation.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validation import check_transfer_function, routh_hurwitz_stable

__all__ = ["realize", "routh_hurwitz_stable"]

FloatArray = NDArray[np.float64]


def realize(
    num: ArrayLike, den: ArrayLike, delay: float = 0.0
) -> tuple[FloatArray, FloatArray, float, float]:
    """Validate G(s) = e^{-delay s} num/den and return its controllable canonical form.

    Returns ``(a, c, d, delay)`` where ``a`` holds the monic denominator's coefficients ``a_1..a_n`` (the
    companion matrix's first row is ``-a``), ``c`` the output row and ``d`` the feed-through.
    """
    b, a, delay = check_transfer_function(num, den, delay)
    n = a.size - 1
    an = a / a[0]
    bn = np.concatenate([np.zeros(n + 1 - b.size), b]) / a[0]
    d = float(bn[0])
    c = bn[1:] - d * an[1:]
    return an[1:].copy(), c, d, delay

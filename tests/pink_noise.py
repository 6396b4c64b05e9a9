"""Pink (1/f) noise made without an FFT, for tests and studies of long-memory noise (review 45, failure 1).

A sum of equal-variance AR(1) processes with time constants 1, 2, 4, .. 2^(k-1) samples has a spectrum close
to 1/f between 1/(2 pi 2^(k-1)) and 1/(2 pi) cycles per sample: another way than review 45's FFT shaping
(studies/review45/sim45.py).
"""

from __future__ import annotations

import math

import numpy as np


def sum_of_ar1(n: int, rng: np.random.Generator, k: int = 12) -> np.ndarray:
    """``n`` samples of unit-variance 1/f noise: ``k`` equal-variance AR(1)s with time constants 2^j."""
    out = np.zeros(n)
    for j in range(k):
        a = math.exp(-1.0 / 2.0**j)
        e = rng.normal(size=n) * math.sqrt(1.0 - a * a)
        x = np.empty(n)
        x[0] = rng.normal()
        for i in range(1, n):
            x[i] = a * x[i - 1] + e[i]
        out += x
    return out / float(np.std(out))

"""Starting points of the feedback fit (:mod:`._feedback`): a linear (ARX) estimate of the mass-spring-damper
and seeded draws of the hysteresis around it.

At small amplitude ``z ~ alpha y``, so the records' best linear approximation is a second-order system with
stiffness ``K = k + alpha``; a least-squares ARX(2, 3) fit gives its discrete poles and static gain, hence
``m = K / wn^2`` and ``c = 2 zeta wn m`` (``c`` includes the hysteretic dissipation: an overestimate, which
the search removes).  The split of ``K`` between ``k`` and ``alpha`` and the hysteresis parameters are not
seen by a linear fit: the multi-start draws them.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..validation import count
from ._records import TimeRecord

__all__ = ["linear_start", "random_starts"]

FloatArray = NDArray[np.float64]


def _arx_rows(rec: TimeRecord) -> tuple[FloatArray, FloatArray]:
    y, u = rec.y, rec.u
    phi = np.column_stack([y[1:-1], y[:-2], u[2:], u[1:-1], u[:-2]])
    return phi, y[2:]


def linear_start(recs: list[TimeRecord]) -> FloatArray:
    """``[m, c, K/2, K/2, 0, 0, 1]`` from an ARX(2, 3) least-squares fit of all records (module docstring).

    Raises
    ------
    InvalidParameterError
        The records' linear approximation is not a stable underdamped second-order system: give ``theta0``.
    """
    rows = [_arx_rows(r) for r in recs]
    phi = np.vstack([p for p, _ in rows])
    rhs = np.concatenate([t for _, t in rows])
    coef, *_ = np.linalg.lstsq(phi, rhs, rcond=None)
    a1, a2 = float(coef[0]), float(coef[1])
    gain = float(np.sum(coef[2:])) / (1.0 - a1 - a2)
    z1 = (a1 + cmath.sqrt(a1 * a1 + 4.0 * a2)) / 2.0
    dt = recs[0].dt
    if abs(z1) >= 1.0 or abs(z1.imag) == 0.0 or not gain > 0.0:
        raise InvalidParameterError(
            "the records' linear approximation is not a stable, underdamped second-order system "
            f"(ARX pole {z1:.4g}, static gain {gain:.4g}); give theta0 = [m, c, k, alpha, beta*gamma, "
            "beta*delta, nu] near the system's parameters"
        )
    s = cmath.log(z1) / dt
    wn = abs(s)
    zeta = -s.real / wn
    stiffness = 1.0 / gain
    m = stiffness / wn**2
    return np.array([m, 2.0 * zeta * wn * m, 0.5 * stiffness, 0.5 * stiffness, 0.0, 0.0, 1.0])


def random_starts(theta_ref: FloatArray, y_rms: float, n: int, seed: int) -> list[FloatArray]:
    """``theta_ref`` then ``n - 1`` seeded draws: the mass and damping jittered, ``k + alpha`` kept and split
    at random, ``beta*gamma`` log-uniform over ``[0.1, 3] / y_rms`` and ``beta*delta`` a uniform multiple in
    ``[-1.5, 1.5]`` of it, ``nu`` as in ``theta_ref``; ``y_rms`` is the outputs' RMS."""
    n = count("starts", n, 1)
    rng = np.random.default_rng(seed)
    if not y_rms > 0.0 or not math.isfinite(y_rms):
        raise InvalidParameterError("the outputs are identically zero: nothing to fit")
    out = [np.array(theta_ref, dtype=np.float64)]
    stiffness = float(theta_ref[2] + theta_ref[3])
    for _ in range(n - 1):
        th = np.array(theta_ref, dtype=np.float64)
        th[0] *= rng.uniform(0.8, 1.25)
        th[1] *= rng.uniform(0.3, 1.0)
        share = rng.uniform(0.2, 0.8)
        th[2], th[3] = share * stiffness, (1.0 - share) * stiffness
        th[4] = 10.0 ** rng.uniform(-1.0, math.log10(3.0)) / y_rms
        th[5] = rng.uniform(-1.5, 1.5) * th[4]
        out.append(th)
    return out

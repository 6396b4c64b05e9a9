"""NumPy reference of ``rust/dahl.rs``: Dahl friction's steady loop under a sine, in closed form.

Written from the formulas of the module header of ``rust/dahl.rs`` (docs/diagnosis.md, "Dahl friction"),
vectorised over the grid: ``v_j = a cos(psi_j)``, ``psi_j = 2 pi j / P + psi0`` (``+ pi`` for ``a < 0``);
on the falling branch (``sin psi >= 0``) ``s = -1``, ``xi = 1 - cos psi``, on the rising one ``s = +1``,
``xi = 1 + cos psi``; ``r = sigma |a| / Fc``, ``E = 2 exp(-r xi) / (1 + exp(-2 r))`` and
``F = s Fc (1 - E)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..validation import finite_scalar as _finite_scalar

__all__ = ["dahl_loop"]

FloatArray = NDArray[np.float64]


def dahl_loop(
    a: float, psi0: float, fc: float, sigma: float, p: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(F, dF/dFc, dF/dsigma, dF/da, dF/dpsi0)`` on the P-point grid (``a`` signed)."""
    _finite_scalar("dahl amplitude", a)
    _finite_scalar("dahl phase", psi0)
    _finite_scalar("dahl Fc", fc)
    _finite_scalar("dahl sigma", sigma)
    if fc < 0.0 or sigma < 0.0:
        raise InvalidParameterError(
            f"Dahl friction needs Fc >= 0 and sigma >= 0, got Fc = {fc}, sigma = {sigma}"
        )
    aa = abs(a)
    shift = math.pi if a < 0.0 else 0.0
    sa = -1.0 if a < 0.0 else 1.0
    r = sigma * aa / fc if fc > 0.0 else math.inf
    th = math.tanh(r)
    den = 1.0 + math.exp(-2.0 * r)
    psi = np.mod(2.0 * math.pi * np.arange(p) / p + psi0 + shift, 2.0 * math.pi)
    sn, cs = np.sin(psi), np.cos(psi)
    falling = psi <= math.pi
    s = np.where(falling, -1.0, 1.0)
    xi = np.where(falling, 1.0 - cs, 1.0 + cs)
    if math.isfinite(r):
        em = np.exp(-r * xi)
    else:
        em = np.where(xi > 0.0, 0.0, 1.0)
    e = 2.0 * em / den
    de = e * (1.0 - th - xi)
    finite = math.isfinite(r)
    f = s * fc * (1.0 - e)
    d_fc = s * (1.0 - e) + (s * de * r if finite else 0.0)
    d_sigma = -s * aa * de if finite else np.zeros(p)
    d_a = -s * sigma * de * sa if finite else np.zeros(p)
    d_psi = -sigma * aa * e * sn
    return f, np.asarray(d_fc, dtype=np.float64), d_sigma, d_a, d_psi

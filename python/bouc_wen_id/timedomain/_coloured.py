"""Standard errors that count the residuals' correlation (review 36, problem 9).

The time-domain fit's covariance ``sigma^2 (J^T J)^-1`` holds for white residuals. Coloured measurement noise
(AR(1) with rho = 0.8: review 36 reported c = 0.0147041 ± 8.41e-05 against a truth of 0.014525, 2.1 se off,
beside its own whiteness test at p = 0) leaves the estimate unbiased but its spread several times that
covariance's: neighbouring samples carry nearly the same noise, so there are fewer independent samples than
rows of J.

:func:`hac_covariance` is the Newey-West sandwich ``B S B`` with ``B = (J^T J)^-1`` and ``S`` the long-run
covariance of the scores ``g_t = J_t e_t``, Bartlett-weighted over ``L`` lags within each record (records
are independent of one another). ``L`` follows Andrews' AR(1) plug-in bandwidth from the residuals' own lag-1
correlation, at least Newey-West's ``4 (n/100)^(2/9)``.

:func:`widened` is what the fit uses when its residuals fail the whiteness test: each standard error the
larger of the white one and the sandwich's, with the sandwich's correlations (``D R D`` stays positive
semi-definite). A fit whose residuals are white keeps its covariance (the Cramer-Rao one at the truth).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def bandwidth(resid: Sequence[FloatArray]) -> int:
    """Lags ``L``: Andrews' AR(1) plug-in ``1.1447 (a n)^(1/3)``, ``a = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2)``
    with ``rho`` the residuals' pooled lag-1 correlation (clipped to 0.97), at least ``4 (n/100)^(2/9)``,
    at most a quarter of the shortest record."""
    num = sum(float(r[1:] @ r[:-1]) for r in resid if r.size > 1)
    den = sum(float(r @ r) for r in resid)
    rho = min(max(num / den if den > 0 else 0.0, -0.97), 0.97)
    n = max(min(r.size for r in resid), 2)
    a = 4.0 * rho**2 / ((1.0 - rho) ** 2 * (1.0 + rho) ** 2)
    lags = max(1.1447 * (a * n) ** (1.0 / 3.0), 4.0 * (n / 100.0) ** (2.0 / 9.0))
    return int(max(1, min(math.ceil(lags), n // 4)))


def hac_covariance(jac: Sequence[FloatArray], resid: Sequence[FloatArray], lags: int) -> FloatArray:
    """The Newey-West covariance of the least-squares estimate, per-record blocks ``jac[i]`` (samples x
    parameters) and residuals ``resid[i]``; the parameters' columns must be of full rank together."""
    jt = np.concatenate(jac, axis=0)
    norms = np.linalg.norm(jt, axis=0)
    norms[norms == 0.0] = 1.0
    bread = np.linalg.pinv((jt / norms).T @ (jt / norms)) / np.outer(norms, norms)
    p = jt.shape[1]
    meat = np.zeros((p, p))
    for j, e in zip(jac, resid):
        g = j * e[:, None]
        meat += g.T @ g
        for lag in range(1, min(lags, g.shape[0] - 1) + 1):
            c = g[lag:].T @ g[:-lag]
            meat += (1.0 - lag / (lags + 1.0)) * (c + c.T)
    out: FloatArray = bread @ meat @ bread
    sym: FloatArray = 0.5 * (out + out.T)
    return sym


def widened(cov: FloatArray, hac: FloatArray) -> FloatArray:
    """``D R D``: each standard error the larger of ``cov``'s and ``hac``'s, ``R`` the sandwich's
    correlations (``cov`` where the sandwich has no finite, positive variance)."""
    sw, sh = np.sqrt(np.clip(np.diag(cov), 0.0, None)), np.sqrt(np.clip(np.diag(hac), 0.0, None))
    ok = np.isfinite(sh) & (sh > 0.0) & np.isfinite(sw)
    if not np.all(ok):
        return cov
    r = hac / np.outer(sh, sh)
    d = np.maximum(sw, sh)
    out: FloatArray = r * np.outer(d, d)
    return out

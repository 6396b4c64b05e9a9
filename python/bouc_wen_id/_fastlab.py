"""Fast harmonic least squares for the lab preprocessing (issue #8), on the Rust kernels.

``bouc_wen_id.signal._harmonic_ls`` fits harmonic series ``c + sum_k a_k cos(k theta) + b_k sin(k theta)``
to long records: K <= 10 harmonics of the input in the sine analysis, up to 200 of the output in the
synchronous average.  Its reference paths form the basis (O(n K)) and reduce it by Householder QR
(O(n K^2)), or (``_moment_fit``) build the Gram matrix from complex moments computed by a NumPy loop of
2K + 1 passes over the record.  Here a whole fit is one call of ``_core.harmonic_fit`` (``rust/lab/fit.rs``):
the moments in one vectorised pass, the Gram matrix (Toeplitz-plus-Hankel in the moments), its conditioning
check, the Cholesky factor, the two triangular solves and the explicit residual, each the reference's
formula; and the frequency Gauss-Newton of ``signal._sine._nls`` is one call of ``_core.harmonic_nls``.
The conditioning check is first tried by Gershgorin's theorem on the scaled Gram matrix (which certifies
``cond <= 1e4`` without an eigen-decomposition when the harmonics are nearly orthogonal, as over several
periods); only when it cannot certify are the eigenvalues computed, so the decision is the reference's.

Each function returns ``None`` when the Gram matrix is too ill-conditioned for the normal equations
(``cond > 1e4``, e.g. a record shorter than a period or a harmonic near Nyquist); the caller then uses its
QR path.  ``tests/test_fastlab.py`` holds these paths to the NumPy reference.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import NDArray

from . import _core

FloatArray = NDArray[np.float64]

#: Largest condition number of the scaled Gram matrix for which the normal equations are used (as
#: ``signal._harmonic_ls._moment_fit``).
GRAM_COND_MAX = 1e4


def well_conditioned(gram: FloatArray) -> bool:
    """``cond(D^-1/2 G D^-1/2) <= 1e4`` (and positive definite), the check of the fused fit."""
    g = np.ascontiguousarray(gram, dtype=np.float64)
    return _core.gram_well_conditioned(g.ravel(), g.shape[0])


def _fit(
    theta: FloatArray, y: FloatArray, kmax: int, omega: Optional[float]
) -> Optional[tuple[FloatArray, FloatArray, FloatArray, float]]:
    th = np.ascontiguousarray(theta, dtype=np.float64)
    yy = np.ascontiguousarray(y, dtype=np.float64)
    out = _core.harmonic_fit(th, yy, kmax, omega)
    if out is None:
        return None
    coef, r, qty, rss = out
    m = coef.size
    return coef, r.reshape(m, m), qty, rss


def moment_fit(
    theta: FloatArray, y: FloatArray, kmax: int, omega: Optional[float] = None
) -> Optional[tuple[FloatArray, FloatArray, float]]:
    """``(R, Q^T y, residual^2)`` of the K-harmonic fit, as ``signal._harmonic_ls._moment_fit``; ``None`` when
    ill-conditioned (use the QR path).  With ``omega``, ``theta`` holds times and the phases are ``omega
    theta`` (no wrapped phase array formed)."""
    out = _fit(theta, y, kmax, omega)
    return None if out is None else (out[1], out[2], out[3])


def harmonic_lsq(
    theta: FloatArray, x: FloatArray, kmax: int, omega: Optional[float] = None
) -> Optional[tuple[FloatArray, FloatArray, float]]:
    """``(coef, R, residual^2)`` of the K-harmonic least-squares fit (``R`` the Cholesky factor of the
    Gram matrix: the QR path's R up to the signs of its rows, which neither the solution nor the variances
    see); ``None`` when ill-conditioned.  ``omega`` as :func:`moment_fit`."""
    out = _fit(theta, x, kmax, omega)
    return None if out is None else (out[0], out[1], out[3])


def nls(
    tau: FloatArray, x: FloatArray, omega0: float, dt: float, k: int
) -> Optional[tuple[float, FloatArray, float, float]]:
    """``(omega, coef, rss, se)`` of ``signal._sine._nls`` (the same Gauss-Newton on omega, step rule and
    stopping rule) in one Rust call, without forming the basis; ``None`` when a fit is ill-conditioned (the
    caller then runs the reference)."""
    tt = np.ascontiguousarray(tau, dtype=np.float64)
    xx = np.ascontiguousarray(x, dtype=np.float64)
    return _core.harmonic_nls(tt, xx, float(omega0), float(dt), int(k))

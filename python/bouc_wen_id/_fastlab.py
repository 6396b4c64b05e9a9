"""Fast harmonic least squares for the lab preprocessing (issue #8), on the Rust moment kernels.

``bouc_wen_id.signal._harmonic_ls`` fits harmonic series ``c + sum_k a_k cos(k theta) + b_k sin(k theta)``
to long records: K <= 10 harmonics of the input in the sine analysis, up to 200 of the output in the
synchronous average.  Its reference paths form the basis (O(n K)) and reduce it by Householder QR
(O(n K^2)), or (``_moment_fit``) build the Gram matrix from complex moments computed by a NumPy loop of 2K + 1
passes over the record.  Here the moments come from one pass of ``_core.harmonic_moments`` and the
explicit residual from ``_core.harmonic_series`` (``rust/lab.rs``); the Gram matrix (Toeplitz-plus-Hankel in
the moments), its conditioning check and the Cholesky factor are formed exactly as in
``_moment_fit``.  The conditioning check is first tried by Gershgorin's theorem on the scaled
Gram matrix (which certifies ``cond <= 1e4`` without an eigen-decomposition when the harmonics are nearly
orthogonal, as over several periods); only when it cannot certify are the eigenvalues computed, so the
decision is the reference's.

Each function returns ``None`` when the Gram matrix is too ill-conditioned for the normal equations
(``cond > 1e4``, e.g. a record shorter than a period or a harmonic near Nyquist); the caller then uses its
QR path.  ``tests/test_fastlab.py`` holds these paths to the NumPy reference.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Largest condition number of the scaled Gram matrix for which the normal equations are used (as
#: ``signal._harmonic_ls._moment_fit``).
GRAM_COND_MAX = 1e4


def gram_from_moments(
    mom: NDArray[np.complex128], rhs: NDArray[np.complex128], kmax: int
) -> tuple[FloatArray, FloatArray]:
    """Real Gram matrix of ``[1, c1, s1, c2, s2, ...]`` and ``X^T y`` from the complex moments.

    ``mom[q] = sum e^{i q theta}`` (q = 0..2K), ``rhs[q] = sum y e^{-i q theta}`` (q = 0..K); the same
    formulas as ``signal._harmonic_ls._moment_fit``.
    """
    m = 2 * kmax + 1
    mu = np.concatenate([np.conj(mom[:0:-1]), mom])
    ks = np.concatenate([[0], np.repeat(np.arange(1, kmax + 1), 2)])
    is_sin = np.concatenate([[False], np.tile([False, True], kmax)])
    lo = mu[ks[:, None] - ks[None, :] + 2 * kmax]
    hi = mu[ks[:, None] + ks[None, :] + 2 * kmax]
    si, sj = is_sin[:, None], is_sin[None, :]
    gram = np.where(
        si & sj,
        0.5 * (lo.real - hi.real),
        np.where(
            si, 0.5 * (hi.imag + lo.imag), np.where(sj, 0.5 * (hi.imag - lo.imag), 0.5 * (lo.real + hi.real))
        ),
    )
    gram = np.asarray(0.5 * (gram + gram.T), dtype=np.float64)
    xty = np.empty(m)
    xty[0] = rhs[0].real
    xty[1::2] = rhs[1:].real
    xty[2::2] = -rhs[1:].imag
    return gram, xty


def well_conditioned(gram: FloatArray) -> bool:
    """``cond(D^-1/2 G D^-1/2) <= 1e4`` (and positive definite), as ``_harmonic_ls._moment_fit`` decides.

    Gershgorin first: every eigenvalue of the unit-diagonal scaled matrix lies within ``r`` of 1, ``r`` its
    largest off-diagonal absolute row sum, so ``r < 1`` and ``(1 + r)/(1 - r) <= 1e4`` certify the check.
    """
    diag = np.diag(gram)
    if not np.all(diag > 0.0):
        return False
    scale = np.sqrt(diag)
    scaled = gram / np.outer(scale, scale)
    radius = float(np.max(np.sum(np.abs(scaled), axis=1) - np.abs(np.diag(scaled))))
    if radius < 1.0 and (1.0 + radius) <= GRAM_COND_MAX * (1.0 - radius):
        return True
    eig = np.linalg.eigvalsh(scaled)
    return bool(eig[0] > 0.0 and eig[-1] / eig[0] <= GRAM_COND_MAX)


def moment_fit(theta: FloatArray, y: FloatArray, kmax: int) -> Optional[tuple[FloatArray, FloatArray, float]]:
    """``(R, Q^T y, residual^2)`` of the K-harmonic fit, as ``signal._harmonic_ls._moment_fit``; ``None`` when
    ill-conditioned (use the QR path)."""
    from scipy.linalg import solve_triangular  # type: ignore[import-untyped]

    from . import _core

    th = np.ascontiguousarray(theta, dtype=np.float64)
    yy = np.ascontiguousarray(y, dtype=np.float64)
    mr, mi, rr, ri = _core.harmonic_moments(th, yy, kmax)
    gram, xty = gram_from_moments(mr + 1j * mi, rr + 1j * ri, kmax)
    if not well_conditioned(gram):
        return None
    m = gram.shape[0]
    # In Rust: LAPACK through a threaded OpenBLAS wakes its threads even for this small matrix (issue #8).
    r = _core.cholesky_upper(np.ascontiguousarray(gram).ravel(), m).reshape(m, m)
    qty: FloatArray = solve_triangular(r, xty, trans="T")
    coef = solve_triangular(r, qty)
    # In Rust: a BLAS ddot on the n-vector wakes OpenBLAS's threads, which on a loaded machine costs
    # milliseconds, more than the whole fit (issue #8, measured on the bench's records).
    return r, qty, _core.harmonic_rss(th, yy, np.ascontiguousarray(coef))


def harmonic_lsq(
    theta: FloatArray, x: FloatArray, kmax: int
) -> Optional[tuple[FloatArray, FloatArray, float]]:
    """``(coef, R, residual^2)`` of the K-harmonic least-squares fit (``R`` the Cholesky factor of the
    Gram matrix: the QR path's R up to the signs of its rows, which neither the solution nor the variances
    see); ``None`` when ill-conditioned."""
    from scipy.linalg import solve_triangular

    out = moment_fit(theta, x, kmax)
    if out is None:
        return None
    r, qty, rss = out
    coef: FloatArray = solve_triangular(r, qty)
    return coef, r, rss


def nls(
    tau: FloatArray, x: FloatArray, omega0: float, dt: float, k: int
) -> Optional[tuple[float, FloatArray, float, float]]:
    """``(omega, coef, rss, se)`` of ``signal._sine._nls`` (the same Gauss-Newton on omega, step rule and
    stopping rule) without forming the basis: each fit from :func:`harmonic_lsq`, the Gauss-Newton terms
    ``r.d, d.d, X^T d`` from one pass of ``_core.harmonic_gauss_newton``.  ``None`` when a fit is
    ill-conditioned (the caller then runs the reference)."""
    from scipy.linalg import solve_triangular

    from . import _core

    tt = np.ascontiguousarray(tau, dtype=np.float64)
    xx = np.ascontiguousarray(x, dtype=np.float64)
    n = xx.size
    bin_width = 2.0 * np.pi / (n * dt)
    two_pi = 2.0 * np.pi

    def fit(omega: float) -> Optional[tuple[FloatArray, tuple[FloatArray, FloatArray, float]]]:
        theta = np.mod(omega * tt, two_pi)  # as _harmonic_ls.phase_angle
        out = harmonic_lsq(theta, xx, k)
        return None if out is None else (theta, out)

    omega = omega0
    cur = fit(omega)
    if cur is None:
        return None
    theta, (coef, r_factor, rss) = cur
    se = np.inf
    dof = max(n - (2 * k + 1) - 1, 1)
    for _ in range(60):
        _, r_d, d_d, xtd = _core.harmonic_gauss_newton(theta, tt, xx, coef)
        q_t_d = solve_triangular(r_factor, xtd, trans="T")
        d_perp2 = d_d - float(q_t_d @ q_t_d)
        if not d_perp2 > 0.0:
            break
        se = float(np.sqrt(rss / dof / d_perp2))
        step = r_d / d_perp2
        step = min(max(step, -0.5 * bin_width), 0.5 * bin_width)
        if not np.isfinite(step) or abs(step) <= max(1e-12 * bin_width, 1e-4 * se):
            break
        previous = rss
        for _half in range(10):
            trial = omega + step
            if trial > 0.0:
                cand = fit(trial)
                if cand is None:
                    return None
                if cand[1][2] <= rss:
                    omega = trial
                    theta, (coef, r_factor, rss) = cand
                    break
            step *= 0.5
        if previous - rss <= 1e-14 * previous:
            break
    return omega, coef, rss, se

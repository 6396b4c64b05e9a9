"""Least squares on harmonics of a known frequency, shared by the sine analysis, the steady-segment
detector and the synchronous average.

The basis ``[1, cos(theta), sin(theta), ..., cos(K theta), sin(K theta)]`` at ``theta = omega tau``; fits by
Householder QR (no Q formed), the nested sub-fits of a blocked QR, and a moment (Toeplitz Gram) path for
very long records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .._backend import current_lab
from ..errors import InvalidParameterError

__all__ = [
    "HarmonicFit",
    "HarmonicLS",
    "fit_at",
    "gram_from_moments",
    "harmonic_basis",
    "nested_fit",
    "phase_angle",
    "solve_qr",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Harmonic fits costing more than this many flops (``n (2K+1)^2``) by QR use the moment path instead.
QR_WORK_MAX = 1e9
#: Rows per chunk of the blocked QR.
QR_CHUNK = 8192
# The fits go through the lab kernels of the backend in force (``bouc_wen_id._backend.current_lab``: on
# Rust, O(n K) moments and the normal equations of the nearly orthogonal harmonics) whenever their Gram
# matrix is well conditioned, else through the NumPy paths below.  The NumPy backend has no kernels and
# runs the NumPy paths throughout: the reference tests/test_fastlab.py holds the kernels to.


def solve_triangular(a: FloatArray, b: FloatArray, **kwargs: Any) -> Any:
    """``scipy.linalg.solve_triangular``, imported on first use: ``import bouc_wen_id`` stays free of
    SciPy (issue #8: import in under 0.2 s)."""
    from scipy.linalg import solve_triangular as solve  # type: ignore[import-untyped]

    return solve(a, b, **kwargs)


def harmonic_basis(theta: FloatArray, harmonics: int) -> FloatArray:
    """``[1, cos(theta), sin(theta), cos(2 theta), sin(2 theta), ...]`` up to ``harmonics``.

    The harmonics come from the angle-addition recurrence (rounding grows like k eps: 1e-13 at k = 200).
    """
    out = np.empty((theta.size, 2 * harmonics + 1), order="F")
    out[:, 0] = 1.0
    c1, s1 = np.cos(theta), np.sin(theta)
    out[:, 1], out[:, 2] = c1, s1
    for k in range(2, harmonics + 1):
        c, s = out[:, 2 * k - 3], out[:, 2 * k - 2]
        out[:, 2 * k - 1] = c * c1 - s * s1
        out[:, 2 * k] = s * c1 + c * s1
    return out


def harmonic_series(theta: FloatArray, coeffs: Any) -> FloatArray:
    """``Re sum_h coeffs[h] exp(i h theta)`` (a period's harmonics at the phases ``theta``), by Horner's
    rule in ``z = exp(i theta)``: O(n K) products instead of the n K complex exponentials of
    ``exp(1j outer(theta, arange(K))) @ coeffs`` (0.33 s for 20000 samples x 201 harmonics, 5 ms here).
    Rounding grows like K eps of ``sum |coeffs|``; the exponentials' own error at large ``theta`` (the
    rounded ``h theta``, 1e-12 of the loop at ``theta`` ~ 300) is the larger of the two."""
    c = np.asarray(coeffs, dtype=np.complex128)
    th = np.asarray(theta, dtype=np.float64)
    if c.size == 0:
        return np.zeros(th.shape)
    z = np.exp(1j * th)
    acc = np.full(th.shape, c[-1], dtype=np.complex128)
    for h in range(c.size - 2, -1, -1):
        acc *= z
        acc += c[h]
    out: FloatArray = acc.real.copy()
    return out


def phase_angle(omega: float, tau: FloatArray) -> FloatArray:
    """``omega tau`` wrapped to [0, 2 pi)."""
    out: FloatArray = np.mod(omega * tau, TWO_PI)
    return out


def solve_qr(matrix: FloatArray, rhs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Least squares by Householder QR of ``[A b]`` (no Q formed): ``(solution, R)``.

    A rank-deficient basis (a harmonic at Nyquist, a record shorter than the basis) falls back to the
    minimum-norm SVD solution, with a scaled identity standing in for R (the variances derived from it
    are then meaningless, but such inputs are refused as undersampled or too short anyway).
    """
    m = matrix.shape[1]
    r_aug = np.asarray(np.linalg.qr(np.column_stack([matrix, rhs]), mode="r"), dtype=np.float64)
    r = r_aug[:m, :m]
    diag = np.abs(np.diag(r)) if r.shape[0] == m else np.zeros(m)
    if diag.min() <= 1e-12 * max(float(diag.max()), np.finfo(np.float64).tiny):
        sol_ls = np.asarray(np.linalg.lstsq(matrix, rhs, rcond=None)[0], dtype=np.float64)
        return sol_ls, np.eye(m) * max(float(diag.max()), 1.0)
    sol: FloatArray = solve_triangular(r, r_aug[:m, m])
    return sol, r


def _unscaled_variance(r: FloatArray) -> FloatArray:
    """Diagonal of ``(R^T R)^-1``, the row sums of squares of ``R^-1`` (``R`` upper triangular)."""
    fast = current_lab().unscaled_variances(r)
    if fast is not None:
        return fast
    m = r.shape[0]
    # R is triangular: its inverse by back substitution, a third of a general inverse's work.
    r_inv = solve_triangular(r, np.eye(m))
    ref: FloatArray = np.sum(r_inv**2, axis=1)
    return ref


@dataclass
class HarmonicFit:
    """A least-squares fit of ``x`` on the harmonic basis at the phases ``omega tau``."""

    coef: FloatArray  # [c, a_1, b_1, a_2, b_2, ...]
    rss: float
    r_factor: FloatArray
    tau: FloatArray
    omega: float

    @property
    def harmonics(self) -> int:
        return (self.coef.size - 1) // 2

    @cached_property
    def theta(self) -> FloatArray:
        """The phases ``omega tau`` wrapped to [0, 2 pi) (formed on first use: the fast path needs none)."""
        return phase_angle(self.omega, self.tau)

    @cached_property
    def basis(self) -> FloatArray:
        """The basis ``[1, cos theta, sin theta, ...]`` (formed on first use: the fast path needs none)."""
        return harmonic_basis(self.theta, self.harmonics)

    def variances(self) -> FloatArray:
        """The noise variance of each coefficient: residual variance times the diagonal of ``(X^T X)^-1``."""
        dof = self.tau.size - self.coef.size
        try:
            out: FloatArray = _unscaled_variance(self.r_factor) * (self.rss / dof if dof > 0 else 0.0)
        except (np.linalg.LinAlgError, InvalidParameterError):
            out = np.zeros(self.coef.size)
        return out

    def fundamental_rss(self, x: FloatArray) -> float:
        """``|x - c - a_1 cos theta - b_1 sin theta|^2``: what offset and fundamental leave of ``x``."""
        head = np.ascontiguousarray(self.coef[:3])
        fast = current_lab().harmonic_rss(self.tau, x, head, self.omega)
        if fast is not None:
            return fast
        r = x - self.basis[:, :3] @ head
        return float(np.einsum("i,i->", r, r))


def fit_at(tau: FloatArray, x: FloatArray, omega: float, k: int) -> HarmonicFit:
    """Linear fit of ``x`` on harmonics 1..k of ``omega`` at times ``tau`` (and a constant)."""
    fast = current_lab().harmonic_lsq(tau, x, k, omega)
    if fast is not None:
        # The residual sum of squares comes from the kernels too (no BLAS on the n-vectors), and neither
        # the wrapped phases nor the basis are formed.
        coef, r_factor, rss = fast
        return HarmonicFit(coef, rss, r_factor, tau, omega)
    theta = phase_angle(omega, tau)
    basis = harmonic_basis(theta, k)
    coef, r_factor = solve_qr(basis, x)
    r = x - basis @ coef
    fit = HarmonicFit(coef, float(r @ r), r_factor, tau, omega)
    fit.theta, fit.basis = theta, basis  # already formed: cached
    return fit


class HarmonicLS:
    """Least-squares fit of ``y`` on ``[1, cos k theta, sin k theta]``, k <= K_max, and its nested sub-fits.

    From the R factor of the basis and ``Q^T y``: the fit with the first ``2k + 1`` columns is
    ``R[:m, :m]^-1 (Q^T y)[:m]`` and its residual is the full one plus ``|(Q^T y)[m:]|^2``.
    """

    def __init__(self, r: FloatArray, qty: FloatArray, rss: float) -> None:
        self.r, self.qty, self.rss_full = r, qty, rss

    def coef(self, k: int) -> FloatArray:
        m = 2 * k + 1
        out: FloatArray = solve_triangular(self.r[:m, :m], self.qty[:m])
        return out

    def rss(self, k: int) -> float:
        m = 2 * k + 1
        return self.rss_full + float(self.qty[m:] @ self.qty[m:])

    def unscaled_variance(self, k: int) -> FloatArray:
        """Diagonal of ``(X^T X)^-1`` for the first ``2k + 1`` columns."""
        m = 2 * k + 1
        return _unscaled_variance(self.r[:m, :m])


def _qr_fit(theta: FloatArray, y: FloatArray, kmax: int) -> tuple[FloatArray, FloatArray, float]:
    """Blocked Householder QR of ``[X y]`` (X the harmonic basis): ``(R, Q^T y, residual^2)``.

    Row blocks of ``QR_CHUNK`` samples are reduced one after the other, each on top of the previous ``R``,
    so memory stays ``O(QR_CHUNK m)`` whatever the record's length.
    """
    m = 2 * kmax + 1
    acc: Optional[FloatArray] = None
    for s in range(0, y.size, QR_CHUNK):
        block = np.column_stack([harmonic_basis(theta[s : s + QR_CHUNK], kmax), y[s : s + QR_CHUNK]])
        if acc is not None:
            block = np.vstack([acc, block])
        acc = np.asarray(np.linalg.qr(block, mode="r"), dtype=np.float64)
    assert acc is not None
    rr = np.zeros((m + 1, m + 1))
    rows = min(acc.shape[0], m + 1)
    rr[:rows] = acc[:rows]
    return rr[:m, :m], rr[:m, m], float(rr[m, m] ** 2)


def gram_from_moments(
    mom: NDArray[np.complex128], rhs: NDArray[np.complex128], kmax: int
) -> tuple[FloatArray, FloatArray]:
    """Real Gram matrix of ``[1, c1, s1, c2, s2, ...]`` and ``X^T y`` from the complex moments
    ``mom[q] = sum e^{i q theta}`` (q = 0..2K) and ``rhs[q] = sum y e^{-i q theta}`` (q = 0..K).

    ``mu[d]``, d = -2K..2K (``mu[-d]`` the conjugate): ``cos a cos b = (cos(a-b) + cos(a+b))/2``,
    ``sin a sin b = (cos(a-b) - cos(a+b))/2``, ``cos a sin b = (sin(a+b) - sin(a-b))/2``; the constant column
    is the k = 0 cosine.  ``rust/lab/fit.rs`` assembles it by the same formulas.
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
    gram = np.asarray(0.5 * (gram + gram.T), dtype=np.float64)  # symmetric to the last bit
    xty = np.empty(m)
    xty[0] = rhs[0].real
    xty[1::2] = rhs[1:].real
    xty[2::2] = -rhs[1:].imag
    return gram, xty


def _moment_fit(theta: FloatArray, y: FloatArray, kmax: int) -> tuple[FloatArray, FloatArray, float]:
    """Same result as :func:`_qr_fit` for long records, in O(n K) instead of O(n K^2).

    In complex form the Gram matrix of ``e^{i k theta}``, k = -K..K, is Toeplitz: ``G[k, l] = mu[l - k]``
    with the moments ``mu[m] = sum_n e^{i m theta_n}``, m = 0..2K, and the right-hand side is
    ``sum_n y_n e^{-i k theta_n}``; both come from one pass of the phasor recurrence.  Over two or more
    periods the harmonics are nearly orthogonal (the Gram matrix is ``n I`` to within a few percent), so
    its condition number is close to 1 and the normal equations lose nothing; it is checked (<= 1e4, else
    the QR path is used).  The fit is returned as the R factor and ``Q^T y`` of the real basis so that the
    nested sub-fits work as for the QR path; the residual is recomputed explicitly.
    """
    n = y.size
    z = np.exp(1j * theta)
    p = np.ones(n, dtype=np.complex128)
    mom = np.empty(2 * kmax + 1, dtype=np.complex128)
    rhs = np.empty(kmax + 1, dtype=np.complex128)
    for q in range(2 * kmax + 1):
        mom[q] = p.sum()
        if q <= kmax:
            rhs[q] = np.dot(y, p.conj())
        p *= z

    gram, xty = gram_from_moments(mom, rhs, kmax)
    scale = np.sqrt(np.diag(gram))
    eig = np.linalg.eigvalsh(gram / np.outer(scale, scale))
    if eig[0] <= 0.0 or eig[-1] / eig[0] > 1e4:
        return _qr_fit(theta, y, kmax)
    r = np.linalg.cholesky(gram).T
    qty: FloatArray = solve_triangular(r, xty, trans="T")
    coef = solve_triangular(r, qty)
    # Explicit residual (no cancellation): y - X coef by the same recurrence.
    fitted = np.full(n, coef[0])
    p = z.copy()
    for k in range(1, kmax + 1):
        fitted += coef[2 * k - 1] * p.real + coef[2 * k] * p.imag
        p *= z
    resid = y - fitted
    return r, qty, float(resid @ resid)


def nested_fit(theta: FloatArray, y: FloatArray, kmax: int, omega: Optional[float] = None) -> HarmonicLS:
    """The fit on harmonics up to ``kmax`` whose sub-fits on fewer harmonics come for free.

    With ``omega``, ``theta`` holds times and the phases are ``omega theta``: the Rust path forms them
    itself (no wrapped phase array), the reference wraps them with :func:`phase_angle`.
    """
    fast = current_lab().moment_fit(theta, y, kmax, omega)
    if fast is not None:
        return HarmonicLS(*fast)
    if omega is not None:
        theta = phase_angle(omega, theta)
    n, m = y.size, 2 * kmax + 1
    fitter = _qr_fit if n * m * m <= QR_WORK_MAX else _moment_fit
    return HarmonicLS(*fitter(theta, y, kmax))

"""NumPy reference of ``rust/solve.rs``: the separable least squares (18)-(24) of the seed paper, its 3 x 3
normal equations and the golden-section search over mu.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    SearchAtBoundError,
    SingularNormalMatrixError,
    ZeroAmplitudeError,
)
from ..validation import MIN_AVERAGE_SAMPLES
from ..validation import finite_array as _finite_array
from ..validation import finite_scalar as _finite_scalar

__all__ = ["sls_inputs", "sls_regressor", "solve_normal", "sls_theta", "golden_section", "sls_search"]

FloatArray = NDArray[np.float64]


#: Conjugate golden ratio, (sqrt(5) - 1) / 2: the fraction of the bracket kept at each step.
GOLDEN_RATIO_CONJ = 0.6180339887498949
#: Smallest reciprocal condition number of the Jacobi-scaled normal matrix that we agree to solve.
RCOND_MIN = 1e-12
#: Largest |m_ij - m_ji| / sqrt(m_ii m_jj) solve_normal accepts (rust/solve.rs SYMMETRY_RTOL).
SYMMETRY_RTOL = 1e-10
#: Default iteration cap of the golden-section search (0.618**200 is far below any double tolerance).
GOLDEN_MAX_ITER = 200


def sls_inputs(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if yb.size != yd.size:
        raise InvalidParameterError(f"ybar ({yb.size}) and ydot ({yd.size}) must have the same length")
    if yb.size < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(f"ybar needs at least {MIN_AVERAGE_SAMPLES} samples per period")
    amplitude = _finite_scalar("amplitude", amplitude)
    omega = _finite_scalar("omega", omega)
    phi = _finite_scalar("phi", phi)
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the input amplitude U is 0: a zero input identifies nothing")
    if omega <= 0.0:
        raise InvalidParameterError(f"omega = {omega} rad/s must be > 0")
    p = yb.size
    dt = 2.0 * np.pi / omega / p
    t = np.arange(p) * dt
    s = amplitude * omega * np.sin(omega * t - phi)
    return yb, yd, s, dt


def sls_regressor(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float, nu: float
) -> FloatArray:
    """Regressor psi_N(nu, t) of (23), shape (P, 3)."""
    yb, yd, s, _ = sls_inputs(ybar, ydot, amplitude, omega, phi)
    ynu = np.abs(yb) ** float(nu)
    return np.column_stack([-s, s * np.sign(yd) * np.sign(yb) * ynu, s * ynu])


def solve_normal(m: ArrayLike, r: ArrayLike) -> tuple[FloatArray, float]:
    """Solve the 3x3 normal equations ``m theta = r`` with Jacobi scaling; return ``(theta, rcond)``."""
    mm = np.asarray(m, dtype=np.float64)
    rr = np.asarray(r, dtype=np.float64)
    if mm.shape != (3, 3) or rr.shape != (3,):
        raise InvalidParameterError(f"expected a (3, 3) matrix and a (3,) vector, got {mm.shape}, {rr.shape}")
    if not (np.all(np.isfinite(mm)) and np.all(np.isfinite(rr))):
        raise NonFiniteError("the normal equations hold a non-finite entry")
    diag = np.diag(mm)
    if np.any(diag <= 0.0):
        raise SingularNormalMatrixError(
            "the normal matrix has a zero regressor column (rcond = 0): the data do not excite "
            "every term of the model"
        )
    dsq = np.sqrt(diag)
    # A normal matrix is symmetric (rust/solve.rs SYMMETRY_RTOL): refuse one that is not rather than
    # read one triangle of it.
    gap = np.abs(mm - mm.T) / np.outer(dsq, dsq)
    if not np.all(gap <= SYMMETRY_RTOL):
        i, j = np.unravel_index(int(np.argmax(np.where(np.isnan(gap), np.inf, gap))), gap.shape)
        raise InvalidParameterError(
            f"the normal matrix is not symmetric: m[{i}][{j}] = {mm[i, j]:e} but m[{j}][{i}] = {mm[j, i]:e} "
            f"(relative gap {gap[i, j]:.1e} > {SYMMETRY_RTOL:g}); pass Psi^T Psi"
        )
    sm = mm / np.outer(dsq, dsq)
    eig = np.linalg.eigvalsh(sm)
    rcond = float(eig[0] / eig[-1]) if eig[-1] > 0 else 0.0
    if rcond < RCOND_MIN:
        raise SingularNormalMatrixError(
            f"the normal matrix is singular or badly conditioned (rcond = {rcond:.3g} < {RCOND_MIN:g}): "
            "the regressor columns are (nearly) collinear"
        )
    chol = np.linalg.cholesky(sm)
    z = np.linalg.solve(chol, rr / dsq)
    theta = np.linalg.solve(chol.T, z) / dsq
    return theta, rcond


def sls_theta(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float, nu: float
) -> tuple[FloatArray, float]:
    """Theta_N(nu) of (22) and the cost I_N(nu) of (21)."""
    yb, yd, s, dt = sls_inputs(ybar, ydot, amplitude, omega, phi)
    psi = sls_regressor(yb, yd, amplitude, omega, phi, nu)
    m = dt * psi.T @ psi
    r = dt * psi.T @ yd
    theta, _ = solve_normal(m, r)
    resid = yd - psi @ theta
    return theta, float(dt * np.sum(resid**2))


def golden_section(
    func: Callable[[float], float], lo: float, hi: float, tol: float, max_iter: int = GOLDEN_MAX_ITER
) -> tuple[float, float, int]:
    """Golden-section minimisation of ``func`` on ``[lo, hi]`` to a bracket width ``tol``.

    Returns ``(x, func(x), iterations)``.  Raises :class:`SearchAtBoundError` when the search never left
    one end of the bracket (the minimum is at or beyond the bound).
    """
    lo = _finite_scalar("lo", lo)
    hi = _finite_scalar("hi", hi)
    tol = _finite_scalar("tol", tol)
    if not lo < hi:
        raise InvalidParameterError(f"the bracket [{lo}, {hi}] is empty: lo must be < hi")
    if not 0.0 < tol < hi - lo:
        raise InvalidParameterError(f"tol = {tol} must be > 0 and smaller than the bracket width {hi - lo}")
    if max_iter < 1:
        raise InvalidParameterError(f"max_iter = {max_iter} must be >= 1")

    def f(x: float) -> float:
        v = float(func(x))
        if not np.isfinite(v):
            raise NonFiniteError(f"the objective returned {v} at x = {x}")
        return v

    a, b = lo, hi
    c = b - GOLDEN_RATIO_CONJ * (b - a)
    d = a + GOLDEN_RATIO_CONJ * (b - a)
    fc, fd = f(c), f(d)
    it = 0
    while b - a > tol and it < max_iter:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN_RATIO_CONJ * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN_RATIO_CONJ * (b - a)
            fd = f(d)
        it += 1
    if a == lo or b == hi:
        raise SearchAtBoundError(
            f"the minimum lies at the {'lower' if a == lo else 'upper'} end "
            f"{lo if a == lo else hi} of the bracket [{lo}, {hi}] (tol {tol:g}); widen the bracket, "
            "or check that the data excite the hysteresis",
            bound=lo if a == lo else hi,
            lower=a == lo,
        )
    x = 0.5 * (a + b)
    return x, f(x), it


def sls_search(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    phi: float,
    lo: float,
    hi: float,
    tol: float,
    max_iter: int = GOLDEN_MAX_ITER,
) -> tuple[float, FloatArray, float, int]:
    """Estimator (24a-b): golden-section search of I_N(nu) on [lo, hi], then Theta_N at the minimiser.

    Returns ``(mu, theta, cost, iterations)``.
    """
    if lo < 1.0:
        raise InvalidParameterError(f"the mu bracket starts at {lo} < 1; the model needs mu > 1")
    yb, yd, _, _ = sls_inputs(ybar, ydot, amplitude, omega, phi)
    mu, _, it = golden_section(
        lambda nu: sls_theta(yb, yd, amplitude, omega, phi, nu)[1], lo, hi, tol, max_iter
    )
    theta, cost = sls_theta(yb, yd, amplitude, omega, phi, mu)
    return mu, theta, cost, it

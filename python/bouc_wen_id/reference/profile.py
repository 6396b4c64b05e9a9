"""NumPy reference of ``rust/profile.rs``: the separable fit profiled over the phase (sgn(xdot) from the
candidate phase, Prop. 2), and the gain and phase at a further frequency.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InvalidParameterError,
    SearchAtBoundError,
    SingularNormalMatrixError,
)
from ..validation import finite_array as _finite_array
from .solve import golden_section, sls_inputs, solve_normal

__all__ = ["profile_phase_sls", "profile_phase_gain"]

FloatArray = NDArray[np.float64]


def _phase_sign_inputs(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """s_j and sgn(xdot_j) sgn(ybar_j) with sgn(xdot) = -sgn(s) from the candidate phase (Prop. 2)."""
    yb, yd, s, dt = sls_inputs(ybar, ydot, amplitude, omega, phi)
    return yb, yd, s, -np.sign(s) * np.sign(yb), dt


def _sls_cost_signed(
    yb: FloatArray, yd: FloatArray, s: FloatArray, sgn: FloatArray, dt: float, nu: float
) -> tuple[FloatArray, float]:
    ynu = np.abs(yb) ** nu
    psi = np.column_stack([-s, s * sgn * ynu, s * ynu])
    theta, _ = solve_normal(dt * psi.T @ psi, dt * psi.T @ yd)
    return theta, float(dt * np.sum((yd - psi @ theta) ** 2))


def _profile_at(
    ybar: FloatArray,
    ydot: FloatArray,
    amplitude: float,
    omega: float,
    phi: float,
    lo: float,
    hi: float,
    tol: float,
) -> Optional[tuple[float, FloatArray, float, Optional[bool]]]:
    """``(mu, theta, cost, at_bound)`` at phi; a search ending on the bracket gives the bound's cost."""
    yb, yd, s, sgn, dt = _phase_sign_inputs(ybar, ydot, amplitude, omega, phi)
    if lo < 1.0:
        raise InvalidParameterError(f"the mu bracket starts at {lo} < 1; the model needs mu > 1")
    try:
        mu, _, _ = golden_section(lambda nu: _sls_cost_signed(yb, yd, s, sgn, dt, nu)[1], lo, hi, tol)
        theta, cost = _sls_cost_signed(yb, yd, s, sgn, dt, mu)
        return mu, theta, cost, None
    except SingularNormalMatrixError:
        return None
    except SearchAtBoundError as exc:
        assert exc.bound is not None
        try:
            theta, cost = _sls_cost_signed(yb, yd, s, sgn, dt, exc.bound)
        except SingularNormalMatrixError:
            return None
        return exc.bound, theta, cost, exc.lower


#: Final bracket width (rad) of the phase refinement.
PHASE_TOL = 1e-9
#: Default number of candidate phases of the coarse grid.
DEFAULT_PHASE_GRID = 48


def profile_phase_sls(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    lo: float,
    hi: float,
    tol: float,
    grid: int,
) -> tuple[float, float, float, float, float, float, int]:
    """Profile-phase SLS: the cost (21) minimised over (phi, nu, theta), sgn(xdot) from the phase.

    Returns ``(phi, mu, gain, beta, gamma, cost, skipped)``, canonical (gain > 0).
    """
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if grid < 3:
        raise InvalidParameterError(f"the phase grid needs at least 3 points, got {grid}")
    step = np.pi / grid
    best: Optional[tuple[int, float]] = None
    skipped = 0
    for k in range(grid):
        out = _profile_at(yb, yd, amplitude, omega, k * step, lo, hi, tol)
        if out is None:
            skipped += 1
        elif best is None or out[2] < best[1]:
            best = (k, out[2])
    if best is None:
        raise SingularNormalMatrixError(
            f"no candidate phase on a {grid}-point grid gave a solvable separable fit"
        )
    centre = best[0] * step

    def profiled(phi: float) -> float:
        out = _profile_at(yb, yd, amplitude, omega, phi, lo, hi, tol)
        return np.finfo(float).max if out is None else out[2]

    try:
        phi, _, _ = golden_section(profiled, centre - step, centre + step, PHASE_TOL)
    except SearchAtBoundError:
        phi = centre
    out = _profile_at(yb, yd, amplitude, omega, phi, lo, hi, tol)
    if out is None:
        out = _profile_at(yb, yd, amplitude, omega, centre, lo, hi, tol)
        if out is None:
            raise SingularNormalMatrixError("the refined phase gave no solvable fit")
    mu, theta, cost, at_bound = out
    if at_bound is not None:
        raise SearchAtBoundError(
            f"the minimum lies at the {'lower' if at_bound else 'upper'} end {mu} of the mu bracket "
            f"[{lo}, {hi}] (tol {tol:g}); widen the bracket, or check that the data excite the hysteresis",
            bound=mu,
            lower=at_bound,
        )
    gain, beta, gamma = theta[0], theta[1] / theta[0], theta[2] / theta[0]
    if gain < 0.0:
        gain, phi, beta = -gain, phi + np.pi, -beta
    return (
        float(np.mod(phi, 2 * np.pi)),
        float(mu),
        float(gain),
        float(beta),
        float(gamma),
        float(cost),
        skipped,
    )


def profile_phase_gain(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    beta: float,
    gamma: float,
    mu: float,
    grid: int,
) -> tuple[float, float, float]:
    """Gain and phase at a further frequency with the hysteresis known; returns ``(gain, phi, cost)``."""
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if grid < 3:
        raise InvalidParameterError(f"the phase grid needs at least 3 points, got {grid}")

    def fit(phi: float) -> Optional[tuple[float, float]]:
        _, _, s, sgn, dt = _phase_sign_inputs(yb, yd, amplitude, omega, phi)
        ymu = np.abs(yb) ** mu
        chi = s * (-1.0 + beta * sgn * ymu + gamma * ymu)
        den = float(np.sum(chi * chi))
        if den <= 0.0:
            return None
        g = float(np.sum(yd * chi) / den)
        return g, float(np.sum((yd - g * chi) ** 2) * dt)

    step = 2 * np.pi / grid
    best: Optional[tuple[int, float]] = None
    for k in range(grid):
        out = fit(k * step)
        if out is not None and out[0] > 0.0 and (best is None or out[1] < best[1]):
            best = (k, out[1])
    if best is None:
        raise SingularNormalMatrixError(
            "no candidate phase gave a positive gain for the identified hysteresis"
        )
    centre = best[0] * step

    def profiled(phi: float) -> float:
        out = fit(phi)
        return np.finfo(float).max if out is None else out[1]

    try:
        phi, _, _ = golden_section(profiled, centre - step, centre + step, PHASE_TOL)
    except SearchAtBoundError:
        phi = centre
    out = fit(phi)
    if out is None:
        raise SingularNormalMatrixError("the gain regressor chi is identically zero")
    g, c = out
    if g < 0.0:
        g, phi = -g, phi + np.pi
    return g, float(np.mod(phi, 2 * np.pi)), c

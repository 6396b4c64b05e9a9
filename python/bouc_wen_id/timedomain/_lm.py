"""A bounded Levenberg-Marquardt for small parameter vectors over stacked residuals.

``fun(p) -> (r, J)`` returns the residual vector and its exact Jacobian (the models of this package
supply it by forward sensitivities).  The search minimises ``cost = 0.5 ||r||^2`` inside the box
``lower <= p <= upper``:

* **Damping** (Marquardt scaling): the step solves ``(J_F^T J_F + lam diag(J_F^T J_F)) d = -J_F^T r`` on
  the free set F, ``lam`` adapted by the gain ratio (H. B. Nielsen, *Damping parameter in Marquardt's
  method*, IMM-REP-1999-05: ``lam *= max(1/3, 1 - (2 rho - 1)^3)`` on success, ``lam *= nu, nu *= 2`` on
  failure).
* **Bounds**: the step is projected on the box; a parameter on a bound whose gradient pushes it outward
  is *active* and held there (its row is dropped from the step).  A search that ends with an active
  bound reports it by name (:attr:`LMResult.at_bound`, reason ``"converged_at_bound"``): the optimum of
  the box is on its boundary, and a standard error there means nothing.
* **Stopping**: the projected gradient (``gtol``, relative to the cost), the relative cost decrease
  (``ftol``) over an accepted step, the step length (``xtol``, relative to ``|p|``); the iteration and
  evaluation caps (``max_iter``, ``max_evaluations``); a ``should_stop()`` hook checked once an
  iteration (reason ``"cancelled"``), beside Ctrl-C, which reaches the caller as ``KeyboardInterrupt``
  from ``fun`` (the Rust simulators are interruptible, rust/cancel.rs).
* **Uncertainty**: ``covariance = sigma^2 (J_F^T J_F)^-1`` on the free set (NaN rows and columns for
  active parameters), ``sigma^2 = ||r||^2 / (m - |F|)`` unless the caller knows it (``sigma2=``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, NonFiniteError
from ..validation import count

__all__ = ["LMResult", "StopReason", "free_covariance", "levenberg_marquardt"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Residuals = Callable[[FloatArray], tuple[FloatArray, FloatArray]]

StopReason = Literal[
    "converged", "converged_at_bound", "max_iter", "max_evaluations", "cancelled", "no_progress"
]

#: Largest damping before the search gives up (the quadratic model predicts nothing any more).
MAX_DAMPING = 1e16
#: Damping of the first step, relative to diag(J^T J) (Marquardt scaling).
INITIAL_DAMPING = 1e-3
#: Floor of the Marquardt scale diag(J^T J), relative to its largest entry: a parameter the data barely
#: see still gets a damped step instead of a division by ~0.
SCALE_FLOOR = 1e-12


@dataclass(frozen=True, eq=False)
class LMResult:
    """What :func:`levenberg_marquardt` returns.

    Attributes
    ----------
    p : ndarray
        The parameters at the end (inside the box).
    cost : float
        ``0.5 ||r||^2`` there.
    residuals, jacobian : ndarray
        ``r`` and ``J`` at ``p`` (as ``fun`` returned them).
    covariance : ndarray
        ``sigma2 (J_F^T J_F)^-1`` on the free set; NaN rows/columns for the active parameters.
    sigma2 : float
        The residual variance used (``||r||^2 / (m - |F|)`` unless given).
    iterations, evaluations : int
        Accepted-or-rejected step trials, and calls of ``fun``.
    reason : StopReason
        Why the search stopped.
    at_lower, at_upper : ndarray of bool
        Parameters held on their lower or upper bound at the end.
    singular : bool
        ``J_F^T J_F`` was numerically singular (the covariance is a pseudo-inverse).
    """

    p: FloatArray
    cost: float
    residuals: FloatArray = field(repr=False)
    jacobian: FloatArray = field(repr=False)
    covariance: FloatArray = field(repr=False)
    sigma2: float
    iterations: int
    evaluations: int
    reason: StopReason
    at_lower: BoolArray = field(repr=False)
    at_upper: BoolArray = field(repr=False)
    singular: bool = False

    @property
    def converged(self) -> bool:
        """The search met a convergence test (possibly on a bound)."""
        return self.reason in ("converged", "converged_at_bound")

    @property
    def at_bound(self) -> BoolArray:
        """Parameters held on a bound."""
        return self.at_lower | self.at_upper

    @property
    def standard_errors(self) -> FloatArray:
        """Square roots of the covariance diagonal (NaN for the active parameters)."""
        return np.sqrt(np.diag(self.covariance))


def _check_box(
    p0: ArrayLike, lower: Optional[ArrayLike], upper: Optional[ArrayLike]
) -> tuple[FloatArray, ...]:
    p = np.array(p0, dtype=np.float64, copy=True).reshape(-1)
    n = p.size
    if n == 0:
        raise InvalidParameterError("the parameter vector is empty")
    if not np.all(np.isfinite(p)):
        raise NonFiniteError("the starting parameters hold a non-finite value")
    lo = np.full(n, -np.inf) if lower is None else np.array(lower, dtype=np.float64).reshape(-1)
    hi = np.full(n, np.inf) if upper is None else np.array(upper, dtype=np.float64).reshape(-1)
    if lo.size != n or hi.size != n:
        raise InvalidParameterError(f"bounds must have {n} entries, got {lo.size} and {hi.size}")
    if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or not np.all(lo < hi):
        raise InvalidParameterError("every lower bound must be below its upper bound (and not NaN)")
    return np.clip(p, lo, hi), lo, hi


def _evaluate(fun: Residuals, p: FloatArray, m: Optional[int]) -> tuple[FloatArray, FloatArray]:
    r_raw, j_raw = fun(p.copy())
    r = np.asarray(r_raw, dtype=np.float64).reshape(-1)
    jac = np.asarray(j_raw, dtype=np.float64)
    if jac.shape != (r.size, p.size) or (m is not None and r.size != m):
        raise InvalidParameterError(
            f"fun must return r of one fixed length m and J of shape (m, {p.size}); "
            f"got {r.shape}, {jac.shape}"
        )
    return r, jac


def _active(p: FloatArray, g: FloatArray, lo: FloatArray, hi: FloatArray) -> tuple[BoolArray, BoolArray]:
    """Parameters on a bound whose descent direction ``-g`` points out of the box."""
    return (p <= lo) & (g > 0.0), (p >= hi) & (g < 0.0)


def _gradient_small(gf: FloatArray, pf: FloatArray, cost: float, gtol: float) -> bool:
    """The projected gradient, scaled by the parameters' size, is small against the cost."""
    if gf.size == 0:
        return True
    scaled = float(np.max(np.abs(gf) * np.maximum(np.abs(pf), 1.0)))
    return scaled <= gtol * max(2.0 * cost, np.finfo(float).tiny)


def _projected_step(
    jac: FloatArray, g: FloatArray, free: BoolArray, lam: float, p: FloatArray, lo: FloatArray, hi: FloatArray
) -> FloatArray:
    """The damped Gauss-Newton step on the free set, projected on the box (NaN when unsolvable)."""
    jf = jac[:, free]
    a = jf.T @ jf
    d = np.diag(a).copy()
    d = np.maximum(d, SCALE_FLOOR * max(float(np.max(d)), np.finfo(float).tiny))
    step = np.zeros_like(p)
    try:
        step[free] = np.linalg.solve(a + lam * np.diag(d), -g[free])
    except np.linalg.LinAlgError:
        step[free] = np.nan
    return np.clip(p + step, lo, hi)


def free_covariance(jac: FloatArray, free: BoolArray, sigma2: float) -> tuple[FloatArray, bool]:
    n = jac.shape[1]
    cov = np.full((n, n), np.nan)
    jf = jac[:, free]
    if jf.shape[1] == 0:
        return cov, False
    # Scaled inverse: (D J^T J D)^-1 is far better conditioned than J^T J when the columns differ in size.
    norms = np.linalg.norm(jf, axis=0)
    norms[norms == 0.0] = 1.0
    js = jf / norms
    u, s, vt = np.linalg.svd(js, full_matrices=False)
    singular = bool(s[-1] <= s[0] * 1e-12 * max(jf.shape))
    keep = s > s[0] * 1e-12 * max(jf.shape)
    inv = (vt[keep].T / s[keep] ** 2) @ vt[keep]
    cov[np.ix_(free, free)] = sigma2 * inv / np.outer(norms, norms)
    return cov, singular


def levenberg_marquardt(
    fun: Residuals,
    p0: ArrayLike,
    lower: Optional[ArrayLike] = None,
    upper: Optional[ArrayLike] = None,
    *,
    max_iter: int = 100,
    max_evaluations: Optional[int] = None,
    ftol: float = 1e-10,
    xtol: float = 1e-10,
    gtol: float = 1e-10,
    sigma2: Optional[float] = None,
    should_stop: Optional[Callable[[], bool]] = None,
) -> LMResult:
    """Minimise ``0.5 ||r(p)||^2`` over ``lower <= p <= upper`` (see the module docstring).

    Parameters
    ----------
    fun : callable
        ``fun(p) -> (r, J)``: residuals (length m, fixed) and their Jacobian ``(m, len(p))``.
    p0 : array_like
        Start (clipped into the box).
    lower, upper : array_like, optional
        Box bounds (``-inf``/``inf`` entries allowed); ``lower < upper``.
    max_iter, max_evaluations : int
        Caps on step trials and on calls of ``fun`` (default ``2 max_iter + 1``).
    ftol, xtol, gtol : float
        Relative cost decrease, relative step and projected gradient tests.
    sigma2 : float, optional
        The known residual variance for the covariance (the Cramer-Rao bound at the truth).
    should_stop : callable, optional
        Checked once an iteration; True stops with reason ``"cancelled"`` (the result is the best so far).

    Raises
    ------
    InvalidParameterError, NonFiniteError
        Bad bounds, caps or shapes from ``fun``; a non-finite start, or non-finite residuals there.
    """
    p, lo, hi = _check_box(p0, lower, upper)
    max_iter = count("max_iter", max_iter, 1)
    max_eval = 2 * max_iter + 1 if max_evaluations is None else count("max_evaluations", max_evaluations, 1)
    r, jac = _evaluate(fun, p, None)
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(jac))):
        raise NonFiniteError("the residuals or their Jacobian are not finite at the start")
    m, cost, evaluations, iterations, lam, nu = r.size, 0.5 * float(r @ r), 1, 0, -1.0, 2.0
    reason: StopReason = "max_iter"
    while True:
        g = jac.T @ r
        act_lo, act_hi = _active(p, g, lo, hi)
        free = ~(act_lo | act_hi)
        gf = g[free]
        if _gradient_small(gf, p[free], cost, gtol):
            reason = "converged"
            break
        if iterations >= max_iter:
            reason = "max_iter"
            break
        if evaluations >= max_eval:
            reason = "max_evaluations"
            break
        if should_stop is not None and should_stop():
            reason = "cancelled"
            break
        lam = INITIAL_DAMPING if lam < 0.0 else lam
        iterations += 1
        trial = _projected_step(jac, g, free, lam, p, lo, hi)
        s = trial - p
        if not np.all(np.isfinite(s)):
            lam, nu = lam * nu, 2.0 * nu
            if lam > MAX_DAMPING:
                reason = "no_progress"
                break
            continue
        predicted = -(float(g @ s) + 0.5 * float(s @ (jac.T @ (jac @ s))))
        r_new, j_new = _evaluate(fun, trial, m)
        evaluations += 1
        new_cost = 0.5 * float(r_new @ r_new) if np.all(np.isfinite(r_new)) else math.inf
        ok = math.isfinite(new_cost) and bool(np.all(np.isfinite(j_new))) and new_cost < cost
        if ok and predicted > 0.0:
            rho = (cost - new_cost) / predicted
            small_step = float(np.linalg.norm(s)) <= xtol * (float(np.linalg.norm(p)) + xtol)
            small_drop = cost - new_cost <= ftol * cost
            p, r, jac, cost = trial, r_new, j_new, new_cost
            lam *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
            if small_step or small_drop:
                reason = "converged"
                break
        else:
            if float(np.linalg.norm(s)) <= xtol * (float(np.linalg.norm(p)) + xtol):
                reason = "converged"
                break
            lam, nu = lam * nu, 2.0 * nu
            if lam > MAX_DAMPING:
                reason = "no_progress"
                break
    return _finish(p, r, jac, cost, lo, hi, reason, iterations, evaluations, sigma2)


def _finish(
    p: FloatArray,
    r: FloatArray,
    jac: FloatArray,
    cost: float,
    lo: FloatArray,
    hi: FloatArray,
    reason: StopReason,
    iterations: int,
    evaluations: int,
    sigma2: Optional[float],
) -> LMResult:
    """The result at the end: the active set, the reason on a bound, and the covariance on the free set."""
    g = jac.T @ r
    act_lo, act_hi = _active(p, g, lo, hi)
    free = ~(act_lo | act_hi)
    if reason == "converged" and not bool(np.all(free)):
        reason = "converged_at_bound"
    dof = r.size - int(free.sum())
    s2 = float(sigma2) if sigma2 is not None else (2.0 * cost / dof if dof > 0 else math.nan)
    cov, singular = free_covariance(jac, free, s2)
    for arr in (p, r, jac, cov):
        arr.setflags(write=False)
    return LMResult(p, cost, r, jac, cov, s2, iterations, evaluations, reason, act_lo, act_hi, singular)

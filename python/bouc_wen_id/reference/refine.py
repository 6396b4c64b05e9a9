"""NumPy reference of ``rust/refine.rs``: the one Levenberg-Marquardt (design.md 7.4) and the joint
output-error refinement of the plain model over every experiment.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BoucWenIdError as BoucWenIdErrorBase
from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
)
from ..validation import finite_array as _finite_array
from .steady import steady_loop

__all__ = ["admissible_bouc_wen", "project_bouc_wen", "levenberg_marquardt", "refine"]

FloatArray = NDArray[np.float64]


#: Levenberg-Marquardt damping schedule (relative to the diagonal of J^T W J).
LM_LAMBDA_START, LM_LAMBDA_DOWN, LM_LAMBDA_UP, LM_LAMBDA_MAX = 1e-3, 0.2, 10.0, 1e12
#: Smallest distance kept between mu and its lower limit 1.
LM_MU_MARGIN = 1e-9


def admissible_bouc_wen(par: FloatArray, mu_lo: float, mu_hi: float) -> bool:
    """The Bouc-Wen conditions of (2a) on ``par[:3] = (beta, gamma, mu)`` and the mu bracket."""
    return bool(
        par[2] > max(mu_lo, 1.0) + LM_MU_MARGIN
        and par[2] <= mu_hi
        and par[0] + par[1] > 0
        and par[0] >= par[1]
    )


def project_bouc_wen(trial: FloatArray, mu_lo: float, mu_hi: float) -> None:
    """In place: ``beta < gamma`` onto ``beta = gamma`` (same sum), mu clipped into its bracket."""
    if trial[0] < trial[1]:
        trial[0] = trial[1] = 0.5 * (trial[0] + trial[1])
    mu_min = max(mu_lo, 1.0) + 2.0 * LM_MU_MARGIN
    if np.isfinite(trial[2]):
        trial[2] = min(max(trial[2], mu_min), max(mu_hi, mu_min))


def levenberg_marquardt(
    params: FloatArray,
    cost_of: Callable[[FloatArray], tuple[float, Any]],
    linearize: Callable[[Any], tuple[FloatArray, FloatArray]],
    project: Callable[[FloatArray], None],
    admissible: Callable[[FloatArray], bool],
    *,
    max_iter: int,
    ftol: float,
    xtol: float,
) -> tuple[FloatArray, float, int, bool, FloatArray, Any]:
    """The one Levenberg-Marquardt of the reference (design.md 7.4), for the plain and the augmented model.

    ``cost_of(par) -> (cost, state)`` (raises a library error where the model has no loop),
    ``linearize(state) -> (J'WJ, J'Wr)`` at an accepted point, ``project(trial)`` in place onto the closed
    constraints, ``admissible(trial)``. Marquardt damping ``lambda diag(J'WJ)`` from 1e-3, x0.2 on success,
    x10 on failure, stop above 1e12; stop on a relative decrease below ``ftol`` or a step below
    ``xtol (|p| + xtol)``. Returns ``(params, cost, iterations, converged, J'WJ, state)``.
    """
    cost, state = cost_of(params)
    fisher, grad = linearize(state)
    lam = LM_LAMBDA_START
    it = 0
    converged = False
    while it < max_iter:
        it += 1
        damped = fisher + lam * np.diag(np.maximum(np.diag(fisher), np.finfo(float).tiny))
        try:
            delta = np.linalg.solve(damped, grad)
        except np.linalg.LinAlgError:
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                converged = True
                break
            continue
        trial = params + delta
        small = bool(np.all(np.abs(delta) <= xtol * (np.abs(params) + xtol)))
        project(trial)
        out = None
        if admissible(trial):
            try:
                out = cost_of(trial)
            except BoucWenIdErrorBase:
                out = None
        if out is not None and out[0] <= cost:
            decrease = (cost - out[0]) / max(cost, np.finfo(float).tiny)
            params = trial
            cost, state = out
            fisher, grad = linearize(state)
            lam = max(lam * LM_LAMBDA_DOWN, 1e-15)
            if decrease < ftol or small:
                converged = True
                break
        else:
            if small:
                converged = True
                break
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                converged = True
                break
    return params, cost, it, converged, fisher, state


def refine(
    ybars: Sequence[ArrayLike],
    amplitudes: ArrayLike,
    weights: ArrayLike,
    beta: float,
    gamma: float,
    mu: float,
    gains: ArrayLike,
    phases: ArrayLike,
    max_iter: int = 200,
    substeps: int = 4,
    ftol: float = 1e-12,
    xtol: float = 1e-10,
    mu_lo: float = 1.0,
    mu_hi: float = float("inf"),
) -> tuple[FloatArray, float, int, bool, FloatArray, list[FloatArray]]:
    """Joint output-error Levenberg-Marquardt over every experiment (Schur complement on the shared part).

    Parameters are ``[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]``.  Returns
    ``(params, cost, iterations, converged, fisher, loops)``.
    """
    ys = [_finite_array(f"ybar[{i}]", y) for i, y in enumerate(ybars)]
    amps = np.asarray(amplitudes, dtype=np.float64)
    wts = np.asarray(weights, dtype=np.float64)
    m = len(ys)
    if m == 0:
        raise InsufficientDataError("the refinement needs at least one experiment")
    g0 = np.asarray(gains, dtype=np.float64)
    p0 = np.asarray(phases, dtype=np.float64)
    if not (amps.size == wts.size == g0.size == p0.size == m):
        raise InvalidParameterError(
            f"{m} experiments but {amps.size} amplitudes, {wts.size} weights, "
            f"{g0.size} gains and {p0.size} phases"
        )
    if np.any(wts <= 0) or not np.all(np.isfinite(wts)):
        raise InvalidParameterError("weights must be finite and > 0 (N / noise variance)")
    if max_iter < 1 or substeps < 1:
        raise InvalidParameterError("max_iter and substeps must be >= 1")
    params = np.concatenate([[beta, gamma, mu], np.column_stack([g0, p0]).ravel()])

    def admissible(par: FloatArray) -> bool:
        """The Bouc-Wen conditions of (2a) and the mu bracket."""
        return admissible_bouc_wen(par, mu_lo, mu_hi)

    if not admissible(params):
        raise InvalidParameterError(
            f"the starting point (beta = {beta}, gamma = {gamma}, mu = {mu}) must satisfy beta >= |gamma|, "
            f"beta + gamma > 0 and {max(mu_lo, 1.0)} < mu <= {mu_hi}"
        )

    def evaluate(par: FloatArray) -> tuple[float, list[FloatArray], list[FloatArray]]:
        cost, resid, jacs = 0.0, [], []
        for i in range(m):
            w, jac, _, _ = steady_loop(
                amps[i] * par[3 + 2 * i], par[0], par[1], par[2], par[4 + 2 * i], ys[i].size, substeps
            )
            r = ys[i] - w
            cost += wts[i] * float(np.sum(r * r))
            resid.append(r)
            jacs.append(jac)
        return cost, resid, jacs

    def blocks(resid: list[FloatArray], jacs: list[FloatArray]) -> tuple[FloatArray, FloatArray]:
        n = 3 + 2 * m
        fisher = np.zeros((n, n))
        grad = np.zeros(n)
        for i in range(m):
            full = np.zeros((ys[i].size, n))
            full[:, :3] = jacs[i][:, :3]
            full[:, 3 + 2 * i] = jacs[i][:, 3] * amps[i]
            full[:, 4 + 2 * i] = jacs[i][:, 4]
            fisher += wts[i] * full.T @ full
            grad += wts[i] * full.T @ resid[i]
        return fisher, grad

    def project(trial: FloatArray) -> None:
        # Project onto the closed constraints the step crossed: beta < gamma -> the nearest point of
        # beta = gamma (same beta + gamma), mu clipped into the bracket (beta + gamma <= 0 stays rejected).
        project_bouc_wen(trial, mu_lo, mu_hi)

    def linearize(state: tuple[list[FloatArray], list[FloatArray]]) -> tuple[FloatArray, FloatArray]:
        return blocks(*state)

    def trial_cost(par: FloatArray) -> tuple[float, tuple[list[FloatArray], list[FloatArray]]]:
        cost, resid, jacs = evaluate(par)
        return cost, (resid, jacs)

    params, cost, it, converged, fisher, (resid, _) = levenberg_marquardt(
        params, trial_cost, linearize, project, admissible, max_iter=max_iter, ftol=ftol, xtol=xtol
    )
    loops = [ys[i] - resid[i] for i in range(m)]
    return params, cost, it, converged, fisher, loops

"""NumPy reference of ``rust/refine.rs``: the one Levenberg-Marquardt (design.md 7.4) and the joint
output-error refinement of the plain model over every experiment.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Callable, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BoucWenIdError as BoucWenIdErrorBase
from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
)
from ..validation import finite_array as _finite_array
from .steady import steady_loop

__all__ = [
    "admissible_bouc_wen",
    "bouc_wen_constraints",
    "project_bouc_wen",
    "levenberg_marquardt",
    "refine",
]

FloatArray = NDArray[np.float64]


#: Levenberg-Marquardt damping schedule (relative to the diagonal of J^T W J).
LM_LAMBDA_START, LM_LAMBDA_DOWN, LM_LAMBDA_UP, LM_LAMBDA_MAX = 1e-3, 0.2, 10.0, 1e12
#: Smallest distance kept between mu and its lower limit 1.
LM_MU_MARGIN = 1e-9
#: A constraint whose slack is below this fraction of its terms' size holds the point on its face.
LM_BOUNDARY_RTOL = 1e-12

#: A closed linear constraint ``normal . par >= bound`` on which a fit may end: ``(name, normal, bound)``.
Constraint = tuple[str, FloatArray, float]


def admissible_bouc_wen(par: FloatArray, mu_lo: float, mu_hi: float) -> bool:
    """The Bouc-Wen conditions of (2a) on ``par[:3] = (beta, gamma, mu)`` and the mu bracket."""
    return bool(
        par[2] > max(mu_lo, 1.0) + LM_MU_MARGIN
        and par[2] <= mu_hi
        and par[0] + par[1] > 0
        and par[0] >= par[1]
    )


def bouc_wen_constraints(n: int, mu_lo: float, mu_hi: float) -> list[Constraint]:
    """The closed constraints of ``par[:3] = (beta, gamma, mu)`` in a vector of ``n`` parameters:
    ``beta >= gamma`` ("beta=gamma"), ``mu >= mu_lo + 2 margin`` ("mu=lower"), ``mu <= mu_hi``
    ("mu=upper", when finite)."""
    mu_min = max(mu_lo, 1.0) + 2.0 * LM_MU_MARGIN
    out: list[Constraint] = [
        ("beta=gamma", _unit(n, {0: 1.0, 1: -1.0}), 0.0),
        ("mu=lower", _unit(n, {2: 1.0}), mu_min),
    ]
    if np.isfinite(mu_hi):
        out.append(("mu=upper", _unit(n, {2: -1.0}), -max(mu_hi, mu_min)))
    return out


def _unit(n: int, entries: dict[int, float]) -> FloatArray:
    v = np.zeros(n)
    for i, c in entries.items():
        v[i] = c
    return v


def _face_step(
    damped: FloatArray, grad: FloatArray, cons: Sequence[Constraint], work: Sequence[tuple[int, float]]
) -> tuple[FloatArray, FloatArray]:
    """The step minimising ``d' grad - d' damped d / 2`` subject to ``normal_k . d = target_k`` on the working
    set, and the multipliers (>= 0: the face holds the step). Raises LinAlgError when singular."""
    n, w = grad.size, len(work)
    if w == 0:
        return np.asarray(np.linalg.solve(damped, grad), dtype=np.float64), np.zeros(0)
    kkt = np.zeros((n + w, n + w))
    kkt[:n, :n] = damped
    rhs = np.concatenate([grad, np.zeros(w)])
    for r, (k, target) in enumerate(work):
        kkt[n + r, :n] = cons[k][1]
        kkt[:n, n + r] = cons[k][1]
        rhs[n + r] = target
    sol = np.linalg.solve(kkt, rhs)
    if not np.all(np.isfinite(sol)):
        raise np.linalg.LinAlgError("non-finite face step")
    return sol[:n], -sol[n:]


def _slack_tol(con: Constraint, par: FloatArray) -> tuple[float, float]:
    _, normal, bound = con
    slack = float(normal @ par) - bound
    size = float(np.sum(np.abs(normal * par)))
    return slack, LM_BOUNDARY_RTOL * max(size + abs(bound), np.finfo(float).tiny)


def constrained_step(
    damped: FloatArray, grad: FloatArray, par: FloatArray, cons: Sequence[Constraint]
) -> tuple[FloatArray, list[int]]:
    """The active-set step of ``rust/refine.rs`` (``constrained_step``): the faces ``par`` sits on start in
    the working set; the most negative multiplier is released, the first face the step crosses is added
    with the target of landing on it, until neither happens (at most ``2 len + 2`` solves). Raises
    LinAlgError."""
    st = [_slack_tol(c, par) for c in cons]
    work = [k for k, (s, t) in enumerate(st) if s <= t]
    best: Optional[tuple[FloatArray, list[int]]] = None
    for _ in range(2 * len(cons) + 2):
        try:
            delta, nu = _face_step(damped, grad, cons, [(k, -st[k][0]) for k in work])
        except np.linalg.LinAlgError:
            if not work:
                raise
            work.pop()
            continue
        scale = max(float(np.max(np.abs(grad))) if grad.size else 0.0, np.finfo(float).tiny)
        neg = [r for r in range(len(work)) if nu[r] < -1e-12 * scale]
        if neg:
            best = (delta, list(work))
            work.pop(min(neg, key=lambda r: nu[r]))
            continue
        crossing = [
            (st[k][0] / -d if st[k][0] > 0 else 0.0, k)
            for k in range(len(cons))
            if k not in work
            for d in [float(cons[k][1] @ delta)]
            if st[k][0] + d < -st[k][1]
        ]
        if crossing:
            best = (delta, list(work))
            work.append(min(crossing)[1])
            continue
        best = (delta, work)
        break
    if best is None:
        raise np.linalg.LinAlgError("no step")
    return best


def _active_names(cons: Sequence[Constraint], work: Sequence[int], par: FloatArray) -> list[str]:
    return sorted(cons[k][0] for k in work if _slack_tol(cons[k], par)[0] <= _slack_tol(cons[k], par)[1])


def project_bouc_wen(trial: FloatArray, mu_lo: float, mu_hi: float) -> None:
    """In place: ``beta < gamma`` onto ``beta = gamma`` (same sum), mu clipped into its bracket."""
    if trial[0] < trial[1]:
        trial[0] = trial[1] = 0.5 * (trial[0] + trial[1])
    mu_min = max(mu_lo, 1.0) + 2.0 * LM_MU_MARGIN
    if np.isfinite(trial[2]):
        trial[2] = min(max(trial[2], mu_min), max(mu_hi, mu_min))


def _predicted(
    h: FloatArray, grad: FloatArray, params: FloatArray, constraints: Callable[[FloatArray], list[Constraint]]
) -> float:
    """The decrease the barely damped Gauss-Newton step ``h`` predicts, ``d . J'Wr`` (inf: no step)."""
    try:
        delta, _ = constrained_step(h, grad, params, constraints(params))
    except np.linalg.LinAlgError:
        return float("inf")
    return float(delta @ grad)


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
    constraints: Callable[[FloatArray], list[Constraint]] = lambda par: [],
    stall: tuple[int, float, float] = (0, 0.0, 0.0),
) -> tuple[FloatArray, float, int, bool, FloatArray, Any, str, list[str]]:
    """The one Levenberg-Marquardt of the reference (design.md 7.4), for the plain and the augmented model.

    ``cost_of(par) -> (cost, state)`` (raises a library error where the model has no loop),
    ``linearize(state) -> (J'WJ, J'Wr)`` at an accepted point, ``constraints(par)`` the closed linear
    constraints (the active set of :func:`constrained_step`), ``project(trial)`` in place onto the closed
    constraints, ``admissible(trial)``. Marquardt damping ``lambda diag(J'WJ)`` from 1e-3, x0.2 on success,
    x10 on failure, stop above 1e12 ("no_decrease"); stop on a relative decrease below ``ftol`` ("ftol") or a
    step below ``xtol (|p| + xtol)`` ("xtol"), or at ``max_iter`` ("max_iter"). Returns ``(params, cost,
    iterations, converged, J'WJ, state, stop, active)``, ``active`` the names of the faces that hold the end.
    ``stall = (window, rtol, step_rtol)``, window > 0: from the second window of ``window`` iterations on,
    stop at a window's end when it lowered the cost by at most ``rtol`` of it; step_rtol > 0: stop after an
    accepted step that lowered it by at most that fraction when the Gauss-Newton step (damping 1e-12) from
    its end predicts no more ("stall" both; the core's ``Options``).
    """
    cost, state = cost_of(params)
    fisher, grad = linearize(state)
    lam = LM_LAMBDA_START
    it = 0
    stop = "max_iter"
    window, window_cost = stall[0], cost

    def damped(lam: float) -> FloatArray:
        return fisher + lam * np.diag(np.maximum(np.diag(fisher), np.finfo(float).tiny))

    while it < max_iter:
        if window > 0 and it > 0 and it % window == 0:
            if it > window and window_cost - cost <= stall[1] * cost:
                stop = "stall"
                break
            window_cost = cost
        it += 1
        cons = constraints(params)
        try:
            delta, _ = constrained_step(damped(lam), grad, params, cons)
        except np.linalg.LinAlgError:
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                stop = "no_decrease"
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
            lowered = cost - out[0]
            params = trial
            cost, state = out
            fisher, grad = linearize(state)
            lam = max(lam * LM_LAMBDA_DOWN, 1e-15)
            if decrease < ftol or small:
                stop = "xtol" if small else "ftol"
                break
            if (
                lowered <= stall[2] * cost
                and _predicted(damped(1e-12), grad, params, constraints) <= stall[2] * cost
            ):
                stop = "stall"
                break
        else:
            if small:
                stop = "xtol"
                break
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                stop = "no_decrease"
                break
    cons = constraints(params)
    active: list[str] = []
    for lam_end in (min(lam, LM_LAMBDA_MAX), LM_LAMBDA_START):
        try:
            active = _active_names(cons, constrained_step(damped(lam_end), grad, params, cons)[1], params)
            break
        except np.linalg.LinAlgError:
            continue
    return params, cost, it, stop != "max_iter", fisher, state, stop, active


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
) -> tuple[FloatArray, float, int, bool, FloatArray, list[FloatArray], str, list[str]]:
    """Joint output-error Levenberg-Marquardt over every experiment (Schur complement on the shared part).

    Parameters are ``[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]``.  Returns
    ``(params, cost, iterations, converged, fisher, loops, stop, active)``.
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

    params, cost, it, converged, fisher, (resid, _), stop, active = levenberg_marquardt(
        params,
        trial_cost,
        linearize,
        project,
        admissible,
        max_iter=max_iter,
        ftol=ftol,
        xtol=xtol,
        constraints=lambda par: bouc_wen_constraints(par.size, mu_lo, mu_hi),
    )
    loops = [ys[i] - resid[i] for i in range(m)]
    return params, cost, it, converged, fisher, loops, stop, active

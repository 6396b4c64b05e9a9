"""Strength degradation's value from the joint fit of the averaged periods and d (session 47).

The correction passes (drift_passes.py) bring the averaged periods back to the virgin strength with the fit
of the pass before and refit the steady model to them: their fixed point solves ``J0' W r = 0``, with ``J0``
the steady model's Jacobian and ``r = ybar - steady(theta) - shift(theta, d)`` (``shift``, the simulated
degradation of the averaged loop, :func:`.drift.corrected`). The optimum of the averaged periods is
``(J0 + dshift/dtheta)' W r = 0``. At 30x the two part: the loop of the largest amplitude degrades most, its
shift moves with its own gain, and the passes leave that gain 4 % low (tests/degradation_sim.py at
``delta_nu = 0.005``, seed 1: steady chi2 1150 on 555 dof, "explained in part", 623 of it on one
experiment); the joint fit of the same periods reaches chi2 473 with every gain within 0.5 % of the others
(studies/nu47/README.md).

:func:`joint` runs that fit: Levenberg-Marquardt on ``(beta, gamma, mu, term values, gains, phases, d)``,
the steady model's Jacobian analytic, the shift's by forward differences (the shared parameters one at a
time, the gains all at once and the phases all at once: each experiment's shift moves only with its own),
from the passes' fit. Its cost is the averaged periods' chi-square plus the drift space's
``C_drift(d) = C0 - 2 d num + d^2 den`` (the cost :func:`.drift_passes.refine` added too).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit, AugParams, augmented_output
from ..errors import BoucWenIdError, BudgetExceededError
from .data import DiagExperiment
from .drift import DegradationTest, _sums, corrected

#: Levenberg-Marquardt iterations at most, and the decrease of the cost (chi-square) that ends them.
MAX_ITER = 12
COST_ATOL = 1.0
#: Forward-difference step of the shift's derivatives, relative to each parameter (absolute for phases).
STEP = 1e-3


def _params(par: AugParams, x: np.ndarray, t: int, m: int) -> AugParams:
    return replace(
        par,
        beta=float(x[0]),
        gamma=float(x[1]),
        mu=float(x[2]),
        values=np.array(x[3 : 3 + t]),
        gains=np.array(x[3 + t : 3 + t + m]),
        phases=np.array(x[3 + t + m : 3 + t + 2 * m]),
    )


Evaluate = Callable[[np.ndarray, bool], tuple[np.ndarray, Optional[np.ndarray]]]


def _levenberg(
    evaluate: Evaluate, x: np.ndarray, r: np.ndarray, j: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Levenberg-Marquardt (Marquardt's diagonal scaling) from ``x`` with its residuals ``r`` and Jacobian
    ``j``, until a step lowers the cost by at most :data:`COST_ATOL` or :data:`MAX_ITER` steps; the point
    reached with its residuals and Jacobian."""
    cost, lam = float(r @ r), 1e-3
    for _ in range(MAX_ITER):
        jtj, g = j.T @ j, j.T @ r
        diag = np.diag(jtj).copy()
        while lam < 1e8:
            try:
                step = -np.linalg.solve(jtj + lam * np.diag(np.maximum(diag, 1e-30)), g)
                trial = x + step
                rt, _ = evaluate(trial, False)
            except BudgetExceededError:
                raise
            except (BoucWenIdError, ValueError, FloatingPointError, np.linalg.LinAlgError):
                lam *= 10.0
                continue
            ct = float(rt @ rt)
            if math.isfinite(ct) and ct < cost:
                break
            lam *= 10.0
        else:
            break
        done = cost - ct <= COST_ATOL
        x, cost, lam = trial, ct, max(lam / 10.0, 1e-9)
        r, jn = evaluate(x, True)
        assert jn is not None
        j = jn
        if done:
            break
    return x, r, j


def joint(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    data: Sequence[Any],
    deg: DegradationTest,
    y_scale: float,
    substeps: int,
) -> Optional[tuple[DegradationTest, AugFit]]:
    """d and the virgin fit from the joint fit (the module's docstring); the standard error of d from the
    Gauss-Newton covariance at the optimum. None when it cannot be formed (a simulation or a step the model
    does not admit at the start)."""
    sums = [_sums(dd, deg.term) for dd in data]
    num, den = sum(c[1] for c in sums), sum(c[2] for c in sums)
    if den <= 0:
        return None
    root = math.sqrt(den)
    par0 = fit.params
    m, t = len(sx), len(par0.terms)
    w = [math.sqrt(a.weight) for a in sx]
    sizes = [a.ybar.size for a in sx]

    def shifts(x: np.ndarray, d: float) -> list[np.ndarray]:
        _, cs = corrected(
            exps, sx, replace(fit, params=_params(par0, x, t, m)), d, y_scale, substeps, deg.term
        )
        return [a.ybar - c.ybar for a, c in zip(sx, cs)]

    frozen: list[np.ndarray] = []

    def evaluate(x: np.ndarray, jac: bool) -> tuple[np.ndarray, Optional[np.ndarray]]:
        par = _params(par0, x, t, m)
        d = float(x[-1])
        sh = shifts(x, d)
        outs = (
            [augmented_output(a, par, i, substeps=substeps, jacobian=True) for i, a in enumerate(sx)]
            if jac
            else []
        )
        ys = (
            [o.y for o in outs]
            if jac
            else [augmented_output(a, par, i, substeps=substeps) for i, a in enumerate(sx)]
        )
        r = np.concatenate([wi * (a.ybar - y - s) for wi, a, y, s in zip(w, sx, ys, sh)])
        r = np.append(r, root * (d - num / den))
        if not jac:
            return r, None
        j = np.zeros((r.size, x.size))
        row = 0
        for i, (o, n) in enumerate(zip(outs, sizes)):
            j[row : row + n, : 3 + t] = -w[i] * o.jacobian
            j[row : row + n, 3 + t + i] = -w[i] * o.own_jacobian[:, 0]
            j[row : row + n, 3 + t + m + i] = -w[i] * o.own_jacobian[:, 1]
            row += n
        j[-1, -1] = root
        if frozen:
            return r, j + frozen[0]
        ds = np.zeros_like(j)
        groups = [[k] for k in range(3 + t)]
        groups += [list(range(3 + t, 3 + t + m)), list(range(3 + t + m, 3 + t + 2 * m)), [x.size - 1]]
        for g in groups:
            h = np.zeros(x.size)
            for k in g:
                h[k] = STEP if 3 + t + m <= k < 3 + t + 2 * m else STEP * max(abs(float(x[k])), 1e-12)
            moved = shifts(x + h, float(x[-1] + h[-1]))
            row = 0
            for i, (n, s0, s1) in enumerate(zip(sizes, sh, moved)):
                k = g[i] if len(g) == m else g[0]
                ds[row : row + n, k] = -w[i] * (s1 - s0) / h[k]
                row += n
        frozen.append(ds)
        return r, j + ds

    x = np.concatenate([[par0.beta, par0.gamma, par0.mu], par0.values, par0.gains, par0.phases, [deg.d]])
    try:
        r, j = evaluate(x, True)
        assert j is not None
        x, r, j = _levenberg(evaluate, x, r, j)
    except BudgetExceededError:
        raise
    except (BoucWenIdError, ValueError, FloatingPointError):
        return None
    try:
        cov = np.linalg.inv(j.T @ j)
    except np.linalg.LinAlgError:
        return None
    d, var = float(x[-1]), float(cov[-1, -1])
    if not (d > 0 and var > 0):
        return None
    se = math.sqrt(var)
    out = replace(deg, d=d, value=d / y_scale**2, standard_error=se / y_scale**2)
    return out, replace(fit, params=_params(par0, x, t, m))


__all__ = ["joint"]

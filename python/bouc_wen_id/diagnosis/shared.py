"""Is a term's value across conditions ONE value? The nested fit of :func:`.across.diagnose_across`'s terms.

A term named across conditions has its value free per condition. The nested model holds ONE physical value
of the term at every condition, every other parameter still free per condition (each condition's beta,
gamma, mu, other terms, |G| and phase per experiment), and is refitted jointly: a Levenberg-Marquardt over
the shared value and every condition's own parameters together (the core fits one condition at a time and
cannot hold a parameter, so the joint steps are formed here from the core's model outputs and Jacobians,
:func:`~bouc_wen_id.augmented.augmented_output`). The F test of the nested fit, as the forward selection's:

    F = ((C_shared - C_free) / (K - 1)) / max(C_free / dof_free, 1)   against   F(K - 1, dof_free)

with ``C_free = sum_k C_k`` the per-condition fits' summed cost, ``dof_free`` their summed dof and the
denominator never below the noise floor (:func:`.select.f_test`). A p at or above ``alpha``: the conditions
share the value (reported with its standard error from the joint fit, inflated by ``sqrt(chi2/dof)`` when
above 1); below: the value varies with the condition. Unlike the smoothness polynomials' chi-square on the
values and their se (a linearisation at each condition's own fit), the shared value is refitted, so the
other parameters take up what they can of a common value (docs/diagnosis.md, "Across conditions").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit, AugParams, augmented_output
from ..errors import BoucWenIdError, BudgetExceededError
from ..terms import TERMS
from . import free_dc
from .fitting import Scale

#: LM iterations of the joint fit at most.
MAX_ITER = 60
#: Stop when an accepted step lowers the joint cost by less than this many units of the F test's
#: denominator (the pooled residual variance): far below what moves the test.
COST_TOL = 1e-3


@dataclass(frozen=True)
class SharedTest:
    """The nested fit with one value of ``term`` at every condition, and its F test against free values."""

    term: str
    #: The shared physical value and its standard error (inflated by sqrt(chi2/dof) when above 1).
    value: float
    standard_error: float
    cost_free: float
    cost_shared: float
    dof_free: int
    statistic: float
    p_value: float
    #: p >= alpha: one value fits as well as one per condition.
    shared: bool
    #: LM iterations of the kept joint fit.
    iterations: int
    #: Whether that fit stopped at a stationary point (a step gaining less than the tolerance, or no step
    #: lowering the cost); False: it reached :data:`MAX_ITER`, so its cost only bounds the best shared fit's
    #: from above and a refusal is not determined.
    converged: bool = True

    def to_dict(self) -> dict[str, Any]:
        def n(v: float) -> Optional[float]:
            return v if math.isfinite(v) else None

        return {
            "term": self.term,
            "value": n(self.value),
            "standard_error": n(self.standard_error),
            "cost_free": n(self.cost_free),
            "cost_shared": n(self.cost_shared),
            "dof_free": self.dof_free,
            "F": n(self.statistic),
            "p_value": n(self.p_value),
            "shared": self.shared,
            "iterations": self.iterations,
            "converged": self.converged,
        }


@dataclass(frozen=True)
class _Cond:
    """One condition's data for the joint fit."""

    sx: Sequence[AugExperiment]
    scale: Scale
    substeps: int
    fit: AugFit
    dof: int


def _factor(term: str, s: Scale, mu: float) -> tuple[float, float]:
    """Physical value per scaled unit at ``mu``, and d ln(factor) / d mu."""
    return s.factor(term, mu), TERMS[term].scaling[2] * math.log(s.y)


def _unpack(term: str, conds: Sequence[_Cond], x: np.ndarray) -> list[AugParams]:
    """The parameters of every condition from the joint vector ``[v, theta_1, ..., theta_K]``."""
    out, at = [], 1
    v = float(x[0])
    for c in conds:
        par = c.fit.params
        i = par.terms.index(term)
        nt, m = len(par.terms), par.gains.size
        own = x[at : at + 3 + nt - 1 + 2 * m]
        at += own.size
        beta, gamma, mu = (float(t) for t in own[:3])
        others = own[3 : 3 + nt - 1]
        values = np.insert(others, i, v / _factor(term, c.scale, mu)[0])
        gp = own[3 + nt - 1 :]
        out.append(
            AugParams(beta, gamma, mu, par.terms, values, gp[0::2].copy(), gp[1::2].copy(), par.smoothing)
        )
    return out


def _pack(term: str, conds: Sequence[_Cond], v: float) -> np.ndarray:
    parts: list[np.ndarray] = [np.array([v])]
    for c in conds:
        par = c.fit.params
        i = par.terms.index(term)
        gp = np.empty(2 * par.gains.size)
        gp[0::2], gp[1::2] = par.gains, par.phases
        parts.append(np.concatenate([[par.beta, par.gamma, par.mu], np.delete(par.values, i), gp]))
    return np.concatenate(parts)


def _evaluate(
    term: str, conds: Sequence[_Cond], x: np.ndarray, jacobian: bool
) -> Optional[tuple[float, np.ndarray, np.ndarray]]:
    """Joint cost, ``J^T W r`` and ``J^T W J`` at ``x`` (None: an inadmissible model somewhere)."""
    n = x.size
    grad, hess = np.zeros(n), np.zeros((n, n))
    cost = 0.0
    at = 1
    with np.errstate(over="ignore", invalid="ignore"):  # a degenerate loop: refused below
        try:
            pars = _unpack(term, conds, x)
            for c, par in zip(conds, pars):
                i = par.terms.index(term)
                nt, m = len(par.terms), par.gains.size
                k = 3 + nt - 1 + 2 * m
                f, dlnf = _factor(term, c.scale, par.mu)
                rs, jacs = [], []
                for j, e in enumerate(c.sx):
                    if not jacobian:
                        rs.append(e.ybar - augmented_output(e, par, j, substeps=c.substeps))
                        continue
                    o = augmented_output(e, par, j, substeps=c.substeps, jacobian=True)
                    rs.append(e.ybar - o.y)
                    jq = o.jacobian[:, 3 + i]
                    jac = np.zeros((e.ybar.size, 1 + k))
                    jac[:, 0] = jq / f  # d y / d v through q~ = v / f(mu)
                    jac[:, 1:4] = o.jacobian[:, :3]
                    jac[:, 3] -= jq * float(par.values[i]) * dlnf  # q~ moves with mu at fixed v
                    jac[:, 4 : 4 + nt - 1] = np.delete(o.jacobian[:, 3:], i, axis=1)
                    jac[:, 4 + nt - 1 + 2 * j : 6 + nt - 1 + 2 * j] = o.own_jacobian
                    jacs.append(jac)
                # A wandering baseline's marked experiments: the projected residuals the condition's own
                # fit minimised (free_dc.py), so C_shared and C_free are costs of one problem.
                prs, pjs = free_dc.project(c.sx, rs, jacs if jacobian else None)
                cols = np.concatenate([[0], np.arange(at, at + k)])
                for j, (e, r) in enumerate(zip(c.sx, prs)):
                    cost += e.weight * float(np.sum(r**2))
                    if pjs is not None:
                        grad[cols] += e.weight * (pjs[j].T @ r)
                        hess[np.ix_(cols, cols)] += e.weight * (pjs[j].T @ pjs[j])
                at += k
        except BudgetExceededError:  # a limit the user set: never an inadmissible step
            raise
        except BoucWenIdError:
            return None
    if not (math.isfinite(cost) and np.all(np.isfinite(grad)) and np.all(np.isfinite(hess))):
        return None  # a degenerate loop (derivatives overflowing): no step goes there
    return cost, grad, hess


#: mu's lower end in the core's fits (rust/refine.rs: ``mu_lo + 2 MU_MARGIN`` with ``mu_lo = 1``).
MU_MIN = 1.0 + 2e-9


def _blocks(conds: Sequence[_Cond]) -> list[int]:
    """Where each condition's own parameters start in the joint vector."""
    out, at = [], 1
    for c in conds:
        out.append(at)
        at += 3 + len(c.fit.params.terms) - 1 + 2 * c.fit.params.gains.size
    return out


def _project(conds: Sequence[_Cond], x: np.ndarray) -> np.ndarray:
    """The core's projection of the Bouc-Wen conditions (rust/refine.rs ``project_hysteresis``): beta < gamma
    onto beta = gamma at the same sum, mu into its bracket; a step may slide along them."""
    y: np.ndarray = np.array(x, dtype=np.float64)
    for at in _blocks(conds):
        if y[at] < y[at + 1]:
            y[at] = y[at + 1] = 0.5 * (y[at] + y[at + 1])
        y[at + 2] = max(y[at + 2], MU_MIN)
    return y


def _faces(conds: Sequence[_Cond], x: np.ndarray) -> np.ndarray:
    """The steps' basis: every parameter free, but a condition ON beta = gamma moves beta and gamma together
    and one at mu's lower end holds mu (the faces its own fit sits on: a step off them is projected back)."""
    cols = []
    n = x.size
    starts = _blocks(conds)
    on_bg = {at for at in starts if x[at] - x[at + 1] <= 1e-12 * max(abs(x[at]), 1.0)}
    on_mu = {at + 2 for at in starts if x[at + 2] <= MU_MIN * (1.0 + 1e-12)}
    for j in range(n):
        if j in on_mu or (j - 1) in on_bg:
            continue  # held mu, or gamma (moved with beta)
        col = np.zeros(n)
        col[j] = 1.0
        if j in on_bg:
            col[j + 1] = 1.0
        cols.append(col)
    out: np.ndarray = np.array(cols).T
    return out


def _joint_fit(
    term: str, conds: Sequence[_Cond], v0: float, tol: float
) -> Optional[tuple[np.ndarray, float, np.ndarray, int, bool]]:
    """Levenberg-Marquardt of the joint vector from the shared value ``v0``, on the faces the conditions' fits
    sit on (:func:`_faces`), trial points projected (:func:`_project`); stops once an accepted step gains less
    than ``tol``: (x, cost, the shared value's J^T W J block's inverse variance, iterations, whether it
    stopped before :data:`MAX_ITER`); None when ``v0`` is inadmissible somewhere."""
    x = _pack(term, conds, v0)
    ev = _evaluate(term, conds, x, True)
    if ev is None:
        return None
    cost, grad, hess = ev
    lam, it, stopped = 1e-3, 0, False
    while it < MAX_ITER:
        it += 1
        t = _faces(conds, x)
        h, g = t.T @ hess @ t, t.T @ grad
        d = np.diag(h).copy()
        d[d <= 0] = 1.0
        try:
            step = t @ np.linalg.solve(h + lam * np.diag(d), g)
        except np.linalg.LinAlgError:
            lam *= 10.0
            continue
        trial = _project(conds, x + step)
        new = _evaluate(term, conds, trial, False)
        if new is None or new[0] >= cost:
            lam *= 10.0
            if lam > 1e10:
                stopped = True  # no step lowers the cost: a stationary point
                break
            continue
        gain = cost - new[0]
        ev = _evaluate(term, conds, trial, True)
        if ev is None:  # a lower cost in a degenerate loop: refused as an inadmissible step
            lam *= 10.0
            if lam > 1e10:
                break
            continue
        x, (cost, grad, hess) = trial, ev
        lam = max(lam / 10.0, 1e-9)
        if gain < tol:
            stopped = True
            break
    t = _faces(conds, x)
    return x, cost, t.T @ hess @ t, it, stopped


def _own(term: str, c: _Cond) -> float:
    """A condition's own physical value of ``term``."""
    from .fitting import physical

    return physical(c.fit, c.scale, term)[0]


def _start(term: str, conds: Sequence[_Cond]) -> float:
    """The inverse-variance mean of the per-condition physical values (their plain mean without se)."""
    from .fitting import physical

    vs, ws = [], []
    for c in conds:
        v, se = physical(c.fit, c.scale, term)
        vs.append(v)
        ws.append(1.0 / se**2 if math.isfinite(se) and se > 0 else math.nan)
    if all(math.isfinite(w) for w in ws):
        return float(np.average(vs, weights=ws))
    return float(np.mean(vs))


def shared_test(
    term: str,
    sx: Sequence[Sequence[AugExperiment]],
    scales: Sequence[Scale],
    substeps: Sequence[int],
    fits: Sequence[AugFit],
    dofs: Sequence[int],
    alpha: float,
) -> Optional[SharedTest]:
    """The F test of one shared value of ``term`` against one per condition (module docstring).

    ``sx``, ``scales``, ``substeps``: each condition's scaled experiments, scale and RK4 steps; ``fits``: its
    final fit (``term`` among its terms); ``dofs``: that fit's dof. None when fewer than two conditions or the
    joint fit has no admissible start.
    """
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    k = len(fits)
    if k < 2 or any(term not in f.params.terms for f in fits):
        return None
    conds = [_Cond(a, s, n, f, d) for a, s, n, f, d in zip(sx, scales, substeps, fits, dofs)]
    c_free = float(sum(f.cost for f in fits))
    dof_free = int(sum(dofs))
    dof_shared = max(dof_free + k - 1, 1)
    den = max(c_free / max(dof_free, 1), 1.0)
    # The joint fit is a local search (a shared value far from some condition's own pulls that condition's
    # other parameters a long way): the better of two starts, the values' inverse-variance mean and median.
    starts = dict.fromkeys([_start(term, conds), float(np.median([_own(term, c) for c in conds]))])
    fits_ = [f for f in (_joint_fit(term, conds, v0, COST_TOL * den) for v0 in starts) if f is not None]
    if not fits_:
        return None
    x, cost, hess, it, converged = min(fits_, key=lambda f: f[1])
    stat = max(cost - c_free, 0.0) / (k - 1) / den
    p = float(fdtrc(k - 1, max(dof_free, 1), stat)) if stat > 0 else 1.0
    try:
        var = float(np.linalg.inv(hess)[0, 0])
    except np.linalg.LinAlgError:
        var = math.nan
    inflate = math.sqrt(max(1.0, cost / dof_shared))
    se = math.sqrt(var) * inflate if var >= 0 else math.nan
    return SharedTest(
        term, float(x[0]), se, c_free, float(cost), dof_free, stat, p, p >= alpha, it, converged
    )

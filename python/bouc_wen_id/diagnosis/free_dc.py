"""A free DC per experiment whose period means were taken out as a wandering baseline (issue 18).

``baseline.removed`` sets each period's mean of a wandering recording to one common centre, so the averaged
period's DC of such an experiment is set, not measured. A term with a DC part of its own (an asymmetry's
DC differs from experiment to experiment) was still fitted against that set DC, and the fit left
"unexplained" structure (the designs bench's ``walk`` rows, asymmetry at 10x: seeds 520000-520002). Here
each marked experiment (a :class:`FreeDC`) has its DC free: zero weight on its residual's mean, the mean
projected out of the residual and of the Jacobian (the law test), its degree of freedom spent. When the
set's common centre was kept (it stands out of the spread of the recordings' centres: an output offset),
only the experiments' DCs about their common one are free (``common``): the common DC is still fitted,
so an offset can still be named.

The core's fit has no free DC, so :func:`fit` profiles it: the core fits data whose DC is the model's own
(plus the common residual DC when ``common``), the DCs are updated from the fit, and so on until they move
by less than :data:`DC_TOL` of the averaged DC's noise sd. At that fixed point the core's normal equations
are those of the projected problem (``J^T W (P r) = 0``), so the estimates are its exact solution; the
cost, the outputs (with the data's DC: a residual formed from them is the projected one) and the Fisher
matrix (``J^T W J`` less each experiment's DC direction) are then those of the projected problem. Residuals
and Jacobians formed elsewhere go through :func:`project` (the across test's shared fit, the detection limits)
or :func:`centred` (the law and shape tests, the held-out refit, the separating-design search); the feedback
structure's held-out check marks the experiments (:func:`marked`, from ``Diagnosis.settings["common_dc"]``),
fits the feedback's folds on data projected by :func:`project` and centres its left-out residual
(:func:`centred`). The feedback's own full fit is not projected (docs/diagnosis.md). A fit whose DCs do not
settle is flagged
(:data:`NOT_CONVERGED`).
Experiments that are not marked are untouched (a set without a wander is fitted as before, bit for bit).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit, AugParams, _covariance, augmented_output
from ..errors import BoucWenIdError, BudgetExceededError

FloatArray = NDArray[np.float64]

#: The fixed point's tolerance: the largest change of an experiment's DC, in averaged-noise sd
#: (``sqrt(weight P)`` units: a change of the cost of at most DC_TOL^2 per experiment).
DC_TOL = 1e-3
#: Most passes of the core's fit (the DCs converge geometrically; a pass starts from the last estimates, so
#: a pass near the fixed point is short).
MAX_PASSES = 20
#: The stop reason of a fit whose DCs did not reach the fixed point (:data:`DC_TOL`) within
#: :data:`MAX_PASSES` or whose backtracking stalled: its estimates are not the projected problem's solution.
NOT_CONVERGED = "dc_not_converged"


@dataclass(frozen=True)
class FreeDC(AugExperiment):
    """An experiment whose averaged period's DC is free in the fit (its period means were taken out)."""

    #: The experiments' DCs are free about one common DC, which is fitted (the common centre was kept).
    common: bool = False


def marked(sx: Sequence[AugExperiment], removed: Sequence[bool], common: bool) -> list[AugExperiment]:
    """``sx`` with each experiment whose period means were taken out (``removed``) a :class:`FreeDC`."""
    out: list[AugExperiment] = []
    for e, r in zip(sx, removed):
        if r and not isinstance(e, FreeDC):
            fields = {k: getattr(e, k) for k in AugExperiment.__dataclass_fields__}
            e = FreeDC(**fields, common=common)
        out.append(e)
    return out


def _free(exps: Sequence[AugExperiment]) -> list[int]:
    return [i for i, e in enumerate(exps) if isinstance(e, FreeDC)]


def _common(exps: Sequence[AugExperiment], free: Sequence[int]) -> bool:
    return any(getattr(exps[i], "common", False) for i in free)


def spent(exps: Sequence[AugExperiment]) -> int:
    """Degrees of freedom spent on the free DCs: one per marked experiment, one fewer when ``common``."""
    free = _free(exps)
    return len(free) - (1 if free and _common(exps, free) else 0)


def count(exps: Sequence[AugExperiment], held_out: bool = False) -> int:
    """How many of ``exps`` :func:`centred` centres."""
    return sum(isinstance(e, FreeDC) and not (held_out and e.common) for e in exps)


def centred(e: AugExperiment, a: FloatArray, held_out: bool = False) -> FloatArray:
    """``a`` (a residual or a Jacobian of ``e``, samples along axis 0) less its mean when ``e``'s DC is
    free (the law test: each experiment's own DC free, so a term's law is judged on the rest of the loop);
    ``a`` itself otherwise, and for the held-out refit (``held_out``) when ``common``: the held-out
    experiment's DC is then judged against the model's, as without a wander (the kept common centre is the
    output offset's evidence, which a held-out DC left free would not see)."""
    if not isinstance(e, FreeDC) or (held_out and e.common):
        return a
    return np.asarray(a - np.mean(a, axis=0), dtype=np.float64)


def project(
    exps: Sequence[AugExperiment],
    residuals: Sequence[FloatArray],
    jacobians: Optional[Sequence[FloatArray]] = None,
) -> tuple[list[FloatArray], Optional[list[FloatArray]]]:
    """The residuals (and Jacobians, samples along axis 0, one column layout for all of ``exps``) of the
    projected problem :func:`fit` solves: each marked experiment's less its mean, plus, when ``common``, the
    ``a``-weighted mean over the marked experiments (``a = weight * N``) added back, as :func:`_projected`
    forms the outputs and the Fisher matrix. Experiments that are not marked are returned as given."""
    free = _free(exps)
    rs = [np.asarray(r, dtype=np.float64) for r in residuals]
    js = None if jacobians is None else [np.asarray(j, dtype=np.float64) for j in jacobians]
    if not free:
        return rs, js
    a = np.array([exps[i].weight * exps[i].ybar.size for i in free])
    keep = _common(exps, free)
    parts: list[list[FloatArray]] = [rs] if js is None else [rs, js]
    for arrs in parts:
        means = [np.mean(arrs[i], axis=0) for i in free]
        back = sum(w * m for w, m in zip(a, means)) / a.sum() if keep else 0.0
        for i, m in zip(free, means):
            arrs[i] = arrs[i] - m + back
    return rs, js


def _residual_dcs(
    exps: Sequence[AugExperiment], outs: Sequence[FloatArray], free: Sequence[int]
) -> FloatArray:
    """Each free experiment's residual DC after the free DCs (the common one when ``common``, else 0)."""
    if not _common(exps, free):
        return np.zeros(len(free))
    a = np.array([exps[i].weight * exps[i].ybar.size for i in free])
    r = np.array([float(np.mean(exps[i].ybar) - np.mean(outs[i])) for i in free])
    return np.full(len(free), float(a @ r / a.sum()))


def fit(
    exps: Sequence[AugExperiment],
    start: AugParams,
    substeps: int,
    max_iter: int,
    inner: Callable[[Sequence[AugExperiment], AugParams, int, int], Optional[AugFit]],
) -> Optional[AugFit]:
    """``inner(exps, start, substeps, max_iter)`` (the core's fit) with each :class:`FreeDC`'s DC free
    (the module docstring); ``inner`` itself when no experiment is marked."""
    free = _free(exps)
    if not free:
        return inner(exps, start, substeps, max_iter)
    a = np.array([exps[i].weight * exps[i].ybar.size for i in free])
    c = _start_dcs(exps, start, free, substeps)
    best: Optional[AugFit] = None
    best_cost, base, step = math.inf, c, np.zeros(len(free))
    met = False  # whether the fixed point's criterion was met (else the last accepted fit, flagged)
    for _ in range(MAX_PASSES):
        work = _with_dcs(exps, free, c)
        new = inner(work, start if best is None else best.params, substeps, max_iter)
        ok = new is not None and len(new.outputs) == len(exps)
        cost = _cost(exps, new.outputs, free) if new is not None and ok else math.inf
        if new is None or not (cost <= best_cost * (1.0 + 1e-12)):
            step = 0.5 * step  # the step went too far: back towards the last accepted DCs
            if best is None or float(np.max(np.abs(step) * np.sqrt(a))) <= DC_TOL:
                break
            c = base + step
            continue
        best, best_cost, base = new, cost, c
        g = (
            np.array([float(np.mean(new.outputs[i])) for i in free])
            + _residual_dcs(exps, new.outputs, free)
            - c
        )
        if float(np.max(np.abs(g) * np.sqrt(a))) <= DC_TOL:
            met = True
            break
        step = _newton(work, new, free, substeps, a, g)
        c = c + step
    if best is None:
        return None
    out = _projected(exps, best, substeps, free)
    return out if met else replace(out, converged=False, stop=NOT_CONVERGED)


def note(f: AugFit, what: str) -> Optional[str]:
    """The diagnosis's note when ``f``'s free DCs did not reach their fixed point (:data:`NOT_CONVERGED`)."""
    if f.stop != NOT_CONVERGED:
        return None
    return (
        f"{what} did not converge: the free DCs of the wandering baseline's experiments did not settle "
        f"(within {DC_TOL:g} of the averaged noise sd in {MAX_PASSES} passes), so its estimates and cost are "
        "those of the last pass, not the solution"
    )


def _with_dcs(exps: Sequence[AugExperiment], free: Sequence[int], c: FloatArray) -> list[AugExperiment]:
    """``exps`` with each free experiment's DC set to ``c``."""
    out = list(exps)
    for k, i in enumerate(free):
        e = exps[i]
        out[i] = replace(e, ybar=e.ybar - float(np.mean(e.ybar)) + float(c[k]))
    return out


def _cost(exps: Sequence[AugExperiment], outs: Sequence[FloatArray], free: Sequence[int]) -> float:
    """The projected problem's cost of the outputs ``outs`` on the data ``exps`` (:func:`_matched`)."""
    return float(
        sum(e.weight * float(np.sum((e.ybar - y) ** 2)) for e, y in zip(exps, _matched(exps, outs, free)))
    )


def _matched(
    exps: Sequence[AugExperiment], outs: Sequence[FloatArray], free: Sequence[int]
) -> list[FloatArray]:
    """The outputs with each free experiment's DC the data's (less the common residual DC when ``common``):
    every residual formed from them is the projected one."""
    target = _residual_dcs(exps, outs, free)
    out = list(outs)
    for k, i in enumerate(free):
        o = np.asarray(out[i], dtype=np.float64)
        y = o - float(np.mean(o)) + float(np.mean(exps[i].ybar)) - float(target[k])
        y.flags.writeable = False
        out[i] = y
    return out


def _start_dcs(
    exps: Sequence[AugExperiment], start: AugParams, free: Sequence[int], substeps: int
) -> FloatArray:
    """The first pass's DCs: the start model's own (plus the common residual DC), else the data's."""
    try:
        outs = [
            np.asarray(augmented_output(exps[i], start, i, substeps=substeps), dtype=np.float64)
            if i in free
            else exps[i].ybar
            for i in range(len(exps))
        ]
    except BudgetExceededError:
        raise
    except BoucWenIdError:
        return np.array([float(np.mean(exps[i].ybar)) for i in free])
    return np.array([float(np.mean(outs[i])) for i in free]) + _residual_dcs(exps, outs, free)


def _jbars(exps: Sequence[AugExperiment], f: AugFit, free: Sequence[int], substeps: int) -> FloatArray:
    """Each free experiment's Jacobian's mean over its samples, in the Fisher matrix's order (rows)."""
    nsh = 3 + len(f.params.terms)
    out = np.zeros((len(free), np.shape(f.fisher)[0]))
    for k, i in enumerate(free):
        o = augmented_output(exps[i], f.params, i, substeps=substeps, jacobian=True)
        out[k, :nsh] = np.mean(o.jacobian, axis=0)
        out[k, nsh + 2 * i : nsh + 2 * i + 2] = np.mean(o.own_jacobian, axis=0)
    return out


def _newton(
    work: Sequence[AugExperiment], f: AugFit, free: Sequence[int], substeps: int, a: FloatArray, g: FloatArray
) -> FloatArray:
    """The DCs' Newton step towards the fixed point ``h(c) = c`` (``g = h(c) - c``): the fit's estimates
    move with the data's DCs by ``F^-1 a_l jbar_l`` (``F`` the Fisher matrix), so ``dh/dc = Q A`` with
    ``A_kl = jbar_k F^-1 jbar_l a_l`` and ``Q`` the common DC's projection (identity without it). ``g``
    itself (the plain update) when the Jacobian cannot be formed."""
    try:
        jb = _jbars(work, f, free, substeps)
    except BudgetExceededError:
        raise
    except BoucWenIdError:
        return g
    fisher = np.asarray(f.fisher, dtype=np.float64)
    d = np.sqrt(np.abs(np.diag(fisher)))
    d[d == 0.0] = 1.0
    finv = np.linalg.pinv(fisher / np.outer(d, d), rcond=1e-12, hermitian=True) / np.outer(d, d)
    amat = (jb @ finv @ jb.T) * a[None, :]
    if _common(work, free):
        amat = (np.eye(len(free)) - np.outer(np.ones(len(free)), a) / a.sum()) @ amat
    try:
        step = np.linalg.solve(np.eye(len(free)) - amat, g)
    except np.linalg.LinAlgError:
        return g
    return step if np.all(np.isfinite(step)) else g


def _projected(exps: Sequence[AugExperiment], f: AugFit, substeps: int, free: Sequence[int]) -> AugFit:
    """``f`` as the projected problem's: outputs with the data's DCs (less the common residual DC), the
    cost of those residuals, and the Fisher matrix less the free DC directions."""
    outs = _matched(exps, f.outputs, free)
    cost = float(sum(e.weight * float(np.sum((e.ybar - y) ** 2)) for e, y in zip(exps, outs)))
    fisher = np.array(f.fisher, dtype=np.float64)
    nsh = 3 + len(f.params.terms)
    means, weights = [], []
    try:
        for i in free:
            e = exps[i]
            out = augmented_output(e, f.params, i, substeps=substeps, jacobian=True)
            jbar = np.zeros(fisher.shape[0])
            jbar[:nsh] = np.mean(out.jacobian, axis=0)
            jbar[nsh + 2 * i : nsh + 2 * i + 2] = np.mean(out.own_jacobian, axis=0)
            means.append(jbar)
            weights.append(e.weight * e.ybar.size)
    except BudgetExceededError:
        raise
    except BoucWenIdError:
        fisher = np.full_like(fisher, np.nan)
    else:
        for a, jbar in zip(weights, means):
            fisher -= a * np.outer(jbar, jbar)
        if _common(exps, free):
            s = np.sum([a * jbar for a, jbar in zip(weights, means)], axis=0)
            fisher += np.outer(s, s) / float(np.sum(weights))
        fisher = 0.5 * (fisher + fisher.T)
    fisher.flags.writeable = False
    cov = _covariance(fisher)
    cov.flags.writeable = False
    return replace(f, cost=cost, fisher=fisher, covariance=cov, outputs=tuple(outs))


__all__ = [
    "FreeDC",
    "marked",
    "spent",
    "count",
    "centred",
    "project",
    "fit",
    "note",
    "DC_TOL",
    "MAX_PASSES",
    "NOT_CONVERGED",
]

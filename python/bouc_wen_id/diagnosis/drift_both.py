"""Both drift terms modelled at once, when the period record needs both (issue 18, review 34 problem 4).

The drift stage names one drift term, strength (``delta_nu``) or stiffness (``delta_eta``) degradation, and
tests the other given it (drift.compare: the partial F on the two-column fit in the period blocks). When that
test passes, the other term passes its own test alone, and the two-column fit predicts each experiment's
block deviations from the others' better than the named term alone (leave one experiment out), both are
modelled: the averaged periods are brought back to the virgin state by one simulation with both terms (one
energy drives both: Baber-Noori), and the pair is refined on both costs, as :func:`.drift_passes.refine`
refines one term,

    C(d_1, d_2) = C_drift(d_1, d_2) + C_steady(d_1, d_2),

``C_drift`` the two-column quadratic of the block deviations (the regressors at the plain fit: each loop at
its own mean strength and stiffness, as drift.compare formed them), ``C_steady`` the chi-square of the
steady model refitted to the averaged periods corrected at ``(d_1, d_2)``. The covariance is ``2 H^-1``
(``H`` the cost's Hessian by central differences), and the steady fit's own uncertainty is carried into
both values through the regressors (drift_se.py: ``g' C g`` of each entry of the two-column estimate).
The passes' feedback of drift_se.py is not applied: the pair is not found by correction passes (tried: one
pass re-forming the regressors at the pair's virgin fit, each loop at its own mean strength and stiffness,
moved review 34's degr_both from delta_eta 0.0476, delta_nu 0.0837 to 0.0338, 0.0651, truth 0.05, 0.0854;
the regressors stay the plain fit's, as drift.compare formed them; with strength degradation's column
re-formed alone, each loop at its own mean strength and stiffness, delta_nu went to 0.053-0.056).
Each value's standard error is at least its move from the first-order two-column value to the refined
one: the two estimate the same pair, and on review 34's simulator with a resonant G with delay (case
dboth_res of /work/degpair35_rev/extra35.py: delta_nu 0.00112 with delta_eta 0.0017) the first-order
delta_nu was 0.00147 +- 0.00003 and the refined 0.00175 +- 0.00002. The records' unrecorded ages (age.py)
are not fitted for the pair: age.py's test is one drift term's, and with the second term missing it took
the rival's drift for ages (the library's own pair record from rest was given ages of 5-9 periods).

Measured before this (review 34 degr_both: strength 0.0854 with stiffness 0.05): the verdict named only
stiffness degradation, ``delta_eta = 0.0545 +- 0.0018`` (2.5 se off), the steady fit corrected for it alone,
and blamed the rest on "physics outside the library".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from .data import DiagExperiment
from .drift import DegradationTest, DriftData, _inner, corrected, drift_data
from .drift_pair import needs_both
from .drift_se import variances
from .fitting import Scale, fit_from

#: The search box of the pair around the two-column fit's values (relative to each).
PAIR_BRACKET = 0.4
#: The search's tolerance on each value (relative) and its largest number of cost evaluations.
PAIR_XTOL = 2e-3
PAIR_MAXFEV = 60
#: The relative step of the Hessian's central differences.
HESSIAN_STEP = 0.03


def beside(deg: Optional[DegradationTest]) -> tuple[tuple[str, float], ...]:
    """The second drift term and its value (scaled) for :func:`.drift.corrected` (() when there is none)."""
    if deg is None or deg.second is None:
        return ()
    return ((deg.second.term, float(deg.second.d)),)


def drift_cost(deg: DegradationTest) -> float:
    """The drift chi-square left by the named drift terms: the pair's when both are modelled."""
    return deg.cost1 if deg.second is None else deg.second.cost1


def _normal(dd: DriftData, terms: tuple[str, str]) -> tuple[np.ndarray, np.ndarray, float]:
    """One experiment's two-column normal matrix, right-hand side and ``C0``."""
    regs = [dd.energy * dd.t[:, None] * dd.column(t)[None, :] for t in terms]
    a = np.array([[float(np.dot(dd.w, _inner(p, q, dd.hw))) for q in regs] for p in regs])
    r = np.array([float(np.dot(dd.w, _inner(dd.dev, p, dd.hw))) for p in regs])
    return a, r, float(np.dot(dd.w, _inner(dd.dev, dd.dev, dd.hw)))


def _cost(a: np.ndarray, r: np.ndarray, c0: float, d: np.ndarray) -> float:
    return float(c0 - 2.0 * d @ r + d @ a @ d)


def held_out_better(per: Sequence[tuple[np.ndarray, np.ndarray, float]]) -> bool:
    """Whether the pair, fitted on the other experiments, predicts each one's block deviations better in
    sum than the first term alone fitted the same way (both clipped at 0; False for one experiment)."""
    if len(per) < 2:
        return False
    a_all = np.sum([p[0] for p in per], axis=0)
    r_all = np.sum([p[1] for p in per], axis=0)
    one = two = 0.0
    for a, r, c0 in per:
        a_rest, r_rest = a_all - a, r_all - r
        d1 = max(r_rest[0] / a_rest[0, 0], 0.0) if a_rest[0, 0] > 0 else 0.0
        one += _cost(a, r, c0, np.array([d1, 0.0]))
        try:
            d2 = np.clip(np.linalg.solve(a_rest, r_rest), 0.0, None)
        except np.linalg.LinAlgError:
            return False
        two += _cost(a, r, c0, d2)
    return two < one


def modelled(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    plain: AugFit,
    fit: AugFit,
    deg: DegradationTest,
    s: Scale,
    substeps: int,
    alpha: float,
    named: bool,
) -> Optional[tuple[DegradationTest, AugFit]]:
    """``deg`` with its rival modelled beside it (``deg.second``) and both values from the pair, with the
    steady fit of the periods corrected for both, when the record needs both (module docstring); else None.
    ``fit``: the steady fit corrected for ``deg`` alone (the pair's fits start from it)."""
    rival = deg.rival
    if not needs_both(deg, named, alpha) or rival is None or not rival.passed:
        return None
    data = drift_data(exps, sx, plain, s.y, substeps)
    terms = (deg.term, rival.term)
    if not held_out_better([_normal(dd, terms) for dd in data]):
        return None
    per = [_normal(dd, terms) for dd in data]
    a = np.sum([p[0] for p in per], axis=0)
    r = np.sum([p[1] for p in per], axis=0)
    c0 = float(sum(p[2] for p in per))
    try:
        start = np.linalg.solve(a, r)
    except np.linalg.LinAlgError:
        return None
    if not np.all(start > 0):
        return None
    got = _refined(exps, sx, fit, terms, (a, r, c0), start, s, substeps)
    if got is None:
        return None
    dv, cov, pair_fit = got

    def estimate(regs: Sequence[DriftData]) -> np.ndarray:
        moved = [replace(rr, dev=dd.dev, t=dd.t, w=dd.w) for dd, rr in zip(data, regs)]
        parts = [_normal(dd, terms) for dd in moved]
        return np.linalg.solve(np.sum([p[0] for p in parts], axis=0), np.sum([p[1] for p in parts], axis=0))

    extra = variances(exps, sx, plain, data, estimate, s.y, substeps)
    # The first-order two-column values and the refined ones are two estimates of the same pair: where
    # they differ by more than the refined se, the difference is the model's own error, and the se is
    # at least it (module docstring: review 34's resonant G with delay moved delta_nu 19 %).
    se = np.maximum(np.sqrt(np.clip(np.diag(cov), 0.0, None) + extra), np.abs(dv - start)) / s.y**2
    c2 = _cost(a, r, c0, dv)
    out = []
    for k, test in enumerate((deg, rival)):
        out.append(
            replace(
                test,
                d=float(dv[k]),
                value=float(dv[k]) / s.y**2,
                standard_error=float(se[k]),
                cost1=c2 if k else test.cost1,  # the first keeps its own (its F); the pair's on the second
                rate=tuple(float(dv[k]) * dd.energy for dd in data),
                jac=tuple(dd.column(terms[k]) for dd in data),
                experiments=tuple(dd.index for dd in data),
            )
        )
    return replace(out[0], second=out[1]), pair_fit


def _refined(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    terms: tuple[str, str],
    drift: tuple[np.ndarray, np.ndarray, float],
    start: np.ndarray,
    s: Scale,
    substeps: int,
) -> Optional[tuple[np.ndarray, np.ndarray, AugFit]]:
    """``(values, covariance, steady fit)`` of the pair at the minimum of both costs (scaled units); None
    when a cost cannot be formed, or the pair does not lower the cost below the first term alone (the
    rival at 0, the first at its two-column value)."""
    from scipy.optimize import minimize  # type: ignore[import-untyped]

    fits: dict[tuple[float, float], AugFit] = {}

    def cost(dv: np.ndarray) -> float:
        key = (float(dv[0]), float(dv[1]))
        if key[0] < 0 or key[1] < 0:
            return math.inf
        _, fs = corrected(exps, sx, fit, key[0], s.y, substeps, terms[0], ((terms[1], key[1]),))
        f = fit_from(fs, fit.params, substeps, max_iter=50)
        if f is None:
            return math.inf
        fits[key] = f
        return f.cost + _cost(*drift, dv)

    res = minimize(
        lambda x: cost(start * x),
        np.ones(2),
        method="Nelder-Mead",
        bounds=[(1.0 - PAIR_BRACKET, 1.0 + PAIR_BRACKET)] * 2,
        options={"xatol": PAIR_XTOL, "fatol": 1e-3, "maxfev": PAIR_MAXFEV},
    )
    dv = start * np.asarray(res.x, dtype=np.float64)
    best = float(res.fun)
    key = (float(dv[0]), float(dv[1]))
    alone = cost(np.array([start[0], 0.0]))
    if not (math.isfinite(best) and key in fits and best < alone):
        return None
    h = HESSIAN_STEP * dv
    hess = np.zeros((2, 2))
    for i in range(2):
        e = np.zeros(2)
        e[i] = h[i]
        hess[i, i] = (cost(dv + e) - 2.0 * best + cost(dv - e)) / h[i] ** 2
    e1, e2 = np.array([h[0], 0.0]), np.array([0.0, h[1]])
    cross = cost(dv + e1 + e2) - cost(dv + e1 - e2) - cost(dv - e1 + e2) + cost(dv - e1 - e2)
    hess[0, 1] = hess[1, 0] = cross / (4.0 * h[0] * h[1])
    if not np.all(np.isfinite(hess)) or np.linalg.det(hess) <= 0 or hess[0, 0] <= 0:
        return None
    return dv, 2.0 * np.linalg.inv(hess), fits[key]


__all__ = [
    "HESSIAN_STEP",
    "PAIR_BRACKET",
    "PAIR_MAXFEV",
    "PAIR_XTOL",
    "beside",
    "held_out_better",
    "modelled",
]

"""Fits that sat in a local minimum: wide starts for a term, and the check that a step's baseline converged.

Review 31a: a large spring or damper across the hysteretic element (on x), through a resonant G, is absorbed
by the plain model as a nearly linear loop (mu at its lower bound, ``gamma`` near ``-beta``: ``w_u`` far above
the data). Every start of the term from there (the least-squares value on the plain residual, which the
plain loop has already absorbed: about 0) stays in that basin: a 0.3 spring on x moved chi2 3.55e6 ->
3.39e6 (its true fit: 1544 on 1520 dof) and the diagnosis said "unexplained". A step's chosen fit stuck the
same way (viscous on u, chi2 765196 on 1520 dof) made the next step credit whatever term made its refit
escape (a series dashpot named at "100 % of the excess").

- :func:`suspicious`: a fit far from adequate (reduced chi-square above :data:`FAR_CHI2`) that ends on a face
  of its admissible range, with mu beyond the profile bracket, or costs more than its nested base;
- :func:`wide_starts`: starts for a linear term (:attr:`Term.linear`) that let it carry a large share of the
  output: the term at :data:`SHARES` of the data's own projection on its regressor, the hysteresis reset to
  a generic loop saturating at the rest of the output's peak (the base's gains and phases kept);
- :func:`rebase`: forward selection's consistency check. When two or more unrelated candidates lower the
  cost by about the same amount (:data:`SIMILAR`), the improvement may be the refit's, not the terms': the
  base model is refitted from those candidates' fits with their term removed (when the best improvement is
  an F of at least :data:`REBASE_MIN_F`); if that alone recovers most of the improvement
  (:data:`RECOVERED`), the base was not converged, and the step restarts from the refit instead of
  crediting a term.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit, AugParams
from ..terms import TERMS
from .fitting import PROFILE_MU_BRACKET, best_of, fit_dof, fit_from, regressor, screen

#: A fit whose reduced chi-square (cost over its dof) exceeds this is "far from adequate": the level at
#: which a fit ending on a face of its range is taken for a local minimum rather than the data's pull.
FAR_CHI2 = 10.0
#: Shares of the output's projection on a linear term's regressor given to the term by :func:`wide_starts`.
SHARES = (0.25, 0.5, 0.75)
#: The generic loop of :func:`wide_starts`: exponent, gamma/beta, saturation over the rest of the peak.
WIDE_MU = 1.5
WIDE_RATIO = 0.0
WIDE_HEADROOM = 1.1
#: Candidates whose improvements lie within this fraction of the best one lower the cost "by about the same
#: amount" (:func:`rebase`).
SIMILAR = 0.2
#: The base refitted without any term must recover at least this share of the best candidate's improvement
#: for the base to count as not converged (:func:`rebase`).
RECOVERED = 0.5
#: ... and that improvement must be an F of at least this over the base's reduced chi-square (at least 1):
#: no refit for the small, alike improvements of a model at the noise floor (a null's targeted step).
REBASE_MIN_F = 10.0
#: At most this many candidate fits (those with the largest improvements) seed the base's refit.
REBASE_SEEDS = 2


def reduced_chi2(exps: Sequence[AugExperiment], fit: AugFit) -> float:
    """``cost / dof`` (the dof as :func:`.select.dof_of` counts it)."""
    dof = fit_dof(exps, fit.params)
    return fit.cost / dof


def odd_shape(fit: AugFit) -> bool:
    """A fit on a face of its admissible range (``fit.active``: mu at its lower bound, ``|gamma| = beta``), or
    with mu beyond the profile bracket's upper end (a loop drawn as two straight lines)."""
    return bool(fit.active) or fit.params.mu > PROFILE_MU_BRACKET[1]


def suspicious(exps: Sequence[AugExperiment], base: AugFit, fit: Optional[AugFit]) -> bool:
    """Whether ``fit`` (``base`` plus one term; None: no start converged) may be a local minimum worth wide
    starts: none at all, a cost above ``base``'s (the term at 0 reproduces ``base``), or a fit far from
    adequate with an odd shape (:func:`odd_shape`)."""
    if fit is None or not math.isfinite(fit.cost) or fit.cost > base.cost:
        return True
    return reduced_chi2(exps, fit) > FAR_CHI2 and (odd_shape(fit) or odd_shape(base))


def data_projection(exps: Sequence[AugExperiment], par: AugParams, term: str, substeps: int) -> float:
    """The least-squares value of linear ``term`` on the data themselves (all of the output its own)."""
    num = den = 0.0
    for i, e in enumerate(exps):
        g = regressor(term, e, par, i, substeps)
        num += e.weight * float(np.dot(g, e.ybar))
        den += e.weight * float(np.dot(g, g))
    return num / den if den > 0 else 0.0


def wide_starts(exps: Sequence[AugExperiment], base: AugFit, term: str, substeps: int) -> list[AugParams]:
    """Starts of ``base`` plus linear ``term`` (module docstring); empty for another term."""
    if not TERMS[term].linear or TERMS[term].companion:
        return []
    v = data_projection(exps, base.params, term, substeps)
    if not math.isfinite(v) or v == 0.0:
        return []
    peak = max(float(np.max(np.abs(e.ybar - e.ybar.mean()))) for e in exps)
    out = []
    for f in SHARES:
        bg = (WIDE_HEADROOM * (1.0 - f) * peak) ** (-WIDE_MU)  # beta + gamma: saturation at the rest
        beta = bg / (1.0 + WIDE_RATIO)
        par = replace(base.params, beta=beta, gamma=WIDE_RATIO * beta, mu=WIDE_MU)
        out.append(par.with_term(term, f * v))
    return out


def wide_fit(
    exps: Sequence[AugExperiment], base: AugFit, term: str, substeps: int, first: Optional[AugFit]
) -> Optional[AugFit]:
    """``first`` (the term's own fit) or, when it is :func:`suspicious`, the best of it and the
    :func:`wide_starts` (each screened, :func:`.fitting.screen`, the best finished)."""
    if not suspicious(exps, base, first):
        return first
    starts = wide_starts(exps, base, term, substeps)
    if not starts:
        return first
    screened = best_of([screen(exps, st, substeps) for st in starts])
    if screened is None or (first is not None and screened.cost >= first.cost):
        return first
    return best_of([first, screened, fit_from(exps, screened.params, substeps)])


def without(par: AugParams, term: str) -> AugParams:
    """``par`` with ``term`` (and its companion, for a two-term element) removed."""
    drop = {term, TERMS[term].companion} if TERMS[term].companion else {term}
    keep = [i for i, t in enumerate(par.terms) if t not in drop]
    return replace(par, terms=tuple(par.terms[i] for i in keep), values=par.values[keep].copy())


def rebase(
    exps: Sequence[AugExperiment],
    current: AugFit,
    tried: Sequence[tuple[str, Optional[AugFit]]],
    substeps: int,
    related: Sequence[tuple[str, str]] = (),
) -> Optional[AugFit]:
    """A better fit of ``current``'s own model when ``tried`` (each candidate term with its fit of
    ``current`` plus that term) says the base was not converged (module docstring); else None.

    ``related``: pairs of terms that are the same physics (its places): their improvements are alike by
    nature, so they count once."""
    gains = sorted(
        ((current.cost - f.cost, t, f) for t, f in tried if f is not None and math.isfinite(f.cost)),
        key=lambda g: -g[0],
    )
    if not gains or gains[0][0] <= 0.0:
        return None
    best = gains[0][0]
    if best < REBASE_MIN_F * max(reduced_chi2(exps, current), 1.0):
        return None
    alike: list[tuple[float, str, AugFit]] = []
    for g in gains:
        if g[0] < (1.0 - SIMILAR) * best:
            break
        if not any((g[1], a[1]) in related or (a[1], g[1]) in related for a in alike):
            alike.append(g)
    if len(alike) < 2:
        return None
    refits = [fit_from(exps, without(f.params, t), substeps) for _, t, f in alike[:REBASE_SEEDS]]
    refit = best_of(refits)
    if refit is None or current.cost - refit.cost < RECOVERED * best:
        return None
    return refit


def rebased_plain(plain: AugFit, start: AugFit, steps: Sequence[Any]) -> tuple[AugFit, AugFit]:
    """``(plain, start)`` after a forward selection whose first step refitted its base ``start`` (the
    step's ``base``, :func:`rebase`): the refit replaces ``start``, and ``plain`` when ``start`` was it."""
    new = steps[0].base if steps and steps[0].base is not None else None
    if new is None:
        return plain, start
    return (new if plain is start else plain), new


def rebase_groups(
    groups: Sequence[Any], trials: Sequence[Any], related: Sequence[tuple[str, str]]
) -> tuple[str, ...]:
    """diagnose_across's check (:func:`rebase`) at each condition of ``groups`` (``.sx``, ``.current``,
    ``.plain``, ``.substeps``, ``.label``), on the step's ``trials`` (``.term``, ``.fits``: one per
    condition): each condition whose model was not converged gets its refit as its current model (and as
    its plain model when it was that); the labels of those conditions."""
    out = []
    for k, g in enumerate(groups):
        better = rebase(g.sx, g.current, [(tr.term, tr.fits[k]) for tr in trials], g.substeps, related)
        if better is None:
            continue
        if g.plain is g.current:
            g.plain = better
        g.current = better
        out.append(str(g.label))
    return tuple(out)


__all__ = [
    "rebase_groups",
    "rebased_plain",
    "FAR_CHI2",
    "suspicious",
    "odd_shape",
    "wide_starts",
    "wide_fit",
    "without",
    "rebase",
    "reduced_chi2",
]

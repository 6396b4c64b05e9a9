"""What a correctly specified test could say about one bench case: the TRUE model's likelihood-ratio test.

A library row's miss is one of four things, and the bench should say which (issue 18, "Must show": the
right term at the right place in >= 95 % of cases at 10x and 30x):

- **undetectable**: the true model (plain + the hidden term at its place), fitted to the NOISY data, gains
  too little chi2 over the plain model for its own F test to reject the plain model even ALONE, at the
  first step's level (``alpha / 2`` when the global test accepted the plain model, else ``alpha``) with no
  correction for the other candidates: even an oracle that knew the term would say "adequate";
- **below the search's level**: that F test alone rejects the plain model at the step's level, but not
  after the diagnosis's Bonferroni over the step's candidates (p times their number): a test told the term
  sees it, a search over the library that keeps nulls quiet cannot. The price of the search, not of the
  noise (session 35: the bench's "undetectable" 10x sensor lag and series dashpot misses were all of this
  kind, raw p 0.0027-0.033);
- **law refused**: the truth's own law test (one value for every experiment) fails at ``LAW_ALPHA``: the
  test refuses a true term in about that share of cases by construction (docs/diagnosis.md, "Calibration of
  the law test");
- **truth rejected**: the true model fails its own adequacy test at ``alpha`` (a high noise draw): no
  verdict can be "explained", and a share of the excess below one half is "unexplained" by design;
- otherwise a **search** failure: the diagnosis had what it needed and did not name the truth (a local
  minimum shows as the diagnosis's step-1 trial cost of the truth above the oracle's best fit).

The oracle's fit of the truth is the diagnosis's own candidate fit (``fitting.fit_with`` from the plain
fit) and, to rule out a local minimum, restarts from its value times :data:`START_FACTORS`; the best is
kept. Everything is in the diagnosis's own units and weights (``d.experiments``, ``d.plain_fit``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Optional

import numpy as np

#: Restarts of the truth's fit: its fitted value times these (the sign kept), to catch a local minimum.
START_FACTORS = (0.25, 0.5, 2.0, 4.0)
#: A step-1 trial cost of the truth above the oracle's by more than this (chi2 units) is a local minimum.
LOCAL_TOL = 1.0


def _restarts(sx: Any, fit: Any, term: str, substeps: int) -> Any:
    from bouc_wen_id.diagnosis.fitting import best_of, fit_from

    par = fit.params
    k = par.terms.index(term)
    v = float(par.values[k])
    if v == 0.0 or not math.isfinite(v):
        return fit
    starts = []
    for f in START_FACTORS:
        vals = np.array(par.values, dtype=float)
        vals[k] = v * f
        starts.append(replace(par, values=vals))
    return best_of([fit] + [fit_from(sx, st, substeps) for st in starts])


def truth_lr(d: Any, truth: Optional[str]) -> dict[str, Any]:
    """The oracle's numbers for diagnosis ``d`` of a case whose hidden term is ``truth`` (a code name with
    its place, e.g. ``viscous@x``; None or a term outside the diagnosis's candidates: ``{}``).

    Keys: ``lr_gain`` (plain cost minus the truth's), ``lr_p`` (the diagnosis's F test of that gain, alone),
    ``lr_p_adj`` (times ``lr_candidates``, the number of the step's candidates), ``lr_level``,
    ``lr_detectable``, ``truth_p`` (the truth's adequacy p), ``truth_law_p`` (``element_law_test``),
    ``trial_gap`` (the diagnosis's step-1 trial cost of the truth minus the oracle's; NaN when the step
    did not fit it)."""
    from bouc_wen_id.diagnosis import free_dc
    from bouc_wen_id.diagnosis.candidates import step_candidates
    from bouc_wen_id.diagnosis.fitting import Scale, fit_with, scaled
    from bouc_wen_id.diagnosis.locate import adequacy_p
    from bouc_wen_id.diagnosis.select import BOUNDARY_TERMS, dof_of, element_law_test, f_test

    # The candidates of the first step (its trials; else the steady ones): the Bonferroni count is theirs,
    # and a drift term (degradation: fitted in drift space) has no steady fit here.
    steady = step_candidates(tuple(d.settings.get("candidates", ())), pure_sines=False)
    cands = tuple(t.term for t in d.steps[0].trials) if d.steps else steady
    if truth is None or truth not in steady or d.plain_fit is None:
        return {}
    s = Scale(d.settings["scale"]["y"], d.settings["scale"]["u"])
    sx = scaled(list(d.experiments), s)
    substeps = int(d.settings["substeps"])
    plain = d.plain_fit
    f = fit_with(sx, plain, truth, substeps)
    if f is None:
        return {"lr_gain": math.nan, "lr_detectable": False, "truth_no_fit": True}
    f = _restarts(sx, f, truth, substeps)
    alpha = float(d.settings["alpha"])
    targeted = bool(d.steps[0].targeted) if d.steps else True
    level = 0.5 * alpha if targeted else alpha
    d1 = dof_of(sx, f)
    q = max(len(f.params.terms) - len(plain.params.terms), 1)
    _, p = f_test(plain.cost, f.cost, d1, boundary=truth in BOUNDARY_TERMS, q=q)
    p_adj = min(1.0, p * max(len(cands), 1)) if math.isfinite(p) else math.nan
    noise_dof = sum(int(e.noise_dof) for e in d.experiments)
    dof = sum(a.ybar.size for a in sx) - free_dc.spent(sx) - (3 + len(f.params.terms) + 2 * len(sx))
    trial = next((t.cost for t in (d.steps[0].trials if d.steps else ()) if t.term == truth), math.nan)
    return {
        "lr_gain": float(plain.cost - f.cost),
        "lr_p": float(p),
        "lr_p_adj": p_adj,
        "lr_candidates": max(len(cands), 1),
        "lr_level": level,
        "lr_detectable": bool(math.isfinite(p_adj) and p_adj < level),
        "truth_p": adequacy_p(f.cost, dof, noise_dof),
        "truth_law_p": element_law_test(sx, f, truth, substeps),
        "trial_gap": float(trial - f.cost) if math.isfinite(trial) else math.nan,
    }


def powers(lam: float, level: float, candidates: int, boundary: bool) -> tuple[float, float]:
    """The first step's one-parameter test of the plain model against a term that takes up the plain model's
    whole noise-free leftover ``lam`` (its non-centrality: the bench's unabsorbed RMS squared times the
    samples): its power ``(alone, search)`` at ``level``, alone and after the Bonferroni over
    ``candidates``; one-sided (half the p) for a term bounded at 0 (``select.f_test``'s ``boundary``). What
    any test of that size could do with that noise: the ceiling of the row's detection."""
    from scipy.stats import chi2, ncx2, norm  # type: ignore[import-untyped]

    if not (math.isfinite(lam) and lam >= 0.0 and 0.0 < level < 1.0):
        return math.nan, math.nan

    def power(a: float) -> float:
        if boundary:
            return float(norm.sf(norm.isf(a) - math.sqrt(lam)))
        return float(ncx2.sf(chi2.isf(a, 1), 1, lam)) if lam > 0 else a

    return power(level), power(level / max(candidates, 1))


def cause(row: dict[str, Any], alpha: float = 0.05, law_alpha: float = 0.01) -> str:
    """Why a library case that is not right at its place missed (``""`` when it is right or not scored):
    "undetectable", "below search level", "law refused", "truth rejected", "local minimum" or "search"
    (module docstring)."""
    if row.get("right_place") or "lr_detectable" not in row:
        return ""
    if not row["lr_detectable"]:
        raw, level = row.get("lr_p", math.nan), row.get("lr_level", math.nan)
        alone = math.isfinite(raw) and math.isfinite(level) and raw < level
        return "below search level" if alone else "undetectable"
    law = row.get("truth_law_p", math.nan)
    if math.isfinite(law) and law < law_alpha:
        return "law refused"
    tp = row.get("truth_p", math.nan)
    if math.isfinite(tp) and tp < alpha:
        return "truth rejected"
    gap = row.get("trial_gap", math.nan)
    if math.isfinite(gap) and gap > LOCAL_TOL:
        return "local minimum"
    return "search"


def columns(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """A row's oracle columns over its cases that have the oracle's numbers (library rows): ``lr_det``, the
    share detectable by the true model's LR test; ``right_lr``, right at its place among those (the old
    ``right_place`` keeps every case); ``causes``, each miss's :func:`cause` counted; ``power_search``, the
    mean over the cases of the search's power (:func:`powers`, filled by the bench where it measured the
    leftover): the share of the row ANY diagnosis at the step's level and candidates could detect."""
    has = [r for r in rows if "lr_detectable" in r]
    if not has:
        return {"lr_det": math.nan, "right_lr": math.nan, "causes": {}}
    det = [r for r in has if r["lr_detectable"]]
    causes: dict[str, int] = {}
    for r in has:
        c = r.get("cause") or cause(r)
        if c:
            causes[c] = causes.get(c, 0) + 1
    right = [bool(r.get("right_place")) for r in det]
    pw = [float(r["power_search"]) for r in has if math.isfinite(r.get("power_search", math.nan))]
    return {
        "lr_det": len(det) / len(has),
        "right_lr": float(np.mean(right)) if right else math.nan,
        "causes": causes,
        "power_search": float(np.mean(pw)) if pw else math.nan,
    }


__all__ = ["LOCAL_TOL", "START_FACTORS", "cause", "columns", "powers", "truth_lr"]

"""The result's assembly for :func:`.run.diagnose`: a fit's summary and localisation, the status rule
(``classify``), the verdict's words (``_judged``, ``_verdict``, the law-failed and non-physical clauses)
and the explained shares. Moved out of run.py (no behaviour change); run.py re-exports every name."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS, Distortion, Offset, physical_value
from . import (
    adequacy_chi2,
    beyond_range,
    bounds_said,
    distortion_law,
    drift_clause,
    free_dc,
    gate,
    input_dc,
    law_chance,
    null_named,
    pairs,
    revisit,
)
from .data import DiagExperiment
from .drift import DegradationTest
from .fit_notes import centre_clause as _centre_text
from .fitting import Scale, physical
from .locate import Localisation, adequacy_p, locate
from .pinch_shape import is_pinching
from .result import ModelSummary, NamedTerm, Status, term_symbol_unit
from .select import Step
from .shape import has_branch

#: When the final model is still rejected, named terms that remove at least this share of the plain model's
#: excess give "partly explained" (the terms are named, with the share, and the structure left is located);
#: below it "unexplained" (the terms are reported as partial, not named).
PARTLY_EXPLAINED_FRACTION = 0.5


def _localise(
    exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], fit: AugFit, s: Scale
) -> Localisation:
    outs = [np.asarray(y) * s.y for y in fit.outputs]
    amps = [e.amplitude * g for e, g in zip(sx, fit.params.gains)]
    n = 3 + len(fit.params.terms) + 2 * len(sx)
    return locate(exps, outs, amps, list(fit.params.phases), n)


def _summary(
    exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], fit: AugFit, s: Scale, units: tuple[str, str]
) -> ModelSummary:
    par = fit.params
    terms = []
    for t in par.terms:
        v, se = physical(fit, s, t)
        sym, unit = term_symbol_unit(t, *units)
        terms.append(NamedTerm(t, sym, v, se, unit))
    dof = sum(a.ybar.size for a in sx) - free_dc.spent(sx) - (3 + len(par.terms) + 2 * len(sx))
    noise_dof = sum(e.noise_dof for e in exps)
    chi2 = adequacy_chi2.statistic(adequacy_chi2.relative_weights(exps), sx, fit.outputs, fit.cost)
    nr = []
    for e, y in zip(sx, fit.outputs):
        spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
        nr.append(float(np.linalg.norm(e.ybar - y)) / spread if spread > 0 else math.nan)
    return ModelSummary(
        terms=tuple(terms),
        beta=_unscaled(par.beta, s.y, par.mu),
        gamma=_unscaled(par.gamma, s.y, par.mu),
        mu=par.mu,
        cost=fit.cost,
        dof=dof,
        p_value=adequacy_p(chi2, dof, noise_dof),
        chi2=chi2,
        nrmse=tuple(nr),
        outputs=tuple(np.asarray(y) * s.y for y in fit.outputs),
    )


def _unscaled(v: float, s_y: float, mu: float) -> float:
    """``v / s_y^mu`` in logarithms: an extreme mu (a fit to noise) neither overflows nor divides by 0."""
    if v == 0.0 or not math.isfinite(v):
        return v
    lg = math.log(abs(v)) - mu * math.log(s_y)
    return math.copysign(math.exp(lg), v) if lg < 709.0 else math.copysign(math.inf, v)


def classify(plain_adequate: bool, has_terms: bool, final_adequate: bool, fraction: float) -> Status:
    """The verdict's status from the plain model's test, the final model's and the excess explained.

    "explained" only when the final model passes its adequacy test: a share of the excess, however large,
    leaves the rest unexplained (a final chi2/dof of 45 was called "explained" at 90 % of the excess).
    """
    if plain_adequate:
        return "adequate"
    if has_terms and final_adequate:
        return "explained"
    if has_terms and fraction >= PARTLY_EXPLAINED_FRACTION:
        return "partly explained"
    return "unexplained"


#: The localisation's word when no harmonic or region of the cycle stands out (locate.Localisation.where).
SPREAD = "spread over the cycle"


def _verdict(
    status: Status,
    named: Sequence[NamedTerm],
    partial: Sequence[NamedTerm],
    after: Localisation,
    fraction: float,
    drift: str = "",
    empty: str = SPREAD,
) -> str:
    """The verdict's words; ``drift``: the clause on a loop still drifting (:func:`.drift_clause.clause`);
    ``empty``: where the structure remains when the localisation found no place (none, or only
    :data:`SPREAD`): ``centre_only.DC_ONLY_WHERE`` when the only structure is the experiments' DCs."""
    if status == "adequate":
        return gate.ADEQUATE
    where = after.describe()
    if where in ("", SPREAD):  # no place found: the caller's word for that (the DCs alone, or SPREAD)
        where = empty
    if status == "explained":
        return "explained by: " + ", ".join(str(t) for t in named) + drift
    if status == "partly explained":
        return (
            "explained in part by: "
            + ", ".join(str(t) for t in named)
            + f" ({100 * fraction:.0f} % of the excess); unexplained structure remains {where}"
            + (drift if drift_clause.beyond(drift) else "")
        )
    tail = ""
    if partial:
        tail = (
            f" (tested terms {', '.join(t.label for t in partial)} remove {100 * fraction:.0f} % of the "
            "excess but leave structure the library does not model)"
        )
    return f"unexplained structure remains {where}{tail}"


#: What a non-physical value suggests.
NOT_PHYSICAL_HINT = (
    "the term stands in for physics the library places elsewhere (e.g. acting on the hysteresis' own input "
    "x through G, or a G whose phase trades with it); it is not named"
)


def _judged(
    status: Status,
    final: ModelSummary,
    located: tuple[Localisation, Localisation],
    fraction: float,
    fexps: Sequence[DiagExperiment],
    held: Optional[bounds_said.Beyond] = None,
    fit: Optional[AugFit] = None,
    empty: str = SPREAD,
) -> tuple[Status, tuple[NamedTerm, ...], tuple[NamedTerm, ...], str]:
    """``(status, named, partial, verdict)``: a term outside its physical range is never named (the rest is
    at most a partial explanation), nor one at its null value in ``fit`` (null_named.py), and the verdict
    says what the non-physical value and a residual DC of both signs suggest. ``located``: the plain
    model's localisation and the final's; ``empty``: where structure remains when the final's is empty
    (:func:`_verdict`)."""
    before, after = located
    nulls = null_named.terms(fit)
    gone = tuple(t for t in final.terms if t.term in nulls)
    outside = tuple(t for t in final.terms if not physical_value(t.term, t.value) and t not in gone)
    # Just outside, within its uncertainty: no evidence of an element beyond the range (beyond_range.py)
    faint = tuple(t for t in outside if beyond_range.within(t.term, t.value, t.standard_error))
    gone += faint
    unphysical = tuple(t for t in outside if t not in faint)
    if unphysical and status == "explained":
        status = "partly explained"
    named: tuple[NamedTerm, ...] = ()
    if status in ("explained", "partly explained"):
        named = tuple(t for t in final.terms if t not in unphysical and t not in gone)
    if not named and status != "adequate":
        status = "unexplained"
    status, named, head, tail = bounds_said.apply(held, status, named, final.terms, fraction)
    partial = tuple(t for t in final.terms if t not in named and t not in gone)
    drift = drift_clause.clause(after, before, named)  # beyond a named drift term (drift_clause.py)
    if status == "explained" and drift_clause.beyond(drift):  # a drift left over is not explained
        status = "partly explained"
    if head and held is not None and held.targeted_soft:  # no excess to share out (bounds_said.py)
        verdict = head + bounds_said.TARGETED_BODY
    else:
        verdict = head + _verdict(
            status, named, tuple(t for t in partial if t not in unphysical), after, fraction, drift, empty
        )
    verdict = input_dc.qualify(verdict + _unphysical_text(unphysical) + tail, named, fexps)  # a preload
    verdict += null_named.text(tuple(t for t in gone if t not in faint)) + beyond_range.text(faint)
    if status != "adequate":
        offset = any(t.term == Offset.kind for t in final.terms)  # said about it, not against it
        verdict += _centre_text(fexps, final.outputs, max(1.0, final.cost / max(final.dof, 1)), offset)
    return status, named, partial, verdict


def _explained_fraction(plain: ModelSummary, final: ModelSummary, deg: Optional[DegradationTest]) -> float:
    """The share of the plain model's excess the final model removes (both spaces when degradation is
    named: the steady excess and the drift excess), capped at 1 (a model below the noise floor fitted some
    noise too)."""
    drift = [] if deg is None else [(deg.cost0, deg.dof0, deg.cost1)]
    return gate.explained_fraction([(plain.cost, plain.dof, final.cost), *drift])


def _naming_share(fraction: float, deg: Optional[DegradationTest], named_deg: bool) -> float:
    """The share that decides "explained in part": the share of the whole excess, or, when degradation's
    own test names it, at least the share of the drift space's excess it removes. The two spaces are tested
    apart (design.md 10.6): a drift the period record shows and degradation explains stays explained when a
    steady misfit elsewhere (a clipped input's harmonics) dwarfs it in the pooled share (blind
    degradation:30:0:clipped: 27 % of the pooled excess, the drift space's all of it, F = 4088), and the
    verdict then says where the rest sits."""
    if deg is None or not named_deg:
        return fraction
    return max(fraction, gate.explained_fraction([(deg.cost0, deg.dof0, deg.cost1)]))


def _unphysical_text(terms: Sequence[NamedTerm]) -> str:
    if not terms:
        return ""
    what = "; ".join(f"{t} ({TERMS[t.term].unphysical})" for t in terms)
    return f"; not physical: {what}: {NOT_PHYSICAL_HINT}"


def _law_text(steps: Sequence[Step]) -> str:
    """What the verdict says of candidates that fit part of the misfit with a value that differs between
    experiments (select.law_test): stand-ins for physics outside the library or for several library terms
    at once that the pair step (pairs.py) could not name, tested and not named; with why the pair step did
    not name them."""
    failed: dict[str, float] = {}
    # A named term's law-failed alternative (select.preferred_by_fit) is said there: at no step a stand-in.
    listed = {
        a.rival for st in steps for a in getattr(st, "alternatives", ()) if math.isfinite(a.law_p_value)
    }
    # A term named at any step (alone or in a set) is no stand-in: its law failed only before it was named.
    listed |= {t for st in steps for t in (getattr(st, "chosen", None), *getattr(st, "pair", ())) if t}
    for st in steps:
        for tr in st.trials:
            if tr.term in st.law_failed and tr.term not in failed and tr.term not in listed:
                failed[tr.term] = tr.law_p_value
    named = pairs.text(steps) + revisit.text(steps)  # sets named or kept as alternatives (pairs, revisit)
    if not failed:
        return named  # a pair named where each member's law failed alone (pairs.py)
    if (drive := distortion_law.text(failed)) is not None:  # the drive's harmonics, not device physics
        return named + drive
    what = ", ".join(f"{TERMS[t].place_label()} (p = {p:.2g})" for t, p in failed.items())
    shape = "; for Dahl friction, or a branch shape not its own" if any(map(has_branch, failed)) else ""
    shape += "; for pinching, or a band not its own" if any(map(is_pinching, failed)) else ""
    if Distortion.kind in failed:  # its law fails when G at the input's harmonics is not the G carried there
        shape += (
            "; for the measured input waveform, or G at the input's harmonics not the one carried from the "
            "tested band (lam far from 1)"
        )
    return named + (
        f"; not named: {what}: each fits part of the misfit, but with a value that differs between "
        f"experiments (its law, one value for all, fails{shape}): it stands in for physics outside the "
        f"library, or for several library terms at once beyond what the pair step could name ("
        f"{pairs.refusal_text(steps)}){law_chance.text(steps)}"
    )

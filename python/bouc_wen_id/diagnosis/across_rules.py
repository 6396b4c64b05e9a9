"""The single-group selection's step rules, applied to a step of the joint selection across conditions.

:func:`.run.diagnose`'s forward selection (:func:`.select.forward_select`) orders, tests and reports a
step's candidates by rules that :func:`.across.diagnose_across` did not apply. Here they are applied to a
joint step (a candidate added at every condition at once) through the same functions:

- **the pooled F test** (:func:`pooled_f`): the per-condition improvements summed over the pooled residual
  variance (never below the noise), against ``F(q K, sum dof_k)``: the candidate's own test, and the test by
  which a two-term element must beat its simpler limit;
- **simpler first** (:func:`simpler_first`, through :func:`.select.limit_first`): Dahl friction nests a
  spring and dry friction (at either place); unless it beats the best of them that passed by the pooled F
  test of its extra parameter at the step's Bonferroni level, the simpler term goes first;
- **the law** (:func:`law_p`): everything the term claims (:func:`.select.element_law_test`) at every
  condition where it is present, Bonferroni over those conditions;
- **alternatives** (:func:`alternatives`): the chosen term at its other place when the summed costs of the
  two places differ by less than the 5 % point of chi-square(K) (:data:`.select.PLACE_CHI2` for one
  condition), times the pooled chi2/dof when above 1, with a physical value that is not its null wherever
  the chosen term is present (:func:`.select.place_admissible`; else no alternative, said as not physical),
  its own law holding where it is present, with the experiment that separates places
  (:func:`.select._place_separation`); a rival whose summed improvement is within the chosen one's
  uncertainty (:func:`.across_verdict.tied`), or within 10 % of it with its value confounded with the
  chosen one's (``|rho| >= ALTERNATIVE_CORRELATION`` from the two-term fit) at a condition where the
  chosen term is present, with the experiment that separates them (:func:`.select._separating`); a rival
  passed over for its law only while it fits at least as well (:func:`.select.preferred_by_fit`). Each is
  a :class:`.select.Alternative`, said in the verdict by :func:`.caveats.alternatives_text`, as diagnose
  says its own.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Optional

from . import across_dc
from .across_verdict import summed, tied
from .select import (
    ALTERNATIVE_CORRELATION,
    ALTERNATIVE_IMPROVEMENT,
    LAW_ALPHA,
    Alternative,
    _correlation,
    _place_separation,
    _separating,
    at_null,
    dof_of,
    element_law_test,
    limit_first,
    place_admissible,
    pooled_f,
    preferred_by_fit,
    siblings,
)

#: Tail probability of the place rule's chi-square point (select.PLACE_CHI2 is chi-square(1)'s).
PLACE_LEVEL = 0.05


def _fitted(tr: Any) -> bool:
    return bool(tr.fits) and all(f is not None for f in tr.fits)


def simpler_first(groups: Sequence[Any], order: list[Any], level: float) -> list[Any]:
    """``order`` (the passed joint trials, best first) with the simpler limit of a two-term element first
    unless the element beats it by the pooled F test of its extra parameter at ``level`` (the step's
    Bonferroni level, as the candidates' own tests): :func:`.select.simpler_first`'s rule."""

    def beats(simpler: Any, best: Any) -> bool:
        if not (_fitted(simpler) and _fitted(best)):
            return True  # not comparable: the order stands
        q = len(best.fits[0].params.terms) - len(simpler.fits[0].params.terms)
        imp = [a.cost - b.cost for a, b in zip(simpler.fits, best.fits)]
        d1 = [dof_of(g.sx, f) for g, f in zip(groups, best.fits)]
        _, p = pooled_f(imp, [f.cost for f in best.fits], d1, q)
        return p < level

    return limit_first(order, beats)


def law_p(groups: Sequence[Any], tr: Any, present: Sequence[bool]) -> float:
    """The law p of ``tr`` (:func:`.select.element_law_test`) at each condition where it is ``present``,
    Bonferroni over them; NaN where none could be tested."""
    laws = []
    for g, f, pr in zip(groups, tr.fits, present):
        if pr and f is not None:
            with across_dc.between(g):  # each experiment's DC free under a noise coloured at the DC
                laws.append(element_law_test(g.sx, f, tr.term, g.substeps))
    laws = [v for v in laws if math.isfinite(v)]
    return min(1.0, min(laws) * len(laws)) if laws else math.nan


def _s2(groups: Sequence[Any], chosen: Any) -> float:
    """The chosen structure's pooled chi2/dof, at least 1 (a misfit elsewhere inflates every cost
    difference)."""
    dof = sum(dof_of(g.sx, f) for g, f in zip(groups, chosen.fits))
    return max(1.0, sum(f.cost for f in chosen.fits) / dof) if dof > 0 else 1.0


def _rho(groups: Sequence[Any], chosen: Any, rival: str, present: Sequence[bool]) -> float:
    """The correlation of the chosen term's and the rival's values from their two-term fit, the largest
    in size over the conditions where the chosen term is present (NaN: no two-term fit)."""
    best = math.nan
    for g, f, pr in zip(groups, chosen.fits, present):
        if not pr:
            continue
        both = g.fit_term(f, rival)
        rho = _correlation(both, chosen.term, rival) if both is not None else math.nan
        if math.isfinite(rho) and not abs(rho) <= abs(best):
            best = rho
    return best


def _first_present(groups: Sequence[Any], present: Sequence[bool]) -> int:
    return next((k for k, pr in enumerate(present) if pr), 0)


def _places(
    groups: Sequence[Any],
    chosen: Any,
    by_term: dict[str, Any],
    law_failed: Sequence[str],
    preferred: Any,
    unphysical: Optional[list[str]] = None,
) -> list[Alternative]:
    """The chosen term at its other places that the conditions cannot tell from it (module docstring): a
    sibling with a physical value, not its null, at every condition where the chosen term is present
    (:func:`.select.place_admissible`); one that would be an alternative but for a non-physical value is
    appended to ``unphysical`` (said in the verdict)."""
    from scipy.special import chdtri  # type: ignore[import-untyped]

    present = chosen.present
    k = _first_present(groups, present)
    g = groups[k]
    crit = float(chdtri(len(groups), PLACE_LEVEL)) * _s2(groups, chosen)

    def sep() -> str:  # what separates the places, at the first condition where the term is present
        return f"at {g.label}: " + _place_separation(g.sx, chosen.fits[k], chosen.term)

    out = []
    for rival in siblings(chosen.term):
        tr = by_term.get(rival)
        if tr is None or not _fitted(tr):
            continue
        where = [f for f, pr in zip(tr.fits, present) if pr]
        if not place_admissible(where, rival):  # a negative damping is no reading of the data
            close = sum(f.cost for f in tr.fits) - sum(f.cost for f in chosen.fits) < crit
            if unphysical is not None and close and not any(at_null(f, rival) for f in where):
                unphysical.append(rival)
            continue
        if rival in preferred:  # passed over for its law only, while it fits at least as well
            rho = _rho(groups, chosen, rival, present)
            out.append(Alternative(chosen.term, rival, rho, sep(), preferred[rival]))
            continue
        if rival in law_failed or sum(f.cost for f in tr.fits) - sum(f.cost for f in chosen.fits) >= crit:
            continue
        lp = tr.law_p_value if math.isfinite(tr.law_p_value) else law_p(groups, tr, tr.present or present)
        if math.isfinite(lp) and lp < LAW_ALPHA:  # a value that differs between a condition's experiments
            continue
        out.append(Alternative(chosen.term, rival, _rho(groups, chosen, rival, present), sep()))
    return out


def alternatives(
    groups: Sequence[Any],
    chosen: Any,
    trials: Sequence[Any],
    order: Sequence[Any],
    law_failed: Sequence[str],
    unphysical: Optional[list[str]] = None,
) -> tuple[Alternative, ...]:
    """The alternatives of a joint step's chosen trial (module docstring; :func:`.select.step_alternatives`'s
    rules on the conditions' sums). ``trials``: the step's trials with their law p; ``order``: the passed
    ones, best first; ``unphysical`` collects the other places that fit as well only with a non-physical
    value (:func:`_places`)."""
    if chosen is None or not _fitted(chosen):
        return ()
    preferred = preferred_by_fit(summed(chosen), [summed(t) for t in trials if _fitted(t)], law_failed)
    by_term = {t.term: t for t in trials}
    out = _places(groups, chosen, by_term, law_failed, preferred, unphysical)
    best = sum(chosen.improvements)
    for tr in order:
        if tr.term == chosen.term or not _fitted(tr) or tr.term in siblings(chosen.term):
            continue
        if tr.term in law_failed and tr.term not in preferred:  # its value differs: not a rival reading
            continue
        close = tr.term in preferred or tied(groups, chosen, tr)
        if sum(tr.improvements) < ALTERNATIVE_IMPROVEMENT * best and not close:
            continue
        rho = _rho(groups, chosen, tr.term, chosen.present)
        if close or (math.isfinite(rho) and abs(rho) >= ALTERNATIVE_CORRELATION):
            # Where the two readings' improvements differ most, the data come closest to separating them.
            k = max(range(len(groups)), key=lambda i: abs(chosen.improvements[i] - tr.improvements[i]))
            g, fa, fb = groups[k], chosen.fits[k], tr.fits[k]
            sep = f"at {g.label}: " + _separating(g.sx, fa, fb, g.substeps)
            out.append(Alternative(chosen.term, tr.term, rho, sep, preferred.get(tr.term, math.nan)))
    return tuple(out)


__all__ = ["pooled_f", "simpler_first", "law_p", "alternatives", "PLACE_LEVEL"]

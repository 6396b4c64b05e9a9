"""The single-group diagnosis's verdict rules, applied to the diagnosis across conditions (issue 18).

The house must say the same thing whichever path the user takes. :func:`.run.diagnose`'s verdict follows
rules that :func:`.across.diagnose_across` did not apply; here they are applied to the joint structure
through the same functions (no copies):

- **honest status** (:func:`.run.classify`): "explained" only when the final structure passes its adequacy
  test (here: at every condition); named terms that remove less than ``PARTLY_EXPLAINED_FRACTION`` of the
  plain model's excess (summed over the conditions) while the structure still fails leave the structure
  "unexplained" and are reported as tested, not named (``AcrossDiagnosis.partial``);
- **non-physical values are not named** (:func:`.run._unphysical_text`): a term whose value lies outside its
  physical range at a condition where it is present stands in for physics the library places elsewhere;
- **law-failed candidates are said** (:func:`.run._law_text`): a candidate that fits part of the misfit
  with values that differ between a condition's experiments is a stand-in, named in the verdict as such;
- **a term refused beside Dahl's element is said** (:func:`.beside.text`);
- **Dahl's and play's caveats** (:func:`.caveats.family_text`, with every condition's latent levels as its
  final model sees them, as diagnose reads its final fit's), and a spring on x's **Masing caveat** with an
  experiment below saturation measured as diagnose measures it (:func:`.caveats.masing_separation` at each
  condition where the spring is present, :func:`.caveats.joint_separation` over them);
- a viscous damping's **rate caveat** (:func:`.across_rate.text`: the per-level test of
  :mod:`.rate_rival` at each condition where it is present);
- **"law untested"** (:func:`.law_untested.across_text`): a named term carried by fewer than two of a
  condition's experiments where it is present;
- a loop-shape term's **one-amplitude caveat** (:func:`.one_amplitude.across_text`): named when at no
  condition a frequency carries two distinct amplitudes;
- **a rival within the uncertainty of the chosen term's improvement is a near-tied reading**
  (:func:`tied`, through :func:`.select._tied` on the improvements and costs summed over the conditions).

The selection's own rules (the element's law with its branch shape and pinching's band,
:func:`.select.element_law_test`; a term at its null value is no candidate, :func:`.select.at_null`; only
beside Dahl with an effect of its own, :func:`.beside.only_beside`) are applied in :mod:`.across`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from ..terms import TERMS, Play, StiffnessX
from . import (
    across_bounds,
    across_rate,
    across_twin,
    adequacy,
    beside,
    beyond_range,
    bounds_said,
    final_terms,
    gate,
    law_untested,
    one_amplitude,
)
from .across_adequacy import chi2 as chi2
from .across_adequacy import p_of as p_of
from .caveats import family_text, joint_separation, latent_levels, masing_separation, unphysical_places_text
from .result import NamedTerm, Status
from .select import ALPHA, Trial, _tied, dof_of


def explained_fraction(groups: Sequence[Any]) -> float:
    """The share of the plain models' excess (``C - dof``, summed over the conditions) the joint structure
    removes, capped at 1: :func:`.gate.explained_fraction`, as :func:`.run._explained_fraction` for one
    group."""
    return gate.explained_fraction((g.plain.cost, dof_of(g.sx, g.plain), g.current.cost) for g in groups)


def partly_text(groups: Sequence[Any], alpha: float) -> str:
    """The "explained in part" clause: what the share is of (the plain models' excess over the noise floor,
    summed over the conditions: :func:`explained_fraction`) and what remains (the conditions where the
    joint structure fails its adequacy test). Before, "explained in part (100 % of the summed excess)" read
    as a contradiction (review 32): the summed share is capped at 100 % while a condition still fails."""
    fails = [(g, p) for g in groups if not ((p := p_of(g, g.current)) >= alpha)]
    rest = ", ".join(f"condition {g.label} (p = {p:.2g})" for g, p in fails)
    left = f"; what remains fails the adequacy test at {rest}" if rest else ""
    share = explained_fraction(groups)
    below = [str(g.label) for g in groups if g.current.cost < dof_of(g.sx, g.current)]
    if rest and below and round(100 * share) >= 100:  # the sum hides what remains: say why
        left += (
            f" (the share is of the sum: below their noise floor at condition{'s' * (len(below) > 1)} "
            f"{', '.join(below)}, the fits "
            "there offset what remains)"
        )
    return (
        f"; explained in part: the joint structure removes {100 * share:.0f} % of the "
        f"plain models' excess over the noise floor, summed over the conditions{left}"
    )


def plain_gate(groups: Sequence[Any], alpha: float) -> tuple[bool, bool]:
    """``(passes, targeted)``: :func:`.run.diagnose`'s gate at every condition (:func:`.gate.plain_gate`:
    :func:`.gate.plain_passes` at ``alpha / 2`` with the condition's ``moved``, the loop drifting on its
    plain model) and whether the targeted step runs (every condition's noise floor measured noise)."""
    return gate.plain_gate(
        [p_of(g, g.plain) for g in groups],
        alpha,
        [getattr(g, "moved", False) for g in groups],
        [getattr(g, "measured_noise", True) for g in groups],
    )


def plain_adequate(groups: Sequence[Any], terms: Sequence[Any], steps: Sequence[Any], alpha: float) -> bool:
    """:func:`.run.diagnose`'s gate at every condition (:func:`plain_gate`) and its rule on what was added or
    refused (:func:`.gate.plain_adequate`: no term, no law-failed candidate)."""
    return gate.plain_adequate(plain_gate(groups, alpha)[0], bool(terms), steps)


def final_adequate(groups: Sequence[Any], alpha: float) -> bool:
    """Whether the final model (named terms) passes its adequacy test (:func:`.adequacy.passes`, the one rule
    diagnose's status uses) at every condition."""
    return all(adequacy.passes(p_of(g, g.current), alpha, named=True) for g in groups)


def unphysical(terms: Sequence[Any], clearly: bool = True) -> list[NamedTerm]:
    """Each term (a :class:`.across.TermAcross`) with a value outside its physical range by more than its
    uncertainty (:func:`.beyond_range.clearly_outside`) where it is present, as the :class:`NamedTerm` of its
    first such condition (for :func:`.run._unphysical_text`); ``clearly`` False: the terms outside their range
    where present only within their uncertainty (:func:`.beyond_range.within`; for
    :func:`.beyond_range.text`), not named either."""
    out = []
    for t in terms:
        rows = [(v, se) for v, se, pr in zip(t.values, t.standard_errors, t.present) if pr]
        beyond = [(v, se) for v, se in rows if beyond_range.clearly_outside(t.term, v, se)]
        near = [(v, se) for v, se in rows if beyond_range.within(t.term, v, se)]
        hit = beyond if clearly else ([] if beyond else near)
        if hit:
            out.append(NamedTerm(t.term, t.symbol, hit[0][0], hit[0][1], t.unit))
    return out


def judged(
    groups: Sequence[Any], terms: Sequence[Any], alpha: float, steps: Sequence[Any] = ()
) -> tuple[Status, list[Any], list[Any]]:
    """``(status, named, partial)`` of the joint structure by :func:`.run.classify` on
    :func:`plain_adequate` (``steps``: the joint selection's, whose law-failed candidates refuse "adequate")
    and :func:`.run._judged`'s rule on non-physical values (module docstring)."""
    from .run import classify

    bad = {t.term for t in unphysical(terms)}
    faint = {t.term for t in unphysical(terms, clearly=False)}  # not named, no demotion (beyond_range.py)
    status = classify(
        plain_adequate(groups, terms, steps, alpha),
        bool(terms),
        final_adequate(groups, alpha),
        explained_fraction(groups),
    )
    if bad and status == "explained":
        status = "partly explained"
    if status != "adequate" and across_bounds.demotes(across_bounds.found(groups, steps), bool(terms)):
        status = "unexplained"  # a candidate beyond its range removes clearly more (across_bounds.py)
    if status != "adequate" and bounds_said.targeted_across(groups, steps):  # mu held at its lower end
        status = "unexplained"  # on the targeted path: stand-ins for a softer loop (bounds_said.py)
    named = (
        [t for t in terms if t.term not in bad | faint] if status in ("explained", "partly explained") else []
    )
    if not named and status != "adequate":
        status = "unexplained"
    return status, named, [t for t in terms if t not in named]


def summed(tr: Any) -> Trial:
    """A joint trial as the single-group :class:`.select.Trial` :func:`.select._tied` and
    :func:`.select.preferred_by_fit` read: its cost and improvement summed over the conditions, its law p
    (the first condition's fit stands for "fitted")."""
    cost = sum(f.cost for f in tr.fits) if all(f is not None for f in tr.fits) else math.nan
    nan = math.nan
    t = Trial(tr.term, cost, sum(tr.improvements), nan, nan, nan, nan, tr.passed, fit=tr.fits[0])
    return replace(t, law_p_value=getattr(tr, "law_p_value", nan))


def tied(groups: Sequence[Any], chosen: Any, rival: Any) -> bool:
    """Whether ``rival``'s summed improvement is within the uncertainty of ``chosen``'s (:func:`.select._tied`
    on the sums: ``2 sqrt(Delta C s2)``, ``s2`` the chosen structure's pooled chi2/dof when above 1)."""
    if any(f is None for f in (*chosen.fits, *rival.fits)):
        return False
    dof = sum(dof_of(g.sx, f) for g, f in zip(groups, chosen.fits))
    return _tied(summed(chosen), summed(rival), dof)


#: The status words when the joint structure leaves structure unexplained (as :func:`.run._verdict` says it).
UNEXPLAINED = "unexplained structure remains"


#: Where the misfit was found when the targeted step's terms are stand-ins (:func:`head`'s ``soft``).
_FOUND = bounds_said.TARGETED_BODY.removesuffix(" (the terms below)")


def head(status: Status, partial: Sequence[Any], n: int, fraction: float, soft: bool = False) -> str:
    """The verdict's opening when nothing is named: "adequate" as :func:`.run._verdict` says it, or the
    structure "unexplained" with the tested terms that lie in their physical range (as :func:`.run._judged`:
    a non-physical one is said by its own clause, :func:`clauses`, not among the tested terms)."""
    if status == "adequate":
        return f"across {n} conditions: {gate.ADEQUATE} at every condition"
    bad = {t.term for t in (*unphysical(partial), *unphysical(partial, clearly=False))}
    what = ", ".join(t.label for t in partial if t.term not in bad)
    if soft:  # bounds_said.targeted_across: no excess to share out, the loop's shape leads
        return (
            f"across {n} conditions: {bounds_said.SOFT_HEAD} {bounds_said.SOFTER}, a shape outside the model "
            f"(mu held at the lower end of its bracket at every condition); {_FOUND}"
            + (f" (tested terms {what}: fitted with mu held there, not named)" if what else "")
        )
    tail = (
        f" (tested terms {what} remove {100 * fraction:.0f} % of the summed excess but leave structure the "
        "library does not model; not named)"
        if what
        else ""
    )
    return f"across {n} conditions: {UNEXPLAINED}{tail}"


def clauses(
    status: Status,
    named: Sequence[Any],
    partial: Sequence[Any],
    steps: Sequence[Any],
    groups: Sequence[Any],
    alpha: float = ALPHA,
) -> str:
    """What the single-group verdict says beside its terms, said of the joint structure (module docstring)."""
    from .run import _law_text, _unphysical_text

    text = ""
    if status == "partly explained":
        text += partly_text(groups, alpha)
    text += bounds_said.across_text(groups, status) + _unphysical_text(unphysical(partial))
    text += beyond_range.text(unphysical(partial, clearly=False))
    text += _law_text(steps) + beside.text(steps)
    text += final_terms.text(steps, named)  # terms the final check dropped (across_final.py)
    as_said = [NamedTerm(t.term, t.symbol, math.nan, math.nan, t.unit) for t in named if t.term in TERMS]
    # another place that fits only non-physically, unless a physical twin stands for it (across_twin.py)
    twins = across_twin.twins(groups, steps, [t.term for t in named], separate=False)
    text += unphysical_places_text(across_twin.filtered(groups, steps, twins), as_said)
    text += law_untested.across_text(named, [(str(g.label), g.exps) for g in groups])
    text += one_amplitude.across_text(named, [g.exps for g in groups])  # a loop-shape term, one amplitude
    # Play's and the spring on x's caveats hang on whether every experiment saturates where the term acts:
    # a condition where it is absent says nothing of it (a spring on x present only at a saturating
    # condition lost its Masing caveat to the other condition's levels below saturation).
    own = {Play.kind, StiffnessX.kind}
    for t in named:
        if t.term in own:
            one = [NamedTerm(t.term, t.symbol, math.nan, math.nan, t.unit)]
            masing = _masing(named, groups, alpha) if t.term == StiffnessX.kind else (None, "")
            text += family_text(one, _levels(groups, t.present or [True] * len(groups)), *masing)
    rest = [NamedTerm(t.term, t.symbol, math.nan, math.nan, t.unit) for t in named if t.term in TERMS]
    rest = [t for t in rest if t.term not in own]
    text += family_text(rest, _levels(groups, [True] * len(groups)))
    return text + across_rate.text(named, groups)  # a viscous damping's rate caveat (rate_rival.py)


def _levels(groups: Sequence[Any], present: Sequence[bool]) -> list[float]:
    """The latent levels (:func:`.caveats.latent_levels`, final models) of the experiments at the conditions
    where ``present`` holds."""
    return [v for g, pr in zip(groups, present) if pr for v in latent_levels(g.sx, g.current)]


def _masing(named: Sequence[Any], groups: Sequence[Any], alpha: float) -> tuple[Any, str]:
    """``(sep, where)`` for the Masing caveat (:func:`.caveats.joint_separation` over the conditions where
    a named spring on x is present, each by :func:`.caveats.masing_separation` on its final model, as
    diagnose measures its one design)."""
    spring = next((t for t in named if t.term == StiffnessX.kind), None)
    if spring is None:
        return None, ""
    as_named = [NamedTerm(spring.term, spring.symbol, math.nan, math.nan, spring.unit)]
    seps = [
        (str(g.label), masing_separation(as_named, g.sx, g.current, g.exps, alpha, g.substeps))
        for g, pr in zip(groups, spring.present)
        if pr
    ]
    where, sep = joint_separation(seps)
    # Every condition where the spring is present saturating: no measure, and the caveat names them.
    return sep, where if sep is not None else ", ".join(w for w, _ in seps)


def gate_notes(prepared: Sequence[Any], alpha: float) -> tuple[str, ...]:
    """Why the targeted step was not run (gate.NO_TARGETED_STEP, as diagnose notes it), naming the
    conditions whose noise floor is not measured noise."""
    passes, targeted = plain_gate(prepared, alpha)
    if not passes or targeted:
        return ()
    where = ", ".join(str(g.label) for g in prepared if not g.measured_noise)
    return (f"{where}: {gate.NO_TARGETED_STEP}",)


__all__ = [
    "gate_notes",
    "p_of",
    "chi2",
    "final_adequate",
    "summed",
    "explained_fraction",
    "partly_text",
    "plain_adequate",
    "plain_gate",
    "judged",
    "head",
    "clauses",
    "unphysical",
    "tied",
]

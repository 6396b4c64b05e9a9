"""The pair step across conditions: :func:`.pairs.pair_step`'s rules on the joint structure (issue 18).

:func:`.run.diagnose` tries two or three library terms at once where a step names nothing while some
candidate's law failed (pairs.py: two terms missing at once, each alone absorbing part of the other with a
value that differs between experiments). :func:`.across.diagnose_across` ran no such step, so a level's own
diagnosis could name "viscous damping with play" where the joint structure said "unexplained" with both
law-failed: a contradiction the user could not explain. The joint selection now runs the same step, by the
same code (:func:`.pairs.pair_step`), where its step names nothing while some candidate's law failed (never
its targeted first step), each set added at every condition at once. :class:`JointRules` is what the pair
rules read (:class:`.pairs.Rules`), over the conditions:

- a set's fit is its fit at every condition (:class:`JointFit`: the costs summed);
- its degrees of freedom and F tests are pooled (the joint path's F, :func:`.across_rules.pooled_f`: the
  summed improvement over ``q K`` parameters for ``K`` conditions, over the pooled residual variance);
- a member must lie in its physical range at every condition (the conservative side of the joint
  selection's "wherever present": presence per member is judged after the set is named) and away from its
  null at some condition, not at its null at every one;
- its law is tested at every condition, Bonferroni over them (:func:`.across_rules.law_p`);
- the held-out cost is summed over the conditions (each condition's leave-one-experiment-out folds);
- the separating experiment is the first condition's where the two fits differ.

A set named so joins the joint structure as diagnose's named set joins its model: each member reported per
condition (its value, and whether it is needed there on its own evidence: its F test given the other
members at that condition, at ``alpha / K``), and the verdict's clause is diagnose's (:func:`.pairs.text`;
:func:`.pairs.refusal_text` where the sets were refused).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from types import SimpleNamespace
from typing import Any, Optional

from ..augmented import AugFit
from . import across_rules, pairs
from .fitting import at_a_limit
from .select import (
    HeldOut,
    Trial,
    _admissible,
    _separating,
    at_null,
    away_from_null,
    dof_of,
    f_test,
    held_out,
)


@dataclass(frozen=True)
class JointFit:
    """One set of terms fitted at every condition: what the pair rules read as one fit."""

    fits: tuple[AugFit, ...]

    @property
    def cost(self) -> float:
        return float(sum(f.cost for f in self.fits))

    @property
    def params(self) -> Any:  # the terms (the same at every condition) are what the rules read of it
        return self.fits[0].params


class JointRules(pairs.Rules):
    """:class:`.pairs.Rules` over the conditions ``groups`` (across.py's): module docstring."""

    def __init__(self, groups: Sequence[Any]) -> None:
        super().__init__([], 1, None)
        self.groups = list(groups)
        self.per_set = len(self.groups)

    def dof(self, fit: Any) -> int:
        return sum(dof_of(g.sx, f) for g, f in zip(self.groups, fit.fits))

    def physical(self, fit: Any, term: str) -> bool:
        return all(_admissible(f, term) for f in fit.fits) and not all(at_null(f, term) for f in fit.fits)

    def at_limit(self, fit: Any, term: str) -> bool:
        """At its spring or dry-friction limit at some condition (:meth:`.pairs.Rules.at_limit`)."""
        return any(at_a_limit(g.sx, f, term) for g, f in zip(self.groups, fit.fits))

    def away(self, fit: Any, term: str, level: float, s2: float) -> bool:
        return any(
            away_from_null(f, term, level, f.cost / max(dof_of(g.sx, f), 1))
            for g, f in zip(self.groups, fit.fits)
        )

    def law(self, fit: Any, term: str) -> float:
        one = SimpleNamespace(term=term, fits=fit.fits)
        return across_rules.law_p(self.groups, one, [True] * len(self.groups))

    def held_out(self, before: Any, after: Any) -> Optional[HeldOut]:
        parts = [
            held_out(g.sx, b, a, g.substeps, g.cache) for g, b, a in zip(self.groups, before.fits, after.fits)
        ]
        done = [h for h in parts if h is not None]
        if not done:
            return None
        return HeldOut(*(tuple(v for h in done for v in getattr(h, k)) for k in HeldOut.__dataclass_fields__))

    def separating(self, a: Any, b: Any) -> str:
        for g, fa, fb in zip(self.groups, a.fits, b.fits):
            sep = _separating(g.sx, fa, fb, g.substeps)
            if sep:
                return f"at {g.label}: {sep}"
        return ""

    def fitter(self) -> Any:
        """The one-term fit across: :meth:`fit_term` (each condition's memo of the selection)."""
        return self.fit_term

    def fit_term(self, fit: Any, term: str) -> Optional[JointFit]:
        """``term`` added at every condition (each condition's memoised one-term fit), or None where it
        cannot stand at some condition."""
        fits = [g.fit_term(f, term) for g, f in zip(self.groups, fit.fits)]
        done = [f for f in fits if f is not None]
        return JointFit(tuple(done)) if len(done) == len(fits) else None


def _as_trial(tr: Any) -> Trial:
    """A joint trial as the :class:`.select.Trial` the pair rules read (its fits as a :class:`JointFit`)."""
    fitted = bool(tr.fits) and all(f is not None for f in tr.fits)
    jf: Any = JointFit(tuple(tr.fits)) if fitted else None
    cost = jf.cost if fitted else math.nan
    t = Trial(
        tr.term, cost, sum(tr.improvements), tr.statistic, tr.p_value, tr.p_adjusted, tr.share, tr.passed
    )
    return replace(t, fit=jf, law_p_value=tr.law_p_value)


def _member(
    groups: Sequence[Any], fit: JointFit, term: str, terms: Sequence[str], alpha: float, like: Any
) -> Any:
    """Member ``term`` of a named set as a joint trial (``like``'s class): the set's fits, and at each
    condition its F test given the other members (the model of the others, refitted from the step's)."""
    p_each: list[float] = []
    for g, f in zip(groups, fit.fits):
        other: Optional[AugFit] = g.current
        for t in terms:
            if t != term and other is not None:
                other = g.fit_term(other, t)
        if other is None:
            p_each.append(math.nan)
            continue
        q = max(len(f.params.terms) - len(other.params.terms), 1)
        p_each.append(f_test(other.cost, f.cost, dof_of(g.sx, f), q=q)[1])
    k = len(groups)
    imp = tuple(g.current.cost - f.cost for g, f in zip(groups, fit.fits))
    present = tuple(math.isfinite(p) and p < alpha / k for p in p_each)
    nan = math.nan
    return like(term, nan, nan, nan, nan, imp, tuple(p_each), True, fits=fit.fits, present=present)


def step(groups: Sequence[Any], st: Any, n_cands: int, alpha: float, use_held_out: bool, like: Any) -> Any:
    """The joint step ``st`` (across.JointStep) with the pair step's set where ``st`` named nothing while
    some candidate's law failed and it was not the targeted first step (module docstring): the set named
    (``pair``, its members' joint trials in ``members``, its rivals as alternatives), or the sets tried and
    why they were refused (``pairs``); ``like``: the joint trial's class. The step keeps the model it started
    from (``base``: the revisits', across_revisit.py)."""
    st = replace(st, base=JointFit(tuple(g.current for g in groups)))  # the step's model (the revisits')
    if not pairs.ENABLED or st.chosen is not None or not st.law_failed or st.targeted:
        return st
    rules = JointRules(groups)
    tested = [_as_trial(tr) for tr in st.trials]
    order = sorted((t for t in tested if t.passed and t.fit is not None), key=lambda t: t.cost)
    current = JointFit(tuple(g.current for g in groups))
    cache = None
    choice, tried = pairs.pair_step(
        rules, current, order, tested, st.beside, rules.fit_term, 1, st.level, n_cands, use_held_out, cache
    )
    if choice is None or not isinstance(choice.trial.fit, JointFit):
        return replace(st, pairs=tried)
    fit = choice.trial.fit
    members = tuple(_member(groups, fit, t, choice.terms, alpha, like) for t in choice.terms)
    return replace(
        st,
        chosen=choice.terms[0],
        alternatives=tuple(choice.alternatives),
        law_failed=tuple(choice.unnamed(st.law_failed)),
        pair=choice.terms,
        pairs=tried,
        members=members,
    )


__all__ = ["JointFit", "JointRules", "step"]

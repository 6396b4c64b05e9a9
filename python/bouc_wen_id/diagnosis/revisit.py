"""A named single term revisited when a later step points past it (issue 18).

The forward selection never takes back a name. Two library terms at once can be named wrong: stiffness and
viscous damping both on u through a G without delay (1/G a polynomial, so ``(k + c s) G^-1 x`` is nearly a
viscous term on x, the per-experiment free |G| and phase absorbing the rest) make viscous damping on x pass
its law at step 1 while each true term fails alone; at step 2 viscous damping on u removes most of what is
left but fails its law beside the wrong term, and the verdict is "explained in part" by the wrong name.

The revisit runs only there: the final model fails adequacy, the last step named nothing, and a step after the
last named single term had as its best candidate (lowest cost of those that passed their own tests) one that
removes at least :data:`SHARE` of the excess left but failed its law alone (that step may then have named a
set with it: seed 1 of the same plant named viscous on x, then viscous on u with stiffness and inertia on x,
99 % of the excess and still not adequate). The model before the last named single term (step ``j``; later
steps may only have named sets) is taken again and the pair/triple step (:func:`.pairs.pair_step`, the same
rules: each member significant given the others, every law holding jointly, held-out cost lower than that
model's) is run on the candidates that could replace the named term: its alternatives, the law-failed
candidates of step ``j`` and of the last step, the members of sets named after ``j``, never the named term
itself; the best :data:`POOL` by their cost at step ``j`` in pairs with each other, the best with the rest. A
set found so is

- **named in the named term's place** when it also passes adequacy (the model after it is tenable where the
  named term's is not) and its held-out cost is lower than the named term's; the named term is then said as
  the rival with the experiment that would separate the two (a G with a delay, or frequencies where 1/G is
  far from a polynomial);
- otherwise **reported as an alternative** (both tenable as far as the laws go) with that experiment.

Physics outside the library is left alone by construction: the revisit needs a named term (an
"unexplained" verdict has none) and a set whose laws all hold and whose model passes adequacy before it
changes a name.

The experiments are read through :class:`.pairs.Rules` (held-out costs, separating experiment, the one-term
fit): :func:`.across.diagnose_across` runs the same functions on its joint steps with the conditions' rules
(:mod:`.across_revisit`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS
from . import pairs
from .gate import targeted_level
from .select import (
    ALPHA,
    FoldCache,
    HeldOut,
    Step,
    Trial,
    forward_select,
)

#: Whether the revisit runs (module docstring).
ENABLED = True
#: The best this many candidates (by cost at the revisited step) are paired with each other (at most 15
#: pair fits, only where the revisit runs); the best of them with the rest.
POOL = 6
#: The last step's best candidate must remove at least this share of the excess left ("most of it").
SHARE = 0.5


@dataclass(frozen=True)
class Revisit:
    """The revisit of a named single term: the set tried in its place and what came of it."""

    replaced: str
    #: The candidates the pair step was run on (module docstring).
    pool: tuple[str, ...]
    #: The set that passed the pair rules (empty: none did).
    terms: tuple[str, ...]
    #: "named" (in the named term's place), "alternative", or why no set was found / kept.
    outcome: str
    held_out_set: float = math.nan
    held_out_single: float = math.nan
    separating_experiment: str = ""
    tried: tuple[Any, ...] = field(default=(), compare=False)
    #: The members of the sets the selection named after ``replaced`` (replaced with it when named).
    later: tuple[str, ...] = ()
    #: Run for a rival that fit at least as well but failed its law alone (rival_revisit.py), not a lead.
    by_rival: bool = False

    @property
    def refused(self) -> str:
        """As a :class:`.pairs.PairTrial`'s (both sit in ``Step.pairs``): "" when the set was named."""
        return "" if self.outcome == "named" else self.outcome

    def to_dict(self) -> dict[str, Any]:
        def n(v: float) -> Optional[float]:
            return v if math.isfinite(v) else None

        return {
            "revisit_of": self.replaced,
            "pool": list(self.pool),
            "terms": list(self.terms),
            "outcome": self.outcome,
            "held_out_set": n(self.held_out_set),
            "held_out_single": n(self.held_out_single),
            "separating_experiment": self.separating_experiment,
            "tried": [p.to_dict() for p in self.tried],
            "later": list(self.later),
            **({"by_rival": True} if self.by_rival else {}),
        }


def _ho(h: Optional[HeldOut]) -> float:
    return math.nan if h is None else float(sum(h.cost_after))


def _base(steps: Sequence[Step], j: int, plain: AugFit) -> Optional[AugFit]:
    """The model step ``j`` started from."""
    if steps[j].base is not None:
        return steps[j].base
    if j == 0:
        return plain
    prev = steps[j - 1]
    if prev.pair:
        return next((p.fit for p in prev.pairs if getattr(p, "terms", ()) == prev.pair), None)
    return next((tr.fit for tr in prev.trials if tr.term == prev.chosen), None)


def _leads(step: Any) -> list[Trial]:
    """A step's candidates that removed at least :data:`SHARE` of the excess left and failed their laws
    alone (also where the step then named a set of them: pairs.py), best first; empty unless the step's
    best candidate is one of them."""
    passed = sorted((tr for tr in step.trials if tr.passed and math.isfinite(tr.cost)), key=lambda t: t.cost)
    out = [tr for tr in passed if not tr.law_holds and tr.fit is not None and tr.share >= SHARE]
    return out if out and passed[0] is out[0] else []


def trigger(steps: Sequence[Any]) -> tuple[int, list[Trial]]:
    """``(j, leads)``: the step ``j`` of the last named single term (the steps between it and the last may
    only have named sets: pairs.py) and the later steps' leads (:func:`_leads`); no leads where the revisit
    does not run (module docstring; the final model's adequacy is the caller's to test)."""
    if not (ENABLED and pairs.ENABLED) or len(steps) < 2 or steps[-1].chosen is not None:
        return -1, []
    j = max((k for k, s in enumerate(steps) if s.chosen is not None and not s.pair), default=-1)
    return j, [tr for s in steps[j + 1 :] for tr in _leads(s)] if j >= 0 else []


def revisit(
    exps: Sequence[AugExperiment],
    plain: AugFit,
    final: AugFit,
    steps: list[Step],
    adequate: Callable[[AugFit], bool],
    substeps: int,
    alpha: float,
    use_held_out: bool = True,
    cache: Optional[FoldCache] = None,
) -> tuple[AugFit, list[Step]]:
    """``(final, steps)`` after the revisit of the last named single term (module docstring); unchanged
    where it does not run or finds no set."""
    j, leads = trigger(steps)
    if not leads or adequate(final):
        return final, steps
    last = steps[-1]
    st = steps[j]
    named = str(st.chosen)
    base = _base(steps, j, plain)
    if base is None or not math.isclose(base.cost, st.before_cost, rel_tol=1e-6, abs_tol=1e-6):
        return final, steps
    by = {tr.term: tr for tr in st.trials if tr.fit is not None and math.isfinite(tr.cost)}
    single = by.get(named)
    later = [t for s in steps[j + 1 :] for t in s.pair]  # members of the sets named after it
    # What could replace the named term: the later steps' leads and named members, its alternatives, step
    # j's and the last step's law-failed candidates; by cost at step j, the best POOL paired with each
    # other, the best with the rest.
    rivals = [a.rival for a in st.alternatives]  # the named term's own alternatives (a tie, a place)
    terms = dict.fromkeys((*(tr.term for tr in leads), *later, *rivals, *st.law_failed, *last.law_failed))
    cands = sorted((by[t] for t in terms if t in by and t != named), key=lambda t: t.cost)
    if single is None or single.fit is None:
        return final, steps
    order, rest = cands[:POOL], cands[POOL:]
    pool = tuple(t.term for t in cands)
    if len(pool) < 2:
        return final, steps
    level = targeted_level(alpha, st.after_named) if st.targeted else alpha
    rules = pairs._rules(exps, substeps, cache)  # one set of experiments, or several (across_revisit.py)
    choice, tried = pairs.pair_step(
        rules,
        base,
        order,
        rest,
        [],
        rules.fitter(),
        substeps,
        level,
        len(st.trials),
        use_held_out,
        cache,
        len(order),
        0.0,  # every candidate with the best: the revisit's own gate already asks a lead of SHARE
    )
    if choice is None or choice.trial.fit is None:
        best = next((p for p in sorted(tried, key=_cost) if p.refused), None)
        why = (
            "no set could be fitted"
            if best is None
            else f"the best-fitting, {' with '.join(TERMS[t].place_label() for t in best.terms)}, "
            f"was refused: {best.refused}"
        )
        rec = Revisit(named, pool, (), f"no set named: {why}", tried=tried)
        return final, [*steps[:j], replace(st, pairs=(*st.pairs, rec)), *steps[j + 1 :]]
    rec = Revisit(named, pool, choice.terms, "", later=tuple(later))
    return settle(
        exps, base, final, steps, j, single, choice, tried, rec, adequate, substeps, use_held_out, cache
    )


def settle(
    exps: Sequence[AugExperiment],
    base: AugFit,
    final: AugFit,
    steps: list[Step],
    j: int,
    single: Any,
    choice: Any,
    tried: Sequence[Any],
    rec: Revisit,
    adequate: Callable[[AugFit], bool],
    substeps: int,
    use_held_out: bool,
    cache: Optional[FoldCache],
) -> tuple[AugFit, list[Step]]:
    """A revisit's set ``choice`` (from ``base``, the model before step ``j``) against the named path
    (``single``, the step's own trial of the named term, and ``final``): named in the step's place when its
    model passes adequacy and predicts better held out, else recorded on the step as an alternative
    (``rec``: the revisit's record, its held-out costs and separating experiment filled in here). Shared by
    :func:`revisit` and :func:`.rival_revisit.revisit`; ``exps`` as :func:`.pairs.pair_step` takes them (the
    experiments, or the :class:`.pairs.Rules` they are read through: across_revisit.py)."""
    st = steps[j]
    fit = choice.trial.fit
    rules = pairs._rules(exps, substeps, cache)
    # The named path's model from the same base: the single, or the single and the sets after it.
    h_one = _ho(single.held_out if final is single.fit or not use_held_out else rules.held_out(base, final))
    h_set = _ho(choice.trial.held_out)
    better = h_set < h_one if use_held_out and math.isfinite(h_set + h_one) else fit.cost < final.cost
    sep = rules.separating(fit, final)
    tenable = adequate(fit)
    rec = replace(
        rec, held_out_set=h_set, held_out_single=h_one, separating_experiment=sep, tried=tuple(tried)
    )
    if not (tenable and better):
        why = "its model fails adequacy" if not tenable else "its held-out cost is not lower"
        rec = replace(rec, outcome=f"alternative ({why})")
        return final, [*steps[:j], replace(st, pairs=(*st.pairs, rec)), *steps[j + 1 :]]
    new = replace(
        st,
        chosen=choice.trial.term,
        alternatives=tuple(choice.alternatives),
        law_failed=tuple(choice.unnamed(st.law_failed)),
        pair=choice.terms,
        pairs=(*tried, replace(rec, outcome="named")),
    )
    return fit, [*steps[:j], new]


def select(
    exps: Sequence[AugExperiment],
    plain: AugFit,
    candidates: Sequence[str],
    adequate: Callable[[AugFit], bool],
    substeps: int,
    **kw: Any,
) -> tuple[AugFit, list[Step]]:
    """:func:`.select.forward_select` (same arguments), then :func:`revisit` of its result."""
    final, steps = forward_select(exps, plain, candidates, adequate, substeps, **kw)
    return after(exps, plain, final, steps, adequate, substeps, **kw)


def after(
    exps: Sequence[AugExperiment],
    plain: AugFit,
    final: AugFit,
    steps: list[Step],
    adequate: Callable[[AugFit], bool],
    substeps: int,
    **kw: Any,
) -> tuple[AugFit, list[Step]]:
    """:func:`revisit` of a selection already run (by :func:`.after_named.select`), with the selection's
    keywords ``kw`` (``alpha``, ``use_held_out``, ``cache``; the others unused)."""
    return revisit(
        exps, plain, final, steps, adequate, substeps, kw.get("alpha", ALPHA), kw.get("use_held_out", True),
        kw.get("cache"),
    )  # fmt: skip


def _cost(p: Any) -> float:
    c = float(getattr(p, "cost", math.nan))
    return c if math.isfinite(c) else math.inf


def records(steps: Sequence[Any]) -> list[Revisit]:
    return [p for st in steps for p in getattr(st, "pairs", ()) if isinstance(p, Revisit)]


def text(steps: Sequence[Any]) -> str:
    """The verdict's clause on a revisit: the set it named, one the data cannot refuse, or why none."""
    out = ""
    for r in records(steps):
        one = " then ".join(TERMS[t].place_label() for t in (r.replaced, *r.later))
        if not r.terms:  # the revisit ran and named nothing: said, with why (the pair rules' refusal)
            n = sum(1 for p in r.tried if math.isfinite(_cost(p)))
            out += f"; {one} revisited from the model before it ({n} sets of {len(r.pool)} candidates): "
            out += r.outcome
            continue
        both = " with ".join(TERMS[t].place_label() for t in r.terms)
        ho = (
            f"held-out cost {r.held_out_set:.1f} vs {r.held_out_single:.1f}"
            if math.isfinite(r.held_out_set + r.held_out_single)
            else "in-sample cost lower"
        )
        if r.by_rival:
            out += _rival_text(r, one, both, ho)
        elif r.outcome == "named":
            out += (
                f"; revisited: {one} (named first, its law held) left misfit that a later candidate removed "
                f"only with a value differing between experiments; {both}, jointly, hold their laws, pass "
                f"adequacy and predict better ({ho}): named in its place. {one} is the rival; the experiment "
                f"that would separate them: {r.separating_experiment}"
            )
        else:
            out += (
                f"; alternative to {one}: {both}, jointly, hold their laws (not named: {r.outcome[13:-1]}); "
                f"the experiment that would separate them: {r.separating_experiment}"
            )
    return out


def _rival_text(r: Revisit, one: str, both: str, ho: str) -> str:
    """The clause on a revisit run for a law-failed rival (rival_revisit.py)."""
    rival, first = TERMS[r.terms[0]].place_label(), TERMS[r.replaced].place_label()
    if r.outcome == "named":
        return (
            f"; revisited: {first} was named over {rival}, which fit at least as well but whose law failed "
            f"alone; {both}, jointly, hold their laws, pass adequacy and predict better ({ho}): named in its "
            f"place. {one} is the rival; the experiment that would separate them: {r.separating_experiment}"
        )
    costs = f"; {ho}" if ho.startswith("held-out") else ""  # the two models' held-out costs, when run
    return (
        f"; not the only reading: {both}, jointly, hold their laws in place of {one} (not named: "
        f"{r.outcome[13:-1]}{costs}); the experiment that would separate them: {r.separating_experiment}"
    )


__all__ = ["ENABLED", "POOL", "SHARE", "Revisit", "records", "revisit", "select", "text", "trigger"]

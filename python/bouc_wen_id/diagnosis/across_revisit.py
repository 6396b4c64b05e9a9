"""diagnose's two revisits of a named single term, run on the joint structure across conditions (issue 18).

:func:`.run.diagnose` revisits a named single term after its forward selection, by two rules that share
:func:`.revisit.settle`:

- the **revisit** (:mod:`.revisit`): the final model fails adequacy and a later step's best candidate removed
  most of what was left but failed its law; sets that could replace the named term are fitted from the model
  before it;
- the **rival revisit** (:mod:`.rival_revisit`): a rival that fit at least as well as the named term failed
  its law alone (review 33's mx_lag_30: inertia on x beside a sensor lag was named "viscous damping on u");
  the rival is paired with the step's other candidates from the same model.

:func:`.across.diagnose_across` ran neither, and said so in one clause where the first's trigger held: a
level's own diagnosis could name "inertia on x with sensor lag" while the joint structure said "viscous
damping on u" at every condition. Both now run on the joint steps, by the same functions
(:func:`.rival_revisit.after`, which runs :func:`.revisit.after` first), through the interfaces the pair step
already reads across (:class:`.across_pairs.JointRules`: dof and F tests pooled on ``q K`` parameters, laws
at every condition with Bonferroni, the held-out cost summed over the conditions, a set's members added by
each condition's memoised one-term fit):

- each joint step is shown to them as a :class:`.select.Step` (:func:`view`): its trials as
  :class:`.select.Trial` (costs summed over the conditions, the fits a :class:`.across_pairs.JointFit`, the
  held-out costs the joint trial's sums), its model before the step (``JointStep.base``), its targeted flags;
- "the model passes adequacy" is the joint structure's test: at every condition
  (:func:`.across_verdict.p_of` at ``alpha``, as the stop rule and the status judge it);
- a set named in a step's place joins the joint structure as the pair step's does (each member's joint trial,
  its presence per condition given the other members: :func:`.across_pairs._member`), the conditions'
  models become the set's, and the verdict's clause is diagnose's (:func:`.revisit.text`, through
  :func:`.run._law_text`); a set kept as an alternative is recorded on the step, as diagnose records it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from . import across_verdict, rival_revisit
from .across_pairs import JointFit, JointRules, _as_trial, _member
from .select import HeldOut, Step, Trial


def _trial(tr: Any) -> Trial:
    """A joint trial as a :class:`.select.Trial` (:func:`.across_pairs._as_trial`) with its held-out costs
    summed over the conditions (the revisits compare a set's with the named term's)."""
    t = _as_trial(tr)
    hb, ha = tr.held_out_before, tr.held_out_after
    if not math.isfinite(hb + ha):
        return t
    return replace(t, held_out=HeldOut((), (hb,), (ha,), (), ()))


def view(steps: Sequence[Any]) -> list[Step]:
    """The joint steps as the revisits read a selection's steps (module docstring). A step without its
    model (``base`` None) gets a NaN cost before it: no revisit runs from it."""
    out = []
    for j, st in enumerate(steps):
        before = st.base.cost if st.base is not None else math.nan
        out.append(
            Step(
                before,
                0,
                tuple(_trial(t) for t in st.trials),
                st.chosen,
                st.alternatives,
                st.targeted,
                st.law_failed,
                st.beside,
                st.unphysical_places,
                base=st.base,
                pair=st.pair,
                pairs=st.pairs,
                after_named=st.targeted and j > 0,  # after a named step the targeted one is at alpha / 10
            )
        )
    return out


def _final(groups: Sequence[Any], view_steps: Sequence[Step]) -> Any:
    """The conditions' current models as the trial's fit they came from (the named path's own fit: its
    held-out costs are the step's), else a new :class:`.across_pairs.JointFit` of them."""
    now = [g.current for g in groups]
    for st in view_steps:
        for f in (*(t.fit for t in st.trials), *(getattr(p, "fit", None) for p in st.pairs)):
            if isinstance(f, JointFit) and all(a is b for a, b in zip(f.fits, now)):
                return f
    return JointFit(tuple(now))


def after(groups: Sequence[Any], steps: list[Any], alpha: float, use_held_out: bool, like: Any) -> list[Any]:
    """The joint steps after diagnose's revisits (module docstring); the conditions' current models end at
    the final ones. ``like``: the joint trial's class (across.JointTrial)."""
    if not steps:
        return steps
    rules = JointRules(groups)
    seen = view(steps)

    def adequate(fit: Any) -> bool:
        ps = [across_verdict.p_of(g, f) for g, f in zip(groups, fit.fits)]
        return all(math.isfinite(p) and p >= alpha for p in ps)

    # The conditions read through JointRules, their models as JointFits (the revisits' types are one set's).
    exps: Any = rules
    plain: Any = JointFit(tuple(g.plain for g in groups))
    kw: dict[str, Any] = {"alpha": alpha, "use_held_out": use_held_out, "cache": None}
    final, done = rival_revisit.after(exps, plain, _final(groups, seen), seen, adequate, 1, **kw)
    out = []
    for st, old, new in zip(steps, seen, done):
        if new is old:
            out.append(st)
            continue
        st = replace(st, chosen=new.chosen, alternatives=new.alternatives, law_failed=new.law_failed,
                     pair=new.pair, pairs=new.pairs)  # fmt: skip
        if new.pair != old.pair and isinstance(final, JointFit):  # a set named in the step's place
            for g, b in zip(groups, st.base.fits):
                g.current = b  # each member's presence is tested from the step's model
            members = tuple(_member(groups, final, t, new.pair, alpha, like) for t in new.pair)
            st = replace(st, members=members, rivals=())
            for g, f in zip(groups, final.fits):
                g.current = f
        out.append(st)
    return out


__all__ = ["after", "view"]

"""A named single term revisited when a rival that fits at least as well failed its law (review 33).

A step names the best candidate whose law holds; a candidate that fits at least as well but whose value
differs between experiments is said as the named term's alternative (:func:`.select.preferred_by_fit`). Its
law can fail because a second library term sits beside it: the rival is the true physics and the named term
a stand-in that the free per-experiment |G| and phase let fit. Review 33's cases:

- inertia on x and a sensor lag, 30x each, two-pole G (mx_lag_30): inertia on x fits best at step 1 (cost
  664 against 678) but fails its law (p 0.0087, the lag beside it); viscous damping on u was named,
  "explained", the lag never mentioned;
- play and stiffness on u, two-pole G (play_ku): stiffness on u fails its law alone (p 0.0011, the play
  beside it), viscous damping on x (``k u`` through ``1/G``, a polynomial: its ``xdot`` part) passes at
  p 0.049 and was named; play at step 2; "explained by viscous damping on x, play".

The revisit (:mod:`.revisit`) covers a later lead that fails its law when the final model fails adequacy;
here the final model may pass. The model step ``j`` (the last named single term with such a rival) started
from is taken again and the pair/triple step (:func:`.pairs.pair_step`, its rules: each member significant
given the others, every law holding jointly, held-out cost lower than that model's) is run with the rivals
first, each paired with every other candidate of step ``j`` (never the named term). A set found so is

- **named in place** of the named term and the terms named after it when its model passes adequacy and its
  held-out cost is lower than that of the named path's final model (from the same base);
- otherwise **reported as an alternative** (:func:`.revisit.text`), with the experiment that would separate
  them: the verdict then says the named term is not the only tenable reading.

Where no set holds its laws the named term stays, with its rival said as before. The joint selection across
conditions runs it too, on its joint steps (:mod:`.across_revisit`).

Measured (review 33's simulator, ``/tmp/sm33/dbg.py``-style runs of ``/work/review33/run_case.py``'s cases):
mx_lag_30 now names inertia on x m = 0.01093 +- 0.00068 (true 0.01137) with the lag tau = 0.0609 +- 0.0069
(true 0.0559), held-out cost 713 against viscous damping on u's 777; play_ku names stiffness on u
k = 0.0328 +- 0.0011 (true 0.0327) with play b = 0.0162 (true 0.0160), held-out 930 against 1080. The
bench rows of main (session 32's /work/m32, ~600 rows) had one case where the trigger holds (Dahl seed
48001, Dahl on u named over Dahl on x at law p 0.0031): no set passed the pair rules there, and its verdict
is unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from . import pairs
from .gate import targeted_level
from .revisit import Revisit, _base, settle
from .revisit import after as lead_after
from .select import ALPHA, FoldCache, Step, forward_select

#: Whether this revisit runs (module docstring).
ENABLED = True


def trigger(steps: Sequence[Step]) -> tuple[int, tuple[str, ...]]:
    """``(j, rivals)``: the last step ``j`` that named a single term with a rival that fits at least as well
    but whose law failed (an alternative with a law p); ``(-1, ())`` where there is none."""
    if not (ENABLED and pairs.ENABLED):
        return -1, ()
    for j in range(len(steps) - 1, -1, -1):
        st = steps[j]
        if st.chosen is None or st.pair:
            continue
        rivals = tuple(dict.fromkeys(a.rival for a in st.alternatives if math.isfinite(a.law_p_value)))
        if rivals:
            return j, rivals
    return -1, ()


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
    """``(final, steps)`` after the revisit of a named single term with a law-failed rival that fits at
    least as well (module docstring); unchanged where it does not run."""
    j, rivals = trigger(steps)
    if j < 0:
        return final, steps
    st = steps[j]
    named = str(st.chosen)
    base = _base(steps, j, plain)
    if base is None or not math.isclose(base.cost, st.before_cost, rel_tol=1e-6, abs_tol=1e-6):
        return final, steps
    by = {tr.term: tr for tr in st.trials if tr.fit is not None and math.isfinite(tr.cost)}
    single = by.get(named)
    order = [by[t] for t in rivals if t in by]
    rest = sorted((tr for t, tr in by.items() if t != named and t not in rivals), key=lambda t: t.cost)
    if single is None or single.fit is None or not order or not rest:
        return final, steps
    later = tuple(str(s.chosen) for s in steps[j + 1 :] if s.chosen is not None and not s.pair)
    later += tuple(t for s in steps[j + 1 :] for t in s.pair)
    level = targeted_level(alpha, st.after_named) if st.targeted else alpha
    rules = pairs._rules(exps, substeps, cache)  # one set of experiments, or several (across_revisit.py)
    choice, tried = pairs.pair_step(
        rules, base, order, [*order, *rest], [], rules.fitter(), substeps, level,
        len(st.trials), use_held_out, cache, len(order), 0.0,
    )  # fmt: skip
    pool = tuple(t.term for t in (*order, *rest))
    if choice is None or choice.trial.fit is None:
        return final, steps  # no set holds its laws: the rival stays said as before
    rec = Revisit(named, pool, choice.terms, "", later=later, by_rival=True)
    return settle(
        exps, base, final, steps, j, single, choice, tried, rec, adequate, substeps, use_held_out, cache
    )


def after(
    exps: Sequence[AugExperiment],
    plain: AugFit,
    final: AugFit,
    steps: list[Step],
    adequate: Callable[[AugFit], bool],
    substeps: int,
    **kw: Any,
) -> tuple[AugFit, list[Step]]:
    """:func:`.revisit.after` (a later lead that failed its law), then :func:`revisit` (a law-failed rival)
    of a selection already run, with the selection's keywords ``kw``."""
    final, steps = lead_after(exps, plain, final, steps, adequate, substeps, **kw)
    args = (adequate, substeps, kw.get("alpha", ALPHA), kw.get("use_held_out", True), kw.get("cache"))
    return revisit(exps, plain, final, steps, *args)


def select(
    exps: Sequence[AugExperiment],
    plain: AugFit,
    candidates: Sequence[str],
    adequate: Callable[[AugFit], bool],
    substeps: int,
    **kw: Any,
) -> tuple[AugFit, list[Step]]:
    """:func:`.select.forward_select` (same arguments), then :func:`after`."""
    final, steps = forward_select(exps, plain, candidates, adequate, substeps, **kw)
    return after(exps, plain, final, steps, adequate, substeps, **kw)


__all__ = ["ENABLED", "after", "revisit", "select", "trigger"]

"""diagnose's final check of the named set (:mod:`.final_terms`), applied to the joint structure (issue 18).

A joint step names the best candidate given the terms named before it; a term named early can become unneeded
once later terms are named, as in one group. The isolator of tests/test_diagnosis_final_terms.py (a spring and
a damper on x, first-order G, the package's simulator) at two conditions named viscous damping on u at step 1
and kept it in the joint model at c = -0.00024 +- 0.0051 (said "not named" for its sign), and named a sensor
lag tau = 4.7e-19 +- 0.0082 s "explained": zero within its uncertainty, still in the headline.

The check is :func:`.final_terms.check`'s, the joint test in place of the single one: for each term a step
named (alone or in a pair) that is in the final model, the combined F test of dropping it (with its companion)
at every condition (:func:`.select.pooled_f` on the refits without it, as :func:`.final_terms.drop_p` refits
one group), Bonferroni over that step's candidates, at that step's level (``JointStep.level``, the level its
own combined F was tested at). The worst that fails is dropped at every condition, and the check repeats on
the rest; the dropped terms go on the last step (``JointStep.unneeded``) and the verdict says them by
:func:`.final_terms.text`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

from .final_terms import _named_at
from .fitting import fit_from
from .restarts import without
from .select import dof_of, pooled_f


def drop_p(groups: Sequence[Any], term: str, n_trials: int) -> tuple[float, Optional[list[Any]]]:
    """``(p adj, refits)``: the combined F test of dropping ``term`` from every condition's current model,
    Bonferroni over ``n_trials`` (its step's candidates), with the refits without it (None, and p 0, when
    one fails: the term stays)."""
    fits = [fit_from(g.sx, without(g.current.params, term), g.substeps) for g in groups]
    reduced = [r for r in fits if r is not None and math.isfinite(r.cost)]
    if len(reduced) < len(groups):
        return 0.0, None
    q = max(len(groups[0].current.params.terms) - len(reduced[0].params.terms), 1)
    imp = [r.cost - g.current.cost for r, g in zip(reduced, groups)]
    d1 = [dof_of(g.sx, g.current) for g in groups]
    _, p = pooled_f(imp, [g.current.cost for g in groups], d1, q)
    p = p if math.isfinite(p) else 1.0
    return min(1.0, p * max(n_trials, 1)), reduced


def check(groups: Sequence[Any], steps: list[Any], alpha: float) -> list[Any]:
    """``steps`` with every named term that fails its own joint test in the final model dropped (module
    docstring); the groups' current models refitted without it; the dropped terms on the last step."""
    at: dict[str, Any] = dict(_named_at(steps))  # joint steps: chosen, pair, trials and level read
    dropped: list[tuple[str, float]] = []
    while True:
        tested = [t for t in groups[0].current.params.terms if t in at]
        if len(tested) < 2:  # a single named term was tested on this very model at its step
            break
        worst: Optional[tuple[float, str, list[Any]]] = None
        for t in tested:
            st = at[t]
            p, reduced = drop_p(groups, t, len(st.trials))
            level = st.level if math.isfinite(st.level) else alpha
            if reduced is not None and p >= level and (worst is None or p > worst[0]):
                worst = (p, t, reduced)
        if worst is None:
            break
        dropped.append((worst[1], worst[0]))
        for g, f in zip(groups, worst[2]):
            g.current = f
    if dropped:
        steps = [*steps[:-1], replace(steps[-1], unneeded=tuple(dropped))]
    return steps


__all__ = ["check", "drop_p"]

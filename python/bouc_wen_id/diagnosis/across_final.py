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
from typing import Any, Optional

from .final_terms import prune
from .fitting import fit_from
from .restarts import without
from .select import dof_of, pooled_f


def drop_p(
    groups: Sequence[Any], fits: Sequence[Any], term: str, n_trials: int
) -> tuple[float, Optional[list[Any]]]:
    """``(p adj, refits)``: the combined F test of dropping ``term`` from every condition's model (``fits``,
    one per group), Bonferroni over ``n_trials`` (its step's candidates), with the refits without it (None,
    and p 0, when one fails: the term stays)."""
    refits = [fit_from(g.sx, without(f.params, term), g.substeps) for g, f in zip(groups, fits)]
    reduced = [r for r in refits if r is not None and math.isfinite(r.cost)]
    if len(reduced) < len(groups):
        return 0.0, None
    q = max(len(fits[0].params.terms) - len(reduced[0].params.terms), 1)
    imp = [r.cost - f.cost for r, f in zip(reduced, fits)]
    d1 = [dof_of(g.sx, f) for g, f in zip(groups, fits)]
    _, p = pooled_f(imp, [f.cost for f in fits], d1, q)
    p = p if math.isfinite(p) else 1.0  # a refit at least as good: the term adds nothing (final_terms.drop_p)
    return min(1.0, p * max(n_trials, 1)), reduced


def check(groups: Sequence[Any], steps: list[Any], alpha: float) -> list[Any]:
    """``steps`` with every named term that fails its own joint test in the final model dropped (module
    docstring, :func:`.final_terms.prune`'s loop); the groups' current models refitted without it; the
    dropped terms on the last step."""

    def drop(fits: list[Any], term: str, step: Any) -> tuple[float, float, Optional[list[Any]]]:
        p, reduced = drop_p(groups, fits, term, len(step.trials))
        return p, (step.level if math.isfinite(step.level) else alpha), reduced

    fits, steps = prune([g.current for g in groups], steps, lambda fs: fs[0].params.terms, drop)
    for g, f in zip(groups, fits):
        g.current = f
    return steps


__all__ = ["check", "drop_p"]

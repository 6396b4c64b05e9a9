"""The final check of the named set: every named term must still pass its own test in the final model.

A step names the best candidate given the terms named before it; a term named early can become unneeded
once later terms are named (a later term, or a pair named beside it, takes over what it fitted). Review 38
(d1, a lead-rubber isolator with viscous damping on x and a spring, first-order G): viscous damping on u
was named at step 1 (p adj 0.0 on the plain model), then viscous damping on x with a parallel stiffness at
step 2; in the final model its value was c = 0.00019 +- 0.00021, 0.9 se from zero, and the headline named it.

The check: for each term a step named (alone or in a pair) that is in the final model, the F test of
dropping it (with its companion, for a two-term element) from the final model (:func:`.select.f_test`, the
boundary form for a term whose null is its bound), Bonferroni-adjusted over that step's candidates and at
that step's level (``alpha``, or the targeted step's :func:`.gate.targeted_level`): the test that named it,
asked again of the final model. The worst term that fails is dropped and the model refitted without it, and
the check repeats on the rest. The dropped terms are recorded on the last step (``Step.unneeded``) and the
verdict says so (:func:`text`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Callable, Optional, TypeVar

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS
from .fitting import fit_from
from .gate import targeted_level
from .restarts import without
from .select import ALPHA, BOUNDARY_TERMS, Step, dof_of, f_test

#: The model the check prunes: one group's fit, or every condition's (across_final.py).
S = TypeVar("S")


def _named_at(steps: Sequence[Any]) -> dict[str, Any]:
    """Each term a step named (alone or in a pair), with the step (the last that named it); steps of one
    group (:class:`.select.Step`) or joint ones (``across_types.JointStep``)."""
    out: dict[str, Any] = {}
    for st in steps:
        for t in (st.chosen, *st.pair):
            if t:
                out[t] = st
    return out


def drop_p(
    exps: Sequence[AugExperiment], final: AugFit, term: str, step: Step, substeps: int
) -> tuple[float, Optional[AugFit]]:
    """``(p adj, refit)``: the Bonferroni-adjusted p of dropping ``term`` from ``final`` (its step's
    candidate count), with the refit without it (None, and p 0, when that refit fails: the term stays)."""
    reduced = fit_from(exps, without(final.params, term), substeps)
    if reduced is None or not math.isfinite(reduced.cost):
        return 0.0, None
    q = max(len(final.params.terms) - len(reduced.params.terms), 1)
    _, p = f_test(reduced.cost, final.cost, dof_of(exps, final), boundary=term in BOUNDARY_TERMS, q=q)
    p = p if math.isfinite(p) else 1.0  # a refit at least as good as the final model: the term adds nothing
    return min(1.0, p * max(len(step.trials), 1)), reduced


def level_of(step: Step, alpha: float) -> float:
    """The level the step that named a term tested it at."""
    return targeted_level(alpha, step.after_named) if step.targeted else alpha


def check(
    exps: Sequence[AugExperiment], final: AugFit, steps: list[Step], substeps: int, alpha: float = ALPHA
) -> tuple[AugFit, list[Step]]:
    """``(final, steps)`` with every named term that fails its own test in the final model dropped (module
    docstring), the model refitted without it; the dropped terms and their p adj on the last step."""

    def drop(fit: AugFit, term: str, step: Step) -> tuple[float, float, Optional[AugFit]]:
        p, reduced = drop_p(exps, fit, term, step, substeps)
        return p, level_of(step, alpha), reduced

    return prune(final, steps, lambda f: f.params.terms, drop)


def prune(
    state: S,
    steps: list[Any],
    terms_of: Callable[[S], Sequence[str]],
    drop: Callable[[S, str, Any], tuple[float, float, Optional[S]]],
) -> tuple[S, list[Any]]:
    """The check's loop (module docstring), for one group's fit (:func:`check`) or every condition's
    (across_final.py): ``state`` the model, ``terms_of`` its terms, ``drop(state, term, step)`` the p adj of
    dropping a named ``term``, the level its ``step`` tested it at, and the model without it (None: the term
    stays). The worst failing term is dropped and the rest tested again; ``(state, steps)`` with the dropped
    terms and their p adj on the last step."""
    at = _named_at(steps)
    dropped: list[tuple[str, float]] = []
    while True:
        tested = [t for t in terms_of(state) if t in at]
        if len(tested) < 2:  # a single named term was tested on this very model at its step
            break
        worst: Optional[tuple[float, str, S]] = None
        for t in tested:
            p, level, reduced = drop(state, t, at[t])
            if reduced is not None and p >= level and (worst is None or p > worst[0]):
                worst = (p, t, reduced)
        if worst is None:
            break
        dropped.append((worst[1], worst[0]))
        state = worst[2]
    if dropped:
        steps = [*steps[:-1], replace(steps[-1], unneeded=tuple(dropped))]
    return state, steps


def text(steps: Sequence[Step], named: Sequence[object]) -> str:
    """The verdict's clause on terms dropped by :func:`check`: each is not needed once the rest are named."""
    dropped = [d for st in steps for d in st.unneeded]
    if not dropped:
        return ""
    others = ", ".join(getattr(t, "label", str(t)) for t in named) or "the others"
    what = ", ".join(f"{TERMS[t].place_label()} (p adj = {p:.2g})" for t, p in dropped)
    each = "each fails" if len(dropped) > 1 else "it fails"
    return (
        f"; not needed once {others} are named: {what} (named at an earlier step, {each} its own test, "
        "the F test of dropping it, in the final model: dropped, and the model refitted without it)"
    )


__all__ = ["check", "text", "drop_p", "level_of", "prune"]

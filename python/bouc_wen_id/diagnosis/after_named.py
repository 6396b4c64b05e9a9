"""The targeted step after a named one: the forward selection (:func:`.select.forward_select`) run again
from a model that a named term has made pass the global test.

The plain model's gate is a union of tests at family-wise ``alpha`` (select.py's docstring): the global
test at ``alpha / 2`` and, when it accepts, one targeted step whose candidates' F-tests share the other
``alpha / 2``. Before this module that gate was applied only to the plain model: once a term was named and
the model then passed the global test, selection stopped, and a second term the global test cannot see
(a sensor lag, which G's phase nearly absorbs) went unnamed behind the first (review 32: a sensor lag of
0.03 s named alone, missed beside an output offset of 0.05, the final p 0.63).

After a named step the gate is applied to the model with the named terms: the global test at ``alpha / 2``
(the selection's stopping test, ``passes``); when it rejects, the next step runs at ``alpha`` as before; when
it accepts, one targeted step runs and selection ends there unless it names one. That step's candidates share
``alpha / 10`` (:data:`.gate.AFTER_NAMED_SHARE`), not the plain model's ``alpha / 2``. At ``alpha / 2`` a
correct model took a false second term at up to 2.5 % (Bonferroni): on our bench 2 of 40 correct single names
(session 33: play seed 32015 + inertia on u at F = 12.4, p adj 0.0068; pinching seed 44014 + stiffness on x at
F = 10.0, p adj 0.025). Nothing but the level told them from a true term: their laws held (p 0.67, 0.63) and
their held-out gains were as large as their in-sample ones (13.9 and 8.0 against 12.4 and 10.1). Under four
other noise draws of the same plants (studies/after_named_noise.py) inertia never came back (best p adj >=
0.65: noise); stiffness on x came back once at p adj 0.021 (likely in part the first term's misfit, the
bench's pinch band not the library's fixed shape). The plain model's ``alpha / 2`` is the nulls' budget; a
false second term costs every correctly named diagnosis instead, and at ``alpha / 10`` a 20-case row of
correct single terms expects 0.1 of them (0.5 at ``alpha / 2``). The hidden terms the step is for pass far
below it: a 4 ms lag behind an offset at p adj 1e-9 (tests/test_diagnosis_after_named.py). A correct model is
refused a false extra term at most at ``alpha / 2 + alpha / 10``. A null that names nothing at its first step
never reaches this step, so the nulls' rate of any name is the first step's.

Each later call of :func:`.select.forward_select` starts its own step list, so its beside-a-Dahl rule
(:func:`.beside.only_beside`) has no first-step p of a candidate on the plain model and refuses every
candidate beside a Dahl element there (the conservative side; the verdict's clause still quotes the first
step's p).

Only where the first step's gate allowed the targeted step (``again``: measured noise, the loop not
drifting, no degradation named) and every record has the periods that tell a settling transient from a
term (:data:`.zero_drift.MIN_PERIODS`: on blind few_periods seed 11's null the step named an asymmetry
beside the offset that a settling centre's transient had drawn, which centre_decay.py then could not
weigh); else the selection is the old one (stopping at ``adequate``).

:func:`.across.diagnose_across` takes the same step by the same gate (:func:`joint_next`: after a named
joint step, the targeted step at ``alpha / 10`` when every condition's model passes the global test at
``alpha / 2`` and :func:`again` holds at every condition; review 33: diagnose named a 0.1-sd offset beside
viscous damping at one condition while the joint selection stopped after viscous damping).

After a drift term (strength or stiffness degradation) is named, the steady fit starts from the periods
brought back to the virgin loop, and that start often passes the global test at once; selection then stops
with no step. A targeted step there (session 36, built off, removed in session 37) named a parallel
stiffness on x at 8 se beside a stiffness degradation alone on tests/test_degradation.py's independent
generator (seeds 42010 and 42017; k = 0.00128 +- 0.00016, none in the plant): the first-order drift
correction leaves a residue such a step reads as physics (review rv35m F5's mechanism). A steady term beside
a drift term is found where the corrected start fails the global test (an ordinary step).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from ..augmented import AugExperiment, AugFit
from .gate import plain_passes, targeted_level
from .select import ALPHA, Step, forward_select
from .zero_drift import MIN_PERIODS


def again(moved: bool, measured_noise: bool, exps: Sequence[Any]) -> bool:
    """Whether the targeted step after a named one may run on a set of experiments (module docstring): the
    loop not drifting and no degradation named (``moved`` False), measured noise, and every experiment with
    the :data:`.zero_drift.MIN_PERIODS` periods that tell a settling transient from a term."""
    return not moved and measured_noise and all(e.dc.size >= MIN_PERIODS for e in exps)


def joint_next(
    p_values: Sequence[float], alpha: float, again_each: Sequence[bool]
) -> tuple[bool, float, bool]:
    """After a joint step that named a term (across.py; ``p_values``: each condition's global p of the model
    with it): ``(go on, level, targeted)`` by :func:`select`'s gate. Where :func:`again` holds at every
    condition: when every model passes the global test at ``alpha / 2`` (:func:`.gate.plain_passes`), one
    targeted step at :func:`.gate.targeted_level`'s ``alpha / 10``, else a step at ``alpha``; elsewhere the
    old rule (stop once every model passes its adequacy test at ``alpha``)."""
    if again_each and all(again_each):
        if all(plain_passes(p, alpha) for p in p_values):
            return True, targeted_level(alpha, after_named=True), True
        return True, alpha, False
    adequate = all(math.isfinite(p) and p >= alpha for p in p_values)
    return not adequate, alpha, False


def select(
    exps: Sequence[AugExperiment],
    start: AugFit,
    candidates: Sequence[str],
    adequate: Callable[[AugFit], bool],
    p_of: Callable[[AugFit], float],
    substeps: int,
    targeted: bool,
    again: bool,
    **kw: Any,
) -> tuple[AugFit, list[Step]]:
    """The forward selection from ``start`` (:func:`.select.forward_select`, its keywords ``kw``) with the
    targeted step (at :func:`.gate.targeted_level`'s ``alpha / 10``) after each named step that leaves a model
    whose global p-value ``p_of(fit)`` passes the gate at ``alpha / 2`` (:func:`.gate.plain_passes`; module
    docstring), when ``again``; else :func:`.select.forward_select` as it was."""
    alpha = kw.get("alpha", ALPHA)

    def passes(fit: AugFit) -> bool:
        return plain_passes(p_of(fit), alpha)

    if not again:
        return forward_select(exps, start, candidates, adequate, substeps, targeted=targeted, **kw)
    on_trial = kw.pop("on_trial", None)
    steps: list[Step] = []

    def numbered(k: int, t: str, i: int, n: int) -> None:  # progress: the step's number over all calls
        if on_trial is not None:
            on_trial(len(steps) + k, t, i, n)

    final, more = forward_select(
        exps, start, candidates, passes, substeps, targeted=targeted, on_trial=numbered, **kw
    )
    steps += more
    while steps and steps[-1].chosen is not None and passes(final):
        final, more = forward_select(
            exps,
            final,
            candidates,
            passes,
            substeps,
            targeted=True,
            on_trial=numbered,
            after_named=True,
            **kw,
        )
        if not more:  # no candidate left
            break
        steps += more
    return final, steps


__all__ = ["select", "again", "joint_next"]

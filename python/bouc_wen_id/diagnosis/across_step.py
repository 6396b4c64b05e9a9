"""One step of the joint selection across conditions: a candidate's joint trial (``_trial``), its
confirmation (``_confirmed``, ``_accepts``), whether to go on (``_go_on``) and the step (``_step``). Moved out
of across.py (no behaviour change); across.py re-exports every name; ``_select`` stays in across.py (it
calls ``rebase_groups`` through across, which tests patch)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from . import (
    across_rules,
    across_verdict,
    after_named,
)
from .across_types import JointStep, JointTrial, _Group
from .select import (
    LAW_ALPHA,
    held_out,
)


def _confirmed(groups: Sequence[_Group], tr: JointTrial, use_held_out: bool) -> JointTrial:
    """``tr`` with its law test (Bonferroni over the conditions where it is present, across_rules.law_p)
    and its held-out costs summed over the conditions."""
    law_p = across_rules.law_p(groups, tr, tr.present)
    out = replace(tr, law_p_value=law_p)
    if not use_held_out or (math.isfinite(law_p) and law_p < LAW_ALPHA):
        return out
    before = after = 0.0
    for g, f in zip(groups, tr.fits):
        assert f is not None
        ho = held_out(g.sx, g.current, f, g.substeps, g.cache)
        if ho is not None:
            before += sum(ho.cost_before)
            after += sum(ho.cost_after)
    return replace(out, held_out_before=before, held_out_after=after)


def _accepts(tr: JointTrial, use_held_out: bool) -> bool:
    if math.isfinite(tr.law_p_value) and tr.law_p_value < LAW_ALPHA:
        return False
    if not use_held_out or not math.isfinite(tr.held_out_before) or tr.held_out_before == 0.0:
        return True
    return tr.held_out_after < tr.held_out_before


def _go_on(groups: Sequence[_Group], steps: Sequence[JointStep], alpha: float) -> tuple[bool, float, bool]:
    """Whether the joint selection takes another step, its level and whether it is the targeted step: as
    diagnose's selection, after a named step by its gate (after_named.joint_next: the targeted step at ``alpha
    / 10`` when the structure passes the global test at ``alpha / 2`` everywhere; without measured noise or
    settled periods, stop once it passes at ``alpha``); the first step is the targeted one, at ``alpha / 2``
    (select.py), when every condition's plain model passes diagnose's gate (gate.plain_gate: at ``alpha / 2``,
    its loop not drifting) and every noise floor is measured noise; when the gate passes on a floor set by
    quantisation or numerical accuracy, no step runs (gate.NO_TARGETED_STEP, a note); else the first step runs
    at ``alpha``."""
    if not steps:
        passes, targeted = across_verdict.plain_gate(groups, alpha)
        return not passes or targeted, 0.5 * alpha if targeted else alpha, targeted
    if steps[-1].chosen is None:  # after a named step: diagnose's gate (after_named.py)
        return False, alpha, False
    again = [after_named.again(g.moved, g.measured_noise, g.exps) for g in groups]
    return after_named.joint_next([across_verdict.p_of(g, g.current) for g in groups], alpha, again)

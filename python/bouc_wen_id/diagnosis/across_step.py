"""One step of the joint selection across conditions: a candidate's joint trial (``_trial``), its
confirmation (``_confirmed``, ``_accepts``), whether to go on (``_go_on``) and the step (``_step``). Moved out
of across.py (no behaviour change); across.py re-exports every name; ``_select`` stays in across.py (it
calls ``rebase_groups`` through across, which tests patch)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

from . import (
    across_rules,
    across_verdict,
    after_named,
)
from .across_types import JointStep, JointTrial, _Group
from .beside import only_beside
from .select import (
    ALTERNATIVE_IMPROVEMENT,
    LAW_ALPHA,
    MATERIAL_SHARE,
    dof_of,
    held_out,
)

#: A passed candidate whose summed improvement is at least this fraction of the chosen one's is a near-tied
#: rival (select.ALTERNATIVE_IMPROVEMENT's threshold, on the summed improvements).
RIVAL_IMPROVEMENT = ALTERNATIVE_IMPROVEMENT


def _trial(groups: Sequence[_Group], term: str, n_cands: int, alpha: float, level: float) -> JointTrial:
    """``term`` fitted at every condition on top of its current model, with the combined in-sample tests
    (the combined F at ``level``, Bonferroni over the ``n_cands`` candidates; presence at ``alpha / K``)."""
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    from . import across as ac  # its _admissible, at_null, away_from_null: the names tests patch there

    k = len(groups)
    fits = [g.fit_term(g.current, term) for g in groups]
    if any(f is None for f in fits):  # the term cannot stand at some condition: not at every one
        nan = (math.nan,) * k
        return JointTrial(term, math.nan, math.nan, math.nan, math.nan, nan, nan, False, fits=tuple(fits))
    done = [f for f in fits if f is not None]
    q = len(done[0].params.terms) - len(groups[0].current.params.terms)  # 2 for a two-term element
    c0 = [g.current.cost for g in groups]
    c1 = [f.cost for f in done]
    d1 = [dof_of(g.sx, f) for g, f in zip(groups, done)]
    imp = [a - b for a, b in zip(c0, c1)]
    stat, p = across_rules.pooled_f(imp, c1, d1, q)  # over the pooled residual variance (>= the noise)
    padj = min(1.0, p * n_cands)
    excess = sum(max(g.current.cost - dof_of(g.sx, g.current), 0.0) for g in groups)
    share = min(sum(imp) / excess, 1.0) if excess > 0 else 1.0
    # Each condition's own evidence, its own denominator: is the term needed there?
    p_each = []
    for a, c, d in zip(imp, c1, d1):
        f_k = max(a, 0.0) / q / max(c / max(d, 1), 1.0)
        p_each.append(float(fdtrc(q, max(d, 1), f_k)) if f_k > 0 else 1.0)
    present = tuple(pk < alpha / k for pk in p_each)
    # As the single-group selection: a physical value, and not the null value (the model without it: what
    # it "removed" is a refit from another start, select.at_null), wherever it is present.
    # And its value away from the null there (select.away_from_null: the Wald test beside the F test).
    physical = all(
        ac._admissible(f, term)
        and not ac.at_null(f, term)
        and ac.away_from_null(f, term, level, f.cost / max(d, 1))
        for f, d, pr in zip(done, d1, present)
        if pr
    )
    ok = padj < level and share >= MATERIAL_SHARE and physical and any(present)
    imps, ps = tuple(imp), tuple(p_each)
    return JointTrial(term, stat, p, padj, share, imps, ps, ok, fits=tuple(fits), present=present)


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


def _step(
    groups: Sequence[_Group],
    trials: list[JointTrial],
    level: float,
    alpha: float,
    use_held_out: bool,
    alone: dict[str, float],
) -> JointStep:
    """One joint step's choice from its ``trials`` (module docstring): the simpler limit first
    (across_rules.simpler_first), the beside-Dahl rule, the law and held-out tests, the alternatives."""
    passed = sorted((tr for tr in trials if tr.passed), key=lambda tr: -sum(tr.improvements))
    order = across_rules.simpler_first(groups, passed, level / len(trials))
    chosen: Optional[JointTrial] = None
    final = {tr.term: tr for tr in trials}
    refused: list[str] = []
    for tr in order:
        if only_beside(groups[0].current, tr.term, alone.get(tr.term, math.nan), alpha):
            refused.append(tr.term)  # needed only beside a Dahl element (beside.py), as diagnose
            continue
        tr2 = _confirmed(groups, tr, use_held_out)
        final[tr.term] = tr2
        if _accepts(tr2, use_held_out):
            chosen = tr2
            break
    law_failed = tuple(
        t.term for t in final.values() if math.isfinite(t.law_p_value) and t.law_p_value < LAW_ALPHA
    )
    done = tuple(final[t.term] for t in trials)
    if chosen is None:
        return JointStep(done, None, (), law_failed, tuple(refused), level=level)
    best = sum(chosen.improvements)
    rivals = tuple(
        tr.term
        for tr in passed
        if tr.term != chosen.term
        and (sum(tr.improvements) >= RIVAL_IMPROVEMENT * best or across_verdict.tied(groups, chosen, tr))
        and tr.term not in refused + list(law_failed)
    )
    unphysical: list[str] = []  # the chosen term's other places that fit as well, non-physical
    alts = across_rules.alternatives(groups, chosen, done, order, law_failed, unphysical)
    return JointStep(done, chosen.term, rivals, law_failed, tuple(refused), alts, tuple(unphysical), level)

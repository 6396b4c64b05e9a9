"""The diagnosis across conditions: one named structure, its values free per condition (issue 18).

A user who characterises a damper at several conditions (coil currents, temperatures, preloads) wants one
model structure whose parameters move with the condition, not a separate story per condition.
:func:`diagnose_across` takes groups of experiments, one per condition, and runs a forward selection in which
a candidate term is added to EVERY condition at once, its value free per condition (docs/diagnosis.md,
"Across conditions"):

- each condition keeps its own plain Wiener-Bouc-Wen fit (its own beta, gamma, mu, |G|, phi) as in
  :func:`~bouc_wen_id.diagnosis.diagnose`, and a candidate is fitted on each by the same machinery
  (:func:`.fitting.fit_with`);
- the candidate's combined F statistic is the sum of the per-condition numerators ``C0_k - C1_k`` over the
  pooled denominator ``sum C1_k / sum dof_k`` (floored at the noise, as :func:`.select.f_test`), against
  ``F(q K, sum dof_k)`` for K conditions and q added parameters, Bonferroni over the step's candidates;
  it must explain a material share of the summed excess, keep a physical value wherever it is present,
  hold its law (one value for a condition's experiments, :func:`.select.law_test`, Bonferroni over the
  conditions where it is present) and lower the held-out cost summed over the conditions;
- as in :func:`~bouc_wen_id.diagnosis.diagnose` (across_rules.py): a two-term element's simpler limit goes
  first unless the element beats it; a candidate tied with the best at the place the named terms act at
  goes first (place_tie.py); the chosen term's other place, a rival within its uncertainty and one
  whose value trades with its are reported as alternatives with the separating experiment; selection stops
  when no candidate passes or once the structure passes its adequacy test at every condition (the first
  step at ``alpha / 2`` when every condition's plain model passes the gate, the targeted step, and none
  where the gate passes on a noise floor that is not measured noise: :func:`.gate.plain_gate`, diagnose's);
  experiments whose loop has not settled, or that still hold G's free ring-down (across_ring.py: when most
  do, nothing is named), are left out per condition, as diagnose leaves them out (across_settling.py),
  and the verdict's clauses are diagnose's (across_verdict.py); its pair step and its two revisits of a
  named single term run on the joint steps (across_pairs.py, across_revisit.py).

Per condition the result reports each term's value with its standard error (inflated by the final fit's
``sqrt(chi2/dof)`` when above 1: a misfit elsewhere makes the noise-based one too small), whether the term
is present there on its own evidence (its per-condition F test at ``alpha / K``; a term present only at
some conditions is reported so, never forced everywhere), the smoothness of the values in the condition
(the lowest polynomial degree, at most :data:`MAX_DEGREE`, that fits them within their se by a chi-square
test), whether ONE value refitted at every condition fits as well as one per condition (the nested fit's F
test, :mod:`.shared`: "shared: c = ... +- ..." or "varies with the condition (p = ...)"), the final
chi2/dof and the held-out NRMSE; and, when the per-condition diagnoses are given, their named terms and
held-out NRMSE beside the joint structure's.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, Optional, cast

from ..augmented import AugFit
from ..errors import InvalidParameterError
from ..terms import TERMS, Distortion, Offset
from ..units import harmonise_groups
from ..validation import real_number
from . import (
    across_adequacy,
    across_dc,
    across_final,
    across_pairs,
    across_revisit,
    across_rules,
    across_settling,
    across_stable,
    across_verdict,
    baseline,
    bounds_said,
    fit_notes,
    inputs,
    readings,
)
from .across_smooth import MAX_DEGREE, smoothness
from .across_stable import ConditionResult

# re-exported from across_step.py (moved there): importable from across as before
from .across_step import _accepts as _accepts
from .across_step import _confirmed as _confirmed
from .across_step import _go_on as _go_on

# re-exported from across_types.py (moved there): importable from across as before
from .across_types import AcrossDiagnosis as AcrossDiagnosis
from .across_types import JointStep as JointStep
from .across_types import JointTrial as JointTrial
from .across_types import TermAcross as TermAcross
from .across_types import _Group as _Group
from .across_types import _median as _median
from .across_types import _n as _n
from .across_types import _p as _p
from .across_types import _ps as _ps
from .beside import only_beside
from .caveats import alternatives_text
from .fitting import carry_through_g, fit_plain, physical, scale_of, scaled, substeps_for
from .place_tie import named_place_first
from .progress import Progress, ProgressCallback, reporter
from .restarts import rebase_groups
from .result import Diagnosis, NamedTerm, term_symbol_unit
from .select import (
    ALPHA,
    ALTERNATIVE_IMPROVEMENT,
    LAW_ALPHA,
    MATERIAL_SHARE,
    dof_of,
    held_out,
    siblings,
)

# tests patch these here (across._trial reads them)
from .select import _admissible as _admissible
from .select import at_null as at_null
from .select import away_from_null as away_from_null
from .shared import shared_test

# ------------------------------------------------------------------------------------------------------
# Preparing each condition: the single-group diagnosis's own steps


def _group(
    items: Any,
    label: str,
    condition: float,
    cands: Sequence[str],
    own: Optional[Diagnosis],
    alpha: float = ALPHA,
    judged: tuple[Sequence[str], bool] = ((), True),
    zeros: Any = None,
    ringing: frozenset[str] = frozenset(),
) -> _Group:
    """One condition's experiments prepared, checked and plain-fitted as :func:`diagnose` does; from its own
    diagnosis (``own``) when given (its experiments and plain fit, so nothing is fitted twice) unless it
    names degradation; ``judged``: the candidates and held-out rule of the condition's own judgement of a
    drift (across_settling.degrades); ``zeros``: the recordings' zeros differ, each one's DC left free about
    their common one (across_zeros.py; the condition's own diagnosis not reused); ``ringing``: the names of
    its recordings that still ring (across_ring.py), left out as diagnose leaves them out."""
    from . import free_dc, record_zeros, zero_drift
    from .centre_only import slow_dc
    from .data import prepare
    from .drift import DRIFT_TERMS
    from .run import _drift_checked, _localise
    from .settling import _check_experiments, _noise_floors, _settled

    level = alpha / max(len(cands), 1)  # a wandering zero (baseline.py) or a drifting one, as diagnose
    wander = zeros or baseline.detect(items, level) or zero_drift.detect(items, level)
    left = across_settling.from_own(own, label) if own is not None else ()  # its unsettled stay out
    left_p = across_settling.own_p(own, left) if own is not None else ()  # their p, as its diagnosis kept
    degraded = own is not None and across_settling.names_degradation(own)  # not modelled across
    why = across_settling.why_own(own) if left else ""
    # Its own diagnosis freed each recording's DC (record_zeros.py, no wander here): its experiments and plain
    # fit are not this condition's as prepared below; prepared afresh, the joint steps decide (across_zeros)
    freed = own is not None and wander is None and own.settings.get("common_dc") is not None
    if (
        own is not None
        and zeros is None
        and not freed
        and not degraded
        and not ringing & {e.source for e in own.experiments}  # its ringing records: left out below
        and own.plain_fit is not None
        and len(own.plain_fit.params.gains) == len(own.experiments)
    ):
        exps = list(own.experiments)
        s = scale_of(exps)
        sx = scaled(exps, s)
        substeps = substeps_for([e.ybar.size for e in sx])
        plain: AugFit = own.plain_fit
        measured = own.settings.get("measured_noise")
        if measured is None:  # a diagnosis that did not record it: its floors, from the items again
            measured = across_settling.measured_noise(items, wander)
        moved = own.before.drift_detected or any(t.term in DRIFT_TERMS for t in own.named)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the transient trim's warning is diagnose's to give
            settled, _ = _settled(baseline.removed(items, wander))
        exps, qnotes = _noise_floors(settled, prepare(settled))
        exps = record_zeros.freed(exps) if zeros is not None else exps
        measured = not qnotes
        _check_experiments(exps)
        judge = lambda: True if degraded else across_settling.degrades(items, judged[0], alpha, judged[1])  # noqa: E731
        # not settled, as diagnose: each left out with its p (across_settling.py)
        exps, left, why, left_p = across_settling.drop(exps, label, judge, ringing)
        s = scale_of(exps)
        sx = scaled(exps, s)
        if wander is not None:
            sx = free_dc.marked(sx, [e.baseline_removed for e in exps], wander.kept)
        substeps = substeps_for([e.ybar.size for e in sx])
        plain = fit_plain(exps, sx, s, substeps)
        moved = _drift_checked(_localise(exps, sx, plain, s), exps).drift_detected  # as diagnose's gate
    if wander is not None:  # each marked experiment's DC free, as diagnose fits it (free_dc.py)
        sx = free_dc.marked(sx, [e.baseline_removed for e in exps], wander.kept)
    if Distortion.kind in cands and any(e.distorted for e in exps):
        sx = carry_through_g(sx, plain, substeps)
    noise_dof = sum(e.noise_dof for e in exps)
    return _Group(
        label,
        condition,
        sx,
        s,
        substeps,
        noise_dof,
        plain,
        plain,
        exps=list(exps),
        wander=isinstance(wander, baseline.Wander),
        drifts=isinstance(wander, zero_drift.Drift),
        loop_trends=isinstance(wander, zero_drift.Drift) and wander.loop_trends,
        measured_noise=bool(measured),
        moved=bool(moved),
        left_out=left,
        left_why=why,
        left_p=left_p,
        rung=tuple(n for n in left if n in ringing),
        zeros=zeros,
        centres=wander,
        slow_dc=bool(exps) and slow_dc(exps),  # a noise coloured at the DC (dc_between.py), as diagnose
    )


# ------------------------------------------------------------------------------------------------------
# The joint selection


#: A passed candidate whose summed improvement is at least this fraction of the chosen one's is a near-tied
#: rival (select.ALTERNATIVE_IMPROVEMENT's threshold, on the summed improvements).
RIVAL_IMPROVEMENT = ALTERNATIVE_IMPROVEMENT


def _trial(groups: Sequence[_Group], term: str, n_cands: int, alpha: float, level: float) -> JointTrial:
    """``term`` fitted at every condition on top of its current model, with the combined in-sample tests
    (the combined F at ``level``, Bonferroni over the ``n_cands`` candidates; presence at ``alpha / K``)."""
    from scipy.special import fdtrc  # type: ignore[import-untyped]

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
    # And, as diagnose, a centre term's DCs out of their spread under a noise coloured at the DC (across_dc).
    physical = all(
        _admissible(f, term)
        and not at_null(f, term)
        and away_from_null(f, term, level, f.cost / max(d, 1))
        and across_dc.stands_out(g, f, term, level)
        for g, f, d, pr in zip(groups, done, d1, present)
        if pr
    )
    ok = padj < level and share >= MATERIAL_SHARE and physical and any(present)
    imps, ps = tuple(imp), tuple(p_each)
    return JointTrial(term, stat, p, padj, share, imps, ps, ok, fits=tuple(fits), present=present)


def _step(
    groups: Sequence[_Group],
    trials: list[JointTrial],
    level: float,
    alpha: float,
    use_held_out: bool,
    alone: dict[str, float],
) -> JointStep:
    """One joint step's choice from its ``trials`` (module docstring): the simpler limit first
    (across_rules.simpler_first), a tied candidate at the named terms' place first (place_tie.py), the
    beside-Dahl rule, the law and held-out tests, the alternatives."""
    passed = sorted((tr for tr in trials if tr.passed), key=lambda tr: -sum(tr.improvements))
    order = across_rules.simpler_first(groups, passed, level / len(trials))
    # A tied candidate at the place the named terms act at goes first, as in diagnose (place_tie.py).
    order = named_place_first(order, groups[0].current.params.terms, partial(across_verdict.tied, groups))
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


def _select(
    groups: Sequence[_Group],
    cands: Sequence[str],
    alpha: float,
    held: bool,
    report: ProgressCallback,
) -> list[JointStep]:
    """The joint forward selection (module docstring); the groups' current models end at the final ones."""
    steps: list[JointStep] = []
    refitted: tuple[str, ...] = ()
    while True:
        go, level, targeted = _go_on(groups, steps, alpha)
        remaining = [t for t in cands if t not in groups[0].current.params.terms]
        if not (go and remaining):
            break
        trials: list[JointTrial] = []
        for i, t in enumerate(remaining):
            report(
                f"across step {len(steps) + 1}: fitting candidate {t} at every condition", i, len(remaining)
            )
            trials.append(_trial(groups, t, len(remaining), alpha, level))
        if not refitted:  # a condition's model not converged (restarts.py): refitted, the step redone
            refitted = rebase_groups(groups, trials, [(t, u) for t in remaining for u in siblings(t)])
            if refitted:
                continue
        alone = {t.term: t.p_value for t in steps[0].trials} if steps else {}
        step = replace(_step(groups, trials, level, alpha, held, alone), targeted=targeted, refitted=refitted)
        # Every candidate's law failed alone: two or three at once, as diagnose's pair step (across_pairs.py).
        steps.append(across_pairs.step(groups, step, len(trials), alpha, held, JointTrial))
        refitted = ()
        chosen = next(
            (t for t in (*steps[-1].members, *steps[-1].trials) if t.term == steps[-1].chosen), None
        )
        if chosen is None:
            break
        for g, f in zip(groups, chosen.fits):
            assert f is not None
            g.current = f
    steps = across_revisit.after(groups, steps, alpha, held, JointTrial)  # diagnose's revisits, across
    return across_final.check(groups, steps, alpha)  # each named term still needed (final_terms.py)


# ------------------------------------------------------------------------------------------------------
# What the final structure says per term and per condition


def _terms(
    groups: Sequence[_Group], steps: Sequence[JointStep], units: tuple[str, str], alpha: float
) -> tuple[TermAcross, ...]:
    k = len(groups)
    conds = [g.condition for g in groups]
    out = []
    for st in steps:
        if st.chosen is None:
            continue
        for term in groups[0].current.params.terms:
            # The chosen term (or set: across_pairs.py), and a two-term element's companion beside it.
            if term not in (st.chosen, *st.pair) and TERMS[st.chosen].companion != term:
                continue
            tr = next((m for m in st.members if m.term == term), None) or next(
                t for t in (*st.members, *st.trials) if t.term == st.chosen
            )
            vals, ses = [], []
            for g in groups:
                v, se = physical(g.current, g.scale, term)
                inflate = math.sqrt(max(1.0, g.current.cost / max(dof_of(g.sx, g.current), 1)))
                vals.append(v)
                # an output offset where the zeros moved between records: their centres' spread, as diagnose
                ses.append(
                    baseline.offset_se(g.centres, se * inflate) if term == Offset.kind else se * inflate
                )
            ps = smoothness(conds, vals, ses)
            degree = next((d for d, p in enumerate(ps) if p >= alpha), None)
            one = shared_test(
                term,
                [g.sx for g in groups],
                [g.scale for g in groups],
                [g.substeps for g in groups],
                [g.current for g in groups],
                [dof_of(g.sx, g.current) for g in groups],
                alpha,
            )
            sym, unit = term_symbol_unit(term, *units)
            out.append(
                TermAcross(
                    term,
                    TERMS[term].place_label(),
                    sym,
                    unit,
                    tuple(vals),
                    tuple(ses),
                    tuple(p < alpha / k for p in tr.p_each),
                    tr.p_each,
                    ps,
                    degree,
                    one,
                )
            )
    return tuple(out)


def _conditions(
    groups: Sequence[_Group],
    own: Sequence[Optional[Diagnosis]],
    use_held_out: bool,
    checks: Sequence[Any] = (),
) -> tuple[ConditionResult, ...]:
    """Each condition's joint fit beside its own diagnosis; ``checks``: each one's stability check (or None),
    whose alternatives are said as such, not as the condition's terms (across_stable.py)."""
    out = []
    for g, d, st in zip(groups, own, [*checks, *[None] * (len(own) - len(checks))]):
        fin, pl = g.current, g.plain
        dof0, dof1 = dof_of(g.sx, pl), dof_of(g.sx, fin)
        ho = held_out(g.sx, pl, fin, g.substeps, g.cache) if use_held_out and fin is not pl else None
        if ho is None and use_held_out:
            ho = held_out(g.sx, pl, pl, g.substeps, g.cache)
        hp = math.nan if ho is None else _median(ho.nrmse_before)
        hj = math.nan if ho is None else _median(ho.nrmse_after)
        terms: Optional[tuple[str, ...]] = None
        own_ho = math.nan
        alts: tuple[str, ...] = ()
        if d is not None:
            terms, alts = across_stable.split(d, st)
            own_ho = _median(d.held_out.nrmse_after) if d.held_out is not None else hp
        out.append(
            ConditionResult(
                g.label,
                g.condition,
                len(g.sx),
                across_adequacy.chi2(g, pl) / max(dof0, 1),  # diagnose's statistic (colour: harmonic-wise)
                across_adequacy.chi2(g, fin) / max(dof1, 1),
                across_adequacy.p_of(g, fin),
                hp,
                hj,
                terms,
                own_ho,
                alts,
            )
        )
    return tuple(out)


def _how(t: TermAcross) -> str:
    """How a term's value moves with the condition: the shared-value test first, then the smoothness."""
    sf = t.shared_fit
    if sf is not None and sf.shared:
        return (
            f"shared: {t.symbol} = {sf.value:.4g} +- {sf.standard_error:.2g} {t.unit} (one value refitted "
            f"at every condition fits as well as one per condition, p {_p(sf.p_value)})"
        ).replace(" )", ")")
    top = len(t.smooth_p) - 1  # the highest degree tested: one with a dof left (across_smooth.smoothness)
    if t.smooth_degree is None and top < MAX_DEGREE:  # review 43: 3 conditions said "up to degree 2"
        how = (
            f"its values on no polynomial up to degree {top} in the condition within their se (a degree-"
            f"{top + 1} curve passes through any {top + 2} values: nothing higher can be tested)"
        )
    elif t.smooth_degree is None:
        how = "its values not smooth in the condition (no polynomial up to degree "
        how += f"{MAX_DEGREE} fits them within their se)"
    elif t.shared:
        how = "one value shared by the conditions"
    elif t.smooth_degree == 0 and sf is not None:  # linearised, one value fits; refitted, it does not
        how = "its values within their se of one value when linearised at each condition"
    else:
        how = f"its values move with the condition as a degree-{t.smooth_degree} polynomial"
    if sf is not None and not sf.converged:  # its cost only bounds the shared fit's: a refusal not shown
        how = (
            f"one shared value not determined (its joint refit stopped after {sf.iterations} iterations); "
            f"{how}"
        )
    elif sf is not None:
        how = f"varies with the condition (one shared value refused, p {_p(sf.p_value)}); {how}"
    return how


def _verdict(
    terms: Sequence[TermAcross],
    conds: Sequence[ConditionResult],
    steps: Sequence[JointStep],
    alpha: float = ALPHA,
) -> str:
    """The verdict naming the joint structure; "passes its adequacy test" at ``alpha``, the caller's level,
    as the stop rule (:func:`_go_on`) and the status (across_verdict.py) judge it."""
    n = len(conds)
    if not terms:
        why = "no candidate passes all its tests jointly at every condition"
        why = why if any(st.trials for st in steps) else "no candidate tested"
        # Nothing named and not adequate (judged's rule: the status is "unexplained"): said so first, as
        # diagnose does (review 38: the MR damper at chi2/dof 1830-3280 read "nothing named" alone).
        return across_verdict.head("unexplained", (), n, math.nan) + f"; nothing named ({why})"
    parts = []
    for t in terms:
        where = (
            "at every condition"
            if t.everywhere
            else "needed only at " + ", ".join(c.label for c, p in zip(conds, t.present) if p)
        )
        parts.append(f"{t.label} ({where}; {_how(t)})")
    adequate = sum(1 for c in conds if math.isfinite(c.final_p_value) and c.final_p_value >= alpha)
    tail = f"; the joint structure passes its adequacy test at {adequate} of {n} conditions"
    named = [NamedTerm(t.term, t.symbol, math.nan, math.nan, t.unit) for t in terms]
    tail += alternatives_text([a for st in steps for a in st.alternatives], named)  # as diagnose says them
    return f"across {n} conditions, one structure: " + "; ".join(parts) + tail


# ------------------------------------------------------------------------------------------------------
# The public entry point


def _check(
    groups: Any, condition: Any, labels: Any, per_condition: Any
) -> tuple[list[Any], list[float], list[str]]:
    if isinstance(groups, (str, bytes)) or not hasattr(groups, "__len__"):
        raise InvalidParameterError("groups must be a sequence of experiment sets, one per condition")
    gs = [g if isinstance(g, (list, tuple)) else [g] for g in groups]
    if len(gs) < 2:
        raise InvalidParameterError(f"diagnose_across needs at least 2 conditions, got {len(gs)}")
    if condition is None:
        conds = [float(i) for i in range(len(gs))]
    else:
        conds = [real_number("condition", c) for c in condition]
    if len(conds) != len(gs):
        raise InvalidParameterError(f"condition has {len(conds)} values for {len(gs)} groups")
    if len(set(conds)) != len(conds):
        raise InvalidParameterError(f"the condition values must be distinct, got {conds}")
    names = [f"{c:g}" for c in conds] if labels is None else [str(x) for x in labels]
    if len(names) != len(gs):
        raise InvalidParameterError(f"labels has {len(names)} entries for {len(gs)} groups")
    if per_condition is not None and len(per_condition) != len(gs):
        raise InvalidParameterError(f"per_condition has {len(per_condition)} diagnoses for {len(gs)} groups")
    return gs, conds, names


def diagnose_across(
    groups: Sequence[Any],
    condition: Optional[Sequence[float]] = None,
    *,
    labels: Optional[Sequence[str]] = None,
    candidates: Optional[Sequence[str]] = None,
    alpha: float = ALPHA,
    held_out_test: bool = True,
    per_condition: Optional[Sequence[Optional[Diagnosis]]] = None,
    y_unit: str = "",
    u_unit: str = "",
    progress: Progress = None,
) -> AcrossDiagnosis:
    """One named structure for experiments at several conditions, its values free per condition.

    Parameters
    ----------
    groups : sequence of experiment sets
        One set per condition (Recordings, Measurements or AveragedPeriods, as :func:`diagnose` takes).
    condition : sequence of float, optional
        The condition variable of each group (a coil current, a temperature); default 0, 1, 2, ...
    labels : sequence of str, optional
        How each condition is named in the result (default: its value).
    candidates : sequence of str, optional
        The steady-loop terms to try (default: every one of the single-group diagnosis's; the drift terms,
        tested on period blocks, are not candidates here).
    alpha : float
        Family-wise false-alarm level of each step (Bonferroni over the candidates).
    held_out_test : bool
        Require the held-out cost, summed over the conditions, to improve before naming a term.
    per_condition : sequence of Diagnosis or Stability, optional
        Each group's own :func:`diagnose` result: compared with the joint structure, and its experiments,
        plain fit and candidate fits reused (nothing fitted twice). Given as its stability check
        (:func:`bouc_wen_id.diagnosis.stability.stability`), a term its main run named that is only an
        alternative there is not listed among the condition's terms but as an alternative.
    y_unit, u_unit : str
        Units of the output and the input, for the reported values.
    progress : bool or callable, optional (as :func:`diagnose`'s)

    Raises
    ------
    InvalidParameterError
        Fewer than two groups, conditions that do not match the groups or repeat, unknown candidates.
    """
    from . import across_locked

    args = (condition, labels, candidates, alpha, held_out_test)
    out, seen = _across(groups, *args, per_condition, (y_unit, u_unit), progress)
    if seen is None:  # fewer than two settled conditions
        return out
    prepared, names, gs = seen

    def again(fixed: dict[str, list[Any]]) -> AcrossDiagnosis:  # the bridged records read again
        bridged = [fixed.get(n, g) for n, g in zip(names, gs)]
        own = across_locked.without(per_condition, names, set(fixed))
        return _across(bridged, *args, own, (y_unit, u_unit), progress)[0]

    out = across_locked.said(out, prepared, dict(zip(names, gs)), again)  # a locked spike, as diagnose
    return readings.qualified(out, out.named, out.alternatives)  # the headline's qualifiers


def _across(
    groups: Sequence[Any],
    condition: Optional[Sequence[float]],
    labels: Optional[Sequence[str]],
    candidates: Optional[Sequence[str]],
    alpha: float,
    held_out_test: bool,
    per_condition: Optional[Sequence[Optional[Diagnosis]]],
    unit: tuple[str, str],
    progress: Progress,
) -> tuple[AcrossDiagnosis, Any]:
    """:func:`diagnose_across`'s reading, before its headline's qualifiers, and ``(prepared groups, labels,
    each condition's records as read)`` for the locked spike's check (None: fewer than two settled)."""
    from . import across_checks, across_clip, across_ring, across_said, across_zeros, ring_unchecked
    from .drift import DRIFT_TERMS
    from .run import ALL_CANDIDATES, _check_candidates

    y_unit, u_unit = unit
    t0 = time.perf_counter()
    report = reporter(progress)
    gs, conds, names = _check(groups, condition, labels, per_condition)
    gs, joined = harmonise_groups(gs, fixed=per_condition is not None)  # one unit per quantity (units.py)
    cands = tuple(c for c in _check_candidates(candidates) if c not in DRIFT_TERMS)
    alpha = real_number("alpha", alpha)
    if not 0.0 < alpha < 1.0:
        raise InvalidParameterError(f"alpha = {alpha!r} must lie in (0, 1)")
    gs, own, checks, cut = across_clip.unclipped(gs, *across_stable.unpacked(per_condition, len(gs)), names)
    units = (y_unit or joined.units.get("y", ""), u_unit or joined.units.get("u", ""))
    gs, line_notes = across_checks.lines_removed(gs, names)  # a line not locked to the input, as diagnose
    ring = across_ring.found(gs, names)  # G's free ring-down (ring_down.py)
    run = _Run(
        gs, conds, names, own, checks, cands, alpha, held_out_test, candidates, units, report, ring.sources
    )
    got = _joint(run, [None] * len(gs))
    if isinstance(got, AcrossDiagnosis):  # fewer than two settled conditions
        got = across_ring.said(got, ring, len(gs), True)
        left = [across_settling.NotSettled(k, (), w) for k, w in got.settings["not_settled_why"].items()]
        got = ring_unchecked.said(got, ring.short, across_ring.drift_read([], left))
        got = across_checks.lines_said(got, line_notes)
        return replace(got, seconds=time.perf_counter() - t0), None
    got = _zeros_resolved(run, got)  # the recordings' zeros differ inside a condition (across_zeros.py)
    prepared, terms, conditions, steps, settings, unsettled = got
    report("done", 1, 1)
    settings |= {
        "candidates": list(cands),
        "all_candidates": list(ALL_CANDIDATES),
        "alpha": alpha,
        "held_out_test": held_out_test,
        "condition": [g.condition for g in prepared],
    }
    out = _finished(prepared, terms, conditions, steps, settings, alpha, time.perf_counter() - t0)
    out = replace(  # what was left out as not settled (across_settling.py), as diagnose says it
        out,
        verdict=out.verdict
        + across_zeros.clause(prepared)  # the recordings' zeros freed (across_zeros.py)
        + across_settling.clause(prepared, unsettled)
        + across_clip.text(cut),
        notes=(
            *joined.notes,
            *out.notes,
            *across_zeros.notes(prepared),
            *across_settling.notes(prepared, unsettled),
        ),
    )
    out = across_dc.untested(out, prepared)  # an "adequate" whose DC was taken out says so (dc_untested.py)
    out = across_said.said(out, prepared, dict(zip(names, gs)), y_unit, u_unit, joined.units)  # run.py's
    out = across_ring.said(out, ring, len(gs), False)  # the rings' notes
    out = ring_unchecked.said(out, ring.short, across_ring.drift_read(prepared, unsettled))  # as diagnose
    # diagnose's clause on the lines taken out; a weak remainder's p, as diagnose says it (across_checks.py)
    out = across_checks.borderline_said(across_checks.lines_said(out, line_notes), prepared, alpha)
    return out, (prepared, names, gs)


@dataclass(frozen=True)
class _Run:
    """What :func:`diagnose_across` was asked, checked: the joint selection's inputs (:func:`_joint`)."""

    gs: Sequence[Any]
    conds: Sequence[float]
    names: Sequence[str]
    own: Sequence[Optional[Diagnosis]]
    checks: Sequence[Any]
    cands: tuple[str, ...]
    alpha: float
    held_out_test: bool
    candidates: Optional[Sequence[str]]
    units: tuple[str, str]
    report: ProgressCallback
    #: Per condition, the names of its recordings that still ring (across_ring.py).
    ringing: Sequence[frozenset[str]] = ()


_Joint = tuple[
    list[_Group],
    tuple[TermAcross, ...],
    tuple[ConditionResult, ...],
    list[JointStep],
    dict[str, Any],
    list[Any],
]


def _joint(run: _Run, zeros: Sequence[Any]) -> Any:
    """The conditions prepared (``zeros``: per condition, its recordings' zeros to free, or None) and the
    joint selection run: ``(prepared, terms, conditions, steps, settings, unsettled)``, or the result
    when fewer than two conditions settled."""
    from .. import _threads
    from . import fit_share
    from .run import _check_candidates

    cands, alpha, report = run.cands, run.alpha, run.report
    seeds = [getattr(d, "fits", None) for d in run.own]  # their candidate fits, reused (fit_share.py)
    with _threads.one_blas_thread(), fit_share.scope(seeds):
        prepared, kept, kept_checks, unsettled = [], [], [], []
        for i, (items, c, name) in enumerate(zip(run.gs, run.conds, run.names)):
            report(f"preparing condition {name}", i, len(run.gs))
            inputs.check_items(items, f"condition {name}")  # as diagnose checks them (inputs.py)
            try:
                judged = (_check_candidates(run.candidates), run.held_out_test)  # the drift's own judgement
                ring = run.ringing[i] if run.ringing else frozenset()
                prepared.append(_group(items, name, c, cands, run.own[i], alpha, judged, zeros[i], ring))
                kept.append(run.own[i])
                kept_checks.append(run.checks[i])
            except across_settling.NotSettled as e:  # no experiment settled there (across_settling.py)
                unsettled.append(e)
        settings: dict[str, Any] = {
            "not_settled": {u.label: list(u.names) for u in unsettled},
            "not_settled_why": {u.label: u.left_why for u in unsettled},  # (across_settling.RINGS: rings)
        }
        few = across_settling.too_few(prepared, unsettled)  # one structure needs two settled conditions
        if few is not None:
            left = across_settling.notes(prepared, unsettled)
            return AcrossDiagnosis(few, (), (), (), settings, 0.0, notes=left)
        if Distortion.kind in cands and not any(e.waveform.size for g in prepared for e in g.sx):
            cands = tuple(c for c in cands if c != Distortion.kind)
        steps = _select(prepared, cands, alpha, run.held_out_test, report)
        report("held-out check of the joint structure", 0, 1)
        terms = _terms(prepared, steps, run.units, alpha)
        conditions = _conditions(prepared, kept, run.held_out_test, kept_checks)
    return prepared, terms, conditions, steps, settings, unsettled


def _zeros_resolved(run: _Run, got: _Joint) -> _Joint:
    """``got``, or the joint selection again with each recording's DC free about its condition's common one
    where the recordings' zeros differ (across_zeros.py, record_zeros.py's rule) when that fits better."""
    from . import across_zeros

    prepared, terms, _, steps, _, _ = got
    status = across_verdict.judged(prepared, terms, run.alpha, steps)[0]
    if not across_zeros.triggered(prepared, steps, status):
        return got
    zeros = across_zeros.found(prepared, run.alpha / max(len(run.cands), 1))  # diagnose's level
    if zeros is None:
        return got
    by_label = {g.label: z for g, z in zip(prepared, zeros)}
    again = _joint(run, [by_label.get(name) for name in run.names])
    if isinstance(again, AcrossDiagnosis) or not across_zeros.chosen(prepared, again[0]):
        return got
    return cast(_Joint, again)


def _finished(
    prepared: Sequence[_Group],
    terms: tuple[TermAcross, ...],
    conditions: tuple[ConditionResult, ...],
    steps: Sequence[JointStep],
    settings: dict[str, Any],
    alpha: float,
    seconds: float,
) -> AcrossDiagnosis:
    """The result: the verdict by the single-group diagnosis's rules (across_verdict.py) and the wander's
    or the drift's clause."""
    wandering = ", ".join(str(g.label) for g in prepared if g.wander)
    clause = (
        f"; the baseline wanders at {wandering} (removed period by period, each experiment's DC free: an "
        "offset or each experiment's own DC there cannot be told from it)"
        if wandering
        else ""
    )
    drifting = ", ".join(str(g.label) for g in prepared if g.drifts and not g.loop_trends)
    trending = ", ".join(str(g.label) for g in prepared if g.loop_trends)
    if trending:  # the period means trend while the loop trends (zero_drift.py): the DC cannot tell which
        clause += (
            f"; the period means trend in a straight line at {trending} while the loop trends (taken out, "
            "each experiment's DC free): a drifting zero or a degrading loop's centre (an asymmetry's), "
            "which the DC cannot tell apart; an offset or each experiment's own DC there cannot be told "
            "from it"
        )
    if drifting:  # a zero drifting in a straight line (zero_drift.py)
        clause += (
            f"; the output's zero drifts at {drifting} (its straight line taken out, each experiment's DC "
            "free: an offset or each experiment's own DC there cannot be told from it)"
        )
    status, named, partial = across_verdict.judged(prepared, terms, alpha, steps)
    soft = status != "adequate" and bounds_said.targeted_across(prepared, steps)  # mu held (bounds_said.py)
    verdict = (
        across_verdict.head(status, partial, len(prepared), across_verdict.explained_fraction(prepared), soft)
        if status == "adequate" or (partial and not named)
        else _verdict(named, conditions, steps, alpha)
    )
    verdict += across_verdict.clauses(status, named, partial, steps, prepared, alpha)
    if status != "adequate":  # loop centres that differ in sign (fit_notes.centre_clause), as diagnose says
        verdict += fit_notes.centre_text(prepared)
    return AcrossDiagnosis(
        verdict + clause,
        tuple(named),
        conditions,
        tuple(steps),
        settings,
        seconds,
        tuple(g.current for g in prepared),
        status,
        tuple(partial),
        (*fit_notes.condition_notes(prepared), *across_verdict.gate_notes(prepared, alpha)),
    )


__all__ = [
    "diagnose_across",
    "AcrossDiagnosis",
    "TermAcross",
    "ConditionResult",
    "JointStep",
    "JointTrial",
    "smoothness",
]

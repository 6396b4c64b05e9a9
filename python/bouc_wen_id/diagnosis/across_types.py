"""The per-condition state of the joint selection (``_Group``) and the result types of
:func:`.across.diagnose_across` (JointTrial, JointStep, TermAcross, AcrossDiagnosis) with their small
formatters. Moved out of across.py (no behaviour change); across.py re-exports every name."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from . import (
    readings,
)
from .across_stable import ConditionResult
from .data import DiagExperiment
from .fitting import Scale
from .result import Status
from .select import (
    Alternative,
    FoldCache,
    memo_fit_with,
)
from .shared import SharedTest
from .verdict_text import details, headline


@dataclass
class _Group:
    """One condition: its prepared experiments, scale, plain fit and current model (mutable: the model)."""

    label: str
    condition: float
    sx: list[AugExperiment]
    scale: Scale
    substeps: int
    noise_dof: int
    plain: AugFit
    current: AugFit
    cache: FoldCache = field(default_factory=dict)
    #: The condition's prepared experiments (the notes and the loop centres read them).
    exps: list[DiagExperiment] = field(default_factory=list)
    #: The condition's baseline wanders (baseline.py): removed period by period, each experiment's DC free.
    wander: bool = False
    #: ... or its zero drifts in a straight line (zero_drift.py), taken out the same way.
    drifts: bool = False
    #: ... while the loop trends too: a drifting zero or a degrading loop's centre, not told apart
    loop_trends: bool = False
    #: False when some experiment's noise floor is not measured noise (quantisation or numerical accuracy):
    #: no targeted step (gate.plain_gate), as diagnose
    measured_noise: bool = True
    #: The loop drifts on the plain model (diagnose's ``before.drift_detected``): the plain model cannot pass
    #: its gate (gate.plain_passes' ``moved``)
    moved: bool = False
    #: The experiments left out as not settled (across_settling.py), as diagnose leaves them out
    left_out: tuple[str, ...] = ()
    #: ... or why else (across_settling.DEGRADES: degradation explains their drift; UNTESTED: not tested)
    left_why: str = ""
    #: Each left-out experiment's adjusted p of the trend test (settling.drift_p; NaN: not known), in
    #: ``left_out``'s order, and those left out because they still ring (ring_down.py), not for a drift
    left_p: tuple[float, ...] = ()
    rung: tuple[str, ...] = ()
    #: The recordings' zeros differ: each experiment's DC free about their common one (across_zeros.py)
    zeros: Any = None
    #: What was taken out of the recordings' zeros (a baseline.Wander, a zero_drift.Drift or the zeros above),
    #: or None: a named output offset's standard error is their centres' spread (baseline.offset_se)
    centres: Any = None
    #: Its noise is coloured at the DC in every experiment: its centre terms' DC judged between experiments
    #: (dc_between.py, across_dc.py), as diagnose judges it
    slow_dc: bool = False
    #: ``fit_with`` on this condition, once per (model, term) (select.memo_fit_with): an alternative's
    #: two-term fit is the next step's trial of that term.
    fit_term: Callable[[AugFit, str], Optional[AugFit]] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.fit_term = memo_fit_with(self.sx, self.substeps)


@dataclass(frozen=True)
class JointTrial:
    """One candidate added at every condition at once, with its combined tests."""

    term: str
    statistic: float
    p_value: float
    p_adjusted: float
    share: float
    #: Per condition: ``C0_k - C1_k`` and the term's own F-test p-value there (presence).
    improvements: tuple[float, ...]
    p_each: tuple[float, ...]
    passed: bool
    law_p_value: float = math.nan
    held_out_before: float = math.nan
    held_out_after: float = math.nan
    fits: tuple[Optional[AugFit], ...] = field(default=(), repr=False, compare=False)
    #: Per condition: whether the term is needed there on its own evidence (``p_each`` below alpha / K).
    present: tuple[bool, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "F": _n(self.statistic),
            "p_value": _n(self.p_value),
            "p_adjusted": _n(self.p_adjusted),
            "share_of_excess": _n(self.share),
            "improvement_per_condition": [_n(v) for v in self.improvements],
            "p_per_condition": [_n(v) for v in self.p_each],
            "passed_in_sample": self.passed,
            "law_p_value": _n(self.law_p_value),
            "held_out_cost_before": _n(self.held_out_before),
            "held_out_cost_after": _n(self.held_out_after),
            "present": list(self.present),
        }


@dataclass(frozen=True)
class JointStep:
    """One step of the joint selection: every candidate's trial and the chosen term (None: stop)."""

    trials: tuple[JointTrial, ...]
    chosen: Optional[str]
    #: Candidates that passed in sample with a summed improvement of at least :data:`RIVAL_IMPROVEMENT` of
    #: the chosen one's, or within its uncertainty (:func:`.across_verdict.tied`): the candidates checked
    #: as alternatives (the verdict says those of :attr:`alternatives`, as diagnose says its own).
    rivals: tuple[str, ...] = ()
    #: Candidates that passed in sample but whose law failed (element_law_test; said in the verdict).
    law_failed: tuple[str, ...] = ()
    #: Candidates refused beside a Dahl element with no effect of their own on the plain models (beside.py).
    beside: tuple[str, ...] = ()
    #: The readings the conditions cannot tell from the chosen term, by diagnose's rules (across_rules.py):
    #: its other place, a tied rival, a confounded value, one passed over for its law only.
    alternatives: tuple[Alternative, ...] = ()
    #: The chosen term's other places that fit about as well only with a non-physical value where it is
    #: present (across_rules._places): no alternative, said in the verdict as not physical.
    unphysical_places: tuple[str, ...] = ()
    #: The level its candidates were tested at (their combined F, Bonferroni over them: ``level / n``) and
    #: whether it was the targeted first step (at ``alpha / 2``: every plain model passed its gate, _go_on).
    level: float = math.nan
    targeted: bool = False
    #: The conditions whose model the step refitted before its trials (restarts.rebase: not converged).
    refitted: tuple[str, ...] = ()
    #: The set named where every candidate's law failed alone (across_pairs.py: diagnose's pair step), each
    #: member's joint trial (its fits the set's), and the sets the pair step tried (pairs.PairTrial).
    pair: tuple[str, ...] = ()
    members: tuple[JointTrial, ...] = ()
    pairs: tuple[Any, ...] = ()
    #: The model the step started from at every condition (an across_pairs.JointFit: the revisits' base).
    base: Any = field(default=None, repr=False, compare=False)
    #: Named terms dropped by the final check (across_final.py: each fails its own joint test in the final
    #: model), with their p adj; on the last step.
    unneeded: tuple[tuple[str, float], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "trials": [t.to_dict() for t in self.trials],
            "chosen": self.chosen,
            "level": _n(self.level),
            "targeted": self.targeted,
            "rivals": list(self.rivals),
            "alternatives": [a.to_dict() for a in self.alternatives],
        }
        out.update(
            {
                k: list(getattr(self, k))
                for k in ("law_failed", "beside", "unphysical_places", "refitted", "pair")
                if getattr(self, k)
            }
        )
        if self.pairs:
            out["pairs"] = [p.to_dict() for p in self.pairs]
        if self.unneeded:  # the final check dropped a named term (across_final.py)
            out["unneeded"] = [{"term": t, "p_adjusted": p} for t, p in self.unneeded]
        return out


@dataclass(frozen=True)
class TermAcross:
    """A named term across the conditions: its value per condition and how it moves with the condition."""

    term: str
    label: str
    symbol: str
    unit: str
    values: tuple[float, ...]
    standard_errors: tuple[float, ...]
    #: Whether the term is needed at each condition on that condition's own evidence (F at alpha / K).
    present: tuple[bool, ...]
    p_present: tuple[float, ...]
    #: chi-square p of a polynomial of degree 0, 1, ... in the condition through the values (within se).
    smooth_p: tuple[float, ...]
    #: The lowest degree whose p passes (None: none up to :data:`MAX_DEGREE`).
    smooth_degree: Optional[int]
    #: The nested fit with ONE value at every condition, refitted jointly, and its F test
    #: (diagnosis/shared.py; None: not computed, e.g. the joint fit found no admissible start).
    shared_fit: Optional[SharedTest] = None

    @property
    def shared(self) -> bool:
        """One value fits every condition: the nested fit's F test passes (:attr:`shared_fit`); without it,
        the values' degree-0 polynomial fits them within their se."""
        if self.shared_fit is not None:
            return self.shared_fit.shared
        return self.smooth_degree == 0

    @property
    def everywhere(self) -> bool:
        return all(self.present)

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "label": self.label,
            "symbol": self.symbol,
            "unit": self.unit,
            "values": [_n(v) for v in self.values],
            "standard_errors": [_n(v) for v in self.standard_errors],
            "present": list(self.present),
            "p_present": [_n(v) for v in self.p_present],
            "smooth_p": [_n(v) for v in self.smooth_p],
            "smooth_degree": self.smooth_degree,
            "shared": self.shared,
            "shared_fit": None if self.shared_fit is None else self.shared_fit.to_dict(),
        }


@dataclass(frozen=True)
class AcrossDiagnosis:
    """The result of :func:`diagnose_across`: the verdict first, then per term and per condition."""

    verdict: str
    terms: tuple[TermAcross, ...]
    conditions: tuple[ConditionResult, ...]
    steps: tuple[JointStep, ...]
    settings: dict[str, Any]
    seconds: float
    final_fits: tuple[AugFit, ...] = field(default=(), repr=False, compare=False)
    #: As :class:`Diagnosis`'s (across_verdict.py): "explained" only when the joint structure passes its
    #: adequacy test at every condition.
    status: Status = "unexplained"
    #: Terms of the joint structure tested but not named (a non-physical value where present, or a structure
    #: that leaves most of the summed excess), with their values per condition as :attr:`terms`.
    partial: tuple[TermAcross, ...] = ()
    #: What diagnose notes of its fits, per condition (fit_notes.condition_notes): a fit stopped at a
    #: bound, every experiment below saturation; and why the targeted step was not run (gate.py).
    notes: tuple[str, ...] = ()
    readings: tuple[Any, ...] = ()  #: as :class:`Diagnosis`'s (diagnosis/readings.py)

    @property
    def named(self) -> tuple[str, ...]:
        return tuple(t.term for t in self.terms)

    @property
    def alternatives(self) -> tuple[Alternative, ...]:
        return tuple(a for st in self.steps for a in st.alternatives)

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": "bouc_wen_id.diagnosis_across",
            "status": self.status,
            "status_text": readings.status_text(self.status, self.readings),
            "verdict": self.verdict,
            "readings": [r.to_dict() for r in self.readings],
            "terms": [t.to_dict() for t in self.terms],
            "partial": [t.to_dict() for t in self.partial],
            "conditions": [c.to_dict() for c in self.conditions],
            "steps": [s.to_dict() for s in self.steps],
            "notes": list(self.notes),
            "settings": self.settings,
            "seconds": self.seconds,
        }

    def summary(self) -> str:
        """The verdict, a table of each term per condition and one of the conditions' fits."""
        lines = [headline(self.verdict), *(f"  - {c}" for c in details(self.verdict)), ""]
        for t in (*self.terms, *self.partial):
            smooth = (
                f"degree {t.smooth_degree} in the condition" if t.smooth_degree is not None else "not smooth"
            )
            lines.append(f"{t.label} ({t.symbol}, {t.unit}): {smooth}; p per degree " + _ps(t.smooth_p))
            if t.shared_fit is not None:
                sf = t.shared_fit
                lines.append(
                    f"  one shared value refitted: {sf.value:.4g} +- {sf.standard_error:.2g}, F = "
                    f"{sf.statistic:.3g}, p {_p(sf.p_value)} ({'shared' if sf.shared else 'varies'})"
                )
            for c, v, se, pr in zip(self.conditions, t.values, t.standard_errors, t.present):
                lines.append(f"  {c.label}: {v:.4g} +- {se:.2g}{'' if pr else '  (not needed here)'}")
        lines += ["", "condition | chi2/dof plain -> final | held-out NRMSE plain, joint, per-level (terms)"]
        for c in self.conditions:
            own = "-" if c.per_level_terms is None else f"{c.held_out_per_level:.3f} ({c.per_level_text})"
            lines.append(
                f"{c.label} | {c.plain_chi2_dof:.3g} -> {c.final_chi2_dof:.3g} | {c.held_out_plain:.3f}, "
                f"{c.held_out_joint:.3f}, {own}"
            )
        if self.notes:  # as Diagnosis.summary prints its notes
            lines += ["", "notes:", *(f"  - {n}" for n in self.notes)]
        return "\n".join(lines)


def _n(v: float) -> Optional[float]:
    return v if math.isfinite(v) else None


def _p(p: float) -> str:
    """``= 0.03``, or ``< 1e-300`` where the F distribution's tail underflows."""
    return f"= {p:.2g}" if p > 0.0 else "< 1e-300"


def _ps(ps: Sequence[float]) -> str:
    return ", ".join(f"{d}: {p:.2g}" for d, p in enumerate(ps)) or "none (too few conditions)"


def _median(v: Sequence[float]) -> float:
    f = [x for x in v if math.isfinite(x)]
    return float(np.median(f)) if f else math.nan

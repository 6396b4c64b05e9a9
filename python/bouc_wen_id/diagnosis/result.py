"""The diagnosis as a value: verdict first, every claim with its statistic, p-value and comparison."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Optional

import numpy as np
from numpy.typing import NDArray

from ..terms import TERMS, Degradation
from . import adequacy, left_out, limits_void
from .data import DiagExperiment
from .gate import AFTER_NAMED_SHARE
from .locate import Localisation
from .no_fit import no_fit_reason
from .select import Alternative, HeldOut, Step
from .verdict_text import details, headline

FloatArray = NDArray[np.float64]
Status = Literal["adequate", "explained", "partly explained", "unexplained"]

#: Human names of the terms (code name -> phrase), in the order of design.md 9.1, from the registry; a term
#: that can act at more than one place is named with its place (:meth:`Term.place_label`).
TERM_LABELS = {kind: cls.place_label() for kind, cls in TERMS.items()}


def term_symbol_unit(term: str, y_unit: str, u_unit: str) -> tuple[str, str]:
    """The parameter's symbol and its units with the output's and the input's units filled in."""
    cls = TERMS[term]
    return cls.symbol, cls.units(y_unit or "[y]", u_unit or "[u]")


#: What the printed status adds when a named term has a rival reading the data do not refuse (readings.py).
NOT_ONLY = "not the only reading"
#: What the printed status adds to "adequate" when a candidate's own test passed on these data but nothing
#: was named (resolution.detected_text says which; review 35m, F8).
SEEN_NOT_NAMED = "a candidate's own test passed on these data, none named"


def status_text(status: str, readings: Sequence[Any], seen: bool = False) -> str:
    """The status as printed: ``status``, with :data:`NOT_ONLY` when one of ``readings``
    (:class:`.readings.Reading`) is a rival reading of a named term (explained, in full or in part), and the
    p-value of a weak remainder (:mod:`.borderline`: "unexplained (weak evidence of what remains: p =
    0.016; a right model is flagged so in 5 % of cases)"); "adequate" with :data:`SEEN_NOT_NAMED` when
    ``seen`` (a detection limit's own test passed on these data: ``DetectionLimit.detected_here``)."""
    from .borderline import status_words

    said = [SEEN_NOT_NAMED] if seen and status == "adequate" else []
    if status in ("explained", "partly explained") and any(getattr(r, "rival", False) for r in readings):
        said.append(NOT_ONLY)
    weak = status_words(readings) if status in ("unexplained", "partly explained") else ""
    if weak:
        said.append(weak)
    return f"{status} ({'; '.join(said)})" if said else status


@dataclass(frozen=True)
class NamedTerm:
    """A term the diagnosis named (or tried), with its value in physical units."""

    term: str
    symbol: str
    value: float
    standard_error: float
    unit: str

    @property
    def label(self) -> str:
        return TERM_LABELS.get(self.term, self.term)

    def __str__(self) -> str:
        se = f" ± {self.standard_error:.3g}" if math.isfinite(self.standard_error) else ""
        return f"{self.label} {self.symbol} = {self.value:.4g}{se} {self.unit}".rstrip()

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "label": self.label,
            "symbol": self.symbol,
            "value": self.value,
            "standard_error": self.standard_error if math.isfinite(self.standard_error) else None,
            "unit": self.unit,
        }


@dataclass(frozen=True)
class ModelSummary:
    """One fitted model: its terms, hysteresis (alpha = 1, physical units), costs and per-experiment NRMSE."""

    terms: tuple[NamedTerm, ...]
    beta: float
    gamma: float
    mu: float
    cost: float
    dof: int
    p_value: float
    nrmse: tuple[float, ...]
    outputs: tuple[FloatArray, ...] = field(repr=False)
    #: The adequacy test's chi-square (adequacy_chi2.py: a coloured noise weighed harmonic by harmonic; NaN
    #: when not kept, then ``cost`` is it).
    chi2: float = math.nan

    @property
    def chi2_dof(self) -> float:
        """The adequacy statistic per degree of freedom (``cost``'s when the statistic was not kept)."""
        return (self.chi2 if math.isfinite(self.chi2) else self.cost) / max(self.dof, 1)

    def to_dict(self) -> dict[str, Any]:
        return {
            "terms": [t.to_dict() for t in self.terms],
            "beta": self.beta,
            "gamma": self.gamma,
            "mu": self.mu,
            "cost": self.cost,
            "dof": self.dof,
            "p_value": self.p_value,
            "chi2_dof": self.chi2_dof,
            "nrmse": list(self.nrmse),
        }


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What the model leaves out, where, and how much better the fit gets once it is modelled.

    Attributes
    ----------
    status : {"adequate", "explained", "partly explained", "unexplained"}
        ``adequate``: the plain model is at the noise floor. ``explained``: the named terms bring it there
        (the final model passes its adequacy test; nothing less). ``partly explained``: the final model
        fails but they remove at least half of the excess; the share and the structure left are in the
        verdict. ``unexplained``: nothing or too little is explained, or no experiment has settled. A term
        fitted outside its physical range is never named (the verdict says "not physical").
    verdict : str
        One sentence, first in every report.
    named : tuple of NamedTerm
        Terms named (status ``explained`` or ``partly explained``).
    partial : tuple of NamedTerm
        Terms that passed the tests but leave structure unexplained (status ``unexplained``).
    alternatives : tuple of Alternative
        Terms the experiments cannot tell from a named one, with the experiment that would separate them.
    before, after : Localisation
        Where the plain and the final model miss the data.
    steps : tuple of Step
        The forward selection, every candidate with its F statistic, p-value and held-out check.
    held_out : HeldOut or None
        Leave-one-experiment-out NRMSE of the plain and the final model.
    plain, final : ModelSummary
    """

    status: Status
    verdict: str
    named: tuple[NamedTerm, ...]
    partial: tuple[NamedTerm, ...]
    alternatives: tuple[Alternative, ...]
    before: Localisation
    after: Localisation
    steps: tuple[Step, ...]
    held_out: Optional[HeldOut]
    plain: ModelSummary
    final: ModelSummary
    experiments: tuple[DiagExperiment, ...] = field(repr=False)
    explained_fraction: float
    settings: dict[str, Any]
    seconds: float
    #: The fitted plain and final augmented models in scaled units (see ``settings["scale"]``), for
    #: further held-out or what-if work; not serialised.
    plain_fit: Any = field(default=None, repr=False)
    final_fit: Any = field(default=None, repr=False)
    #: The degradation candidate's test in drift space (design.md 10.6); None when not tested.
    degradation: Any = field(default=None, repr=False)
    #: Remarks on the selection, e.g. why a candidate was not tested.
    notes: tuple[str, ...] = ()
    #: The structural candidate's test (Bouc-Wen in feedback, not a cascade: diagnosis/structure.py); None
    #: when the cascade's final model is adequate or explained. When named, ``final``, ``final_fit`` and
    #: ``held_out`` are the feedback model's and ``named`` is empty (a structure, not a term).
    structure: Any = field(default=None, repr=False)
    #: Detection limits (diagnosis/limits.py): per candidate term and place of the first selection step,
    #: the smallest value the design detects (50 % power at the step's level); () when no step ran.
    limits: tuple[Any, ...] = ()
    #: The candidate fits of its selections by the digest of their inputs (diagnosis/fit_share.py), for
    #: ``diagnose_across`` to reuse; not serialised, pickled empty.
    fits: Any = field(default=None, repr=False)
    #: What qualifies the named terms (diagnosis/readings.py): rival readings the data do not refuse and
    #: limits of the evidence, each also said in the headline in a few words; () when none.
    readings: tuple[Any, ...] = ()

    @property
    def status_text(self) -> str:
        """The status as printed: :attr:`status`, with "(not the only reading)" when a rival reading of a
        named term is not refused (diagnosis/readings.py); :attr:`status` itself is unchanged."""
        seen = any(getattr(lim, "detected_here", False) for lim in self.limits)
        return status_text(self.status, self.readings, seen)

    @property
    def named_terms(self) -> tuple[str, ...]:
        return tuple(t.term for t in self.named)

    def to_model(self, recordings: Sequence[Any], **options: Any) -> Any:
        """The model this diagnosis describes, with G, fitted to ``recordings`` (the ones diagnosed).

        The Wiener cascade with the named terms (each starting at its diagnosed value), fitted by
        :func:`~bouc_wen_id.fit_time_domain` with the sine recordings' declared settling left out of the
        residuals (``lead_in``, as identify and diagnose leave it out). Returns a
        :class:`~bouc_wen_id.TimeDomainFit`: its ``.plant`` goes to ``save_model``, ``export``,
        ``validate`` and the compensator. ``options`` go to ``fit_time_domain`` (``order``, ``delay``,
        ``lead_in``, ...). An adequate diagnosis gives the plain cascade; a named structure (feedback) is
        refused by name (``fit_feedback`` fits it).
        """
        from .to_model import diagnosis_model

        return diagnosis_model(self, recordings, **options)

    @property
    def headline(self) -> str:
        """The verdict's first clause: the named terms with their values and share, or what is left."""
        return headline(self.verdict)

    @property
    def details(self) -> tuple[str, ...]:
        """The verdict's further clauses, in order: alternatives, terms not named and why, data notes."""
        return tuple(details(self.verdict))

    def summary(self) -> str:
        """A plain-text report: the verdict (headline, then its further clauses one per line), the selection
        table, the held-out comparison and where the models miss."""
        lines = [f"Diagnosis: {self.headline}", *(f"  - {c}" for c in self.details), ""]
        for label, m in (("plain", self.plain), ("final", self.final)):
            lines.append(f"{label} model: chi2/dof = {m.chi2_dof:.3g} (p = {m.p_value:.2g})")
        lines.append(f"share of the plain model's excess explained: {100 * self.explained_fraction:.1f} %")
        for term, why in dict(self.settings.get("skipped", {})).items():
            lines.append(f"{TERM_LABELS.get(term, term)}: {why}")
        for a in self.alternatives:
            rival, term = TERM_LABELS.get(a.rival, a.rival), TERM_LABELS.get(a.term, a.term)
            law = (
                ""
                if not math.isfinite(a.law_p_value)
                else f", though its law fails (p = {a.law_p_value:.2g})"
            )
            why = (
                f"parameter correlation {a.correlation:+.3f}"
                if math.isfinite(a.correlation)  # a set's rival (pairs.py): no one parameter pair
                else "improvements within their uncertainty"
            )
            lines.append(
                f"alternative: {rival} fits as well as {term}{law} ({why}); to separate them: "
                f"{a.separating_experiment}"
            )
        for k, st in enumerate(self.steps, 1):
            lines.append("")
            chosen = " + ".join(st.pair) + " (together)" if getattr(st, "pair", ()) else (st.chosen or "none")
            lines.append(
                f"step {k}{_targeted(st)}: from chi2 = {st.before_cost:.6g} (dof {st.before_dof}); "
                f"chosen: {chosen}"
            )
            if math.isfinite(st.refitted_from):  # restarts.rebase: the step's base had not converged
                lines.append(
                    f"  (its base refitted from chi2 = {st.refitted_from:.6g}: unrelated candidates lowered "
                    "that by about the same amount, and the model without any of them reached it too)"
                )
            lines.append(f"  {'term':<12} {'chi2':>12} {'F':>10} {'p adj':>9} {'share':>7} {'held-out':>10}")
            for t in st.trials:
                ho = "" if t.held_out is None else ("better" if t.held_out.improves else "worse")
                row = f"  {t.term:<12} {t.cost:12.6g} {t.statistic:10.4g} {t.p_adjusted:9.2g} {t.share:7.2f}"
                lines.append(
                    f"{row} {ho:>10}" if math.isfinite(t.cost) else f"  {t.term:<12} {no_fit_reason(t.term)}"
                )
        deg = self.degradation
        if deg is not None:
            lines.append("")
            ho = "better" if deg.held_out_improves else ("worse" if deg.held_out_after else "")
            lines.append(
                f"{deg.term} (drift space, {len(deg.experiments)} experiments): chi2 {deg.cost0:.6g} -> "
                f"{deg.cost1:.6g} (dof {deg.dof0}), F = {deg.statistic:.4g}, p adj = {deg.p_adjusted:.2g}, "
                f"share {deg.share:.2f}, held-out {ho} (block NRMSE ratio {deg.held_out_nrmse_ratio:.3f})"
            )
            rival = deg.rival
            if rival is not None:  # the other drift term (strength or stiffness), tested alone and given it
                lines.append(
                    f"  rival {rival.term}: chi2 -> {rival.cost1:.6g}, p adj = {rival.p_adjusted:.2g}, share "
                    f"{rival.share:.2f}; given {deg.term}: p adj = {deg.rival_p_adjusted:.2g}; columns' "
                    f"correlation {deg.correlation:.2f}{' (an alternative)' if deg.rival_alternative else ''}"
                )
            if math.isfinite(deg.gain_p_adjusted):  # the rival reading: a drifting gain (gain_drift.py)
                lines.append(
                    f"  rival output gain drifting in each record: chi2 -> {deg.gain_cost:.6g}; {deg.term} "
                    f"given it: p adj = {deg.gain_p_adjusted:.2g}"
                    f"{' (a drifting gain fits as well: not named)' if deg.gain_alternative else ''}"
                )
        for note in self.notes:
            lines.append(note)
        if self.structure is not None and self.structure.named:  # the feedback structure (structure.py)
            lines.append(
                "feedback structure: "
                + ", ".join(f"{k} = {v:.4g} ± {se:.2g}" for k, v, se in self.structure.parameters)
            )
        lines += limits_void.summary_lines(self)  # detection limits (limits.py), void on a failed fit
        if self.held_out is not None:
            lines.append("")
            lines.append("held-out NRMSE (one experiment left out, physics fitted on the others):")
            hold = self.held_out
            for j, nb, na in zip(hold.folds, hold.nrmse_before, hold.nrmse_after):
                src = self.experiments[j].source
                lines.append(
                    f"  {src:<32} plain {nb:.4f}  final {na:.4f}  ratio {na / nb if nb else math.nan:.3f}"
                )
        lines.append("")
        lines += left_out.summary_lines(self)  # the records left out, with why (left_out.py)
        lines.append(f"where the plain model misses: {adequacy.where(self, final=False)}")  # adequacy.py
        lines.append(f"where the final model misses: {adequacy.where(self, final=True)}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "status_text": self.status_text,
            "verdict": self.verdict,
            "headline": self.headline,
            "readings": [r.to_dict() for r in self.readings],
            "named": [t.to_dict() for t in self.named],
            "partial": [t.to_dict() for t in self.partial],
            "alternatives": [a.to_dict() for a in self.alternatives],
            "explained_fraction": self.explained_fraction,
            "before": adequacy.localisation_dict(self, final=False),  # adequate by one rule (adequacy.py)
            "after": adequacy.localisation_dict(self, final=True),
            "steps": [s.to_dict() for s in self.steps],
            "held_out": None if self.held_out is None else self.held_out.to_dict(),
            "plain": self.plain.to_dict(),
            "final": self.final.to_dict(),
            "experiments": [e.to_dict() for e in self.experiments],
            "settings": self.settings,
            "seconds": self.seconds,
            Degradation.kind: None if self.degradation is None else self.degradation.to_dict(),
            "notes": list(self.notes),
            "structure": None if self.structure is None else self.structure.to_dict(),
            "detection_limits": [lim.to_dict() for lim in self.limits],
            "detection_limits_void": limits_void.void(self),  # computed on a failed fit (limits_void.py)
            **left_out.to_dict(self),  # the records left out of its statistics, with why (left_out.py)
        }

    def to_json(self, indent: int = 2) -> str:
        """Strict JSON (NaN and infinities become null); read back by :func:`bouc_wen_id.load_diagnosis`
        (a file) or ``SavedDiagnosis.from_json`` (this text)."""
        return json.dumps(clean(self.to_dict()), indent=indent, allow_nan=False)


def _targeted(st: Step) -> str:
    """A step's label in the summary: which model the global test accepted before a targeted step, and the
    level its candidates shared (gate.targeted_level)."""
    if not st.targeted:
        return ""
    if getattr(st, "after_named", False):
        return (
            " (targeted: the global test accepted the model with the terms named before; its candidates at "
            f"{AFTER_NAMED_SHARE:g} alpha)"
        )
    return " (targeted: the global test accepted the plain model)"


def clean(v: Any) -> Any:
    """``v`` with NumPy scalars and arrays made plain and non-finite floats made None."""
    if isinstance(v, dict):
        return {str(k): clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [clean(x) for x in v]
    if isinstance(v, np.ndarray):
        return clean(v.tolist())
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v

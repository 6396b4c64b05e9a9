"""How strong the evidence is for what a verdict leaves unexplained (issue 18: honest verdicts).

When the only evidence that structure remains is the adequacy test at a modest p-value, the verdict said it
as a fact: review 35's ``null_hiq`` (a plain plant with a Q = 10 resonance, 1 of 5 seeds) was told
"unexplained structure remains spread over the cycle" at p = 0.016, the test's own false-alarm rate at work,
and ``kx_mu2barely`` was told "explained in part ... unexplained structure remains along the loading branch"
at a final p = 0.03. A right model fails the test in ``alpha`` of cases (the plain model's global test and
its targeted step share ``alpha``; a final model is tested at ``alpha``), so a p-value within a factor
:data:`FACTOR` of ``alpha`` is weak evidence: the verdict then says "may remain", with the p-value and that
rate. Smaller p-values, and a remainder shown by a loop still drifting (its own test), are said as before.

The status is unchanged (``d.status`` and the CLI's exit codes, the benches' scoring); the qualifier is a
:class:`.readings.Reading` of kind :data:`KIND` (``rival=False``), printed in :func:`.result.status_text`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from .verdict_text import clauses

if TYPE_CHECKING:
    from .result import Diagnosis

#: A p-value at or above ``alpha / FACTOR`` (and below the level) is weak evidence of structure.
FACTOR = 10.0
#: The reading's kind (readings.py, result.status_text).
KIND = "borderline"
#: The words the verdict's headline carries in place of "remains" (readings.py finds the reading by them).
MARK = "may remain (p = "


def weak(p_value: float, alpha: float, drifting: bool = False) -> bool:
    """Whether a failed adequacy test at ``p_value`` (level ``alpha``) is the only, and weak, evidence."""
    return bool(math.isfinite(p_value) and alpha / FACTOR <= p_value < alpha and not drifting)


def remains(p_value: float, alpha: float, drifting: bool = False, rate: float = math.nan) -> str:
    """ "remains", or, on weak evidence (:func:`weak`), "may remain (p = ...; a right model is flagged so in
    ... % of cases)": in ``alpha`` of them (``rate``: another share, when a model is tested more than once:
    at each of several conditions, :func:`across_rate`)."""
    if not weak(p_value, alpha, drifting):
        return "remains"
    rate = alpha if not math.isfinite(rate) else rate
    return f"{MARK}{p_value:.2g}; a right model is flagged so in {100 * rate:.3g} % of cases)"


def across_rate(alpha: float, k: int) -> float:
    """How often a right model fails its adequacy test at one condition or more of ``k``, each tested at
    ``alpha`` (diagnose_across's status: adequate only when it passes at every one)."""
    return 1.0 - (1.0 - alpha) ** max(k, 1)


def of_headline(head: str) -> str:
    """The qualifier's words in a headline ("" when it has none): "p = 0.016; a right model ... cases"."""
    i = head.find(MARK)
    if i < 0:
        return ""
    j = head.find(")", i)
    return head[i + len(MARK) - len("p = ") : j] if j >= 0 else ""


#: The verdict's words on what is left (run._verdict), which :func:`qualified` qualifies.
REMAINS = "unexplained structure remains"


def qualified(d: Diagnosis, alpha: float) -> Diagnosis:
    """``d`` (a :class:`.result.Diagnosis`) whose "unexplained structure remains" (its headline, or the
    clause after an "explained in part" headline) says "may remain (p = ...)" when the final model's failed
    adequacy test is the only evidence and weak (:func:`weak`); ``d`` itself otherwise. Other evidence keeps
    the words: a loop still drifting (after; before, unless a named degradation took that drift up), a
    candidate whose tests passed with a failed law."""
    from .drift import DRIFT_TERMS

    if d.status not in ("unexplained", "partly explained"):
        return d
    # The plain model's drift is evidence of what remains only where no named degradation took it up: a
    # named one's correction is in the final model, whose own drift test (``after``) says whether any is
    # left (bench48: nu 10x seed 38010, final p = 0.035, the same noise on the plain plant p = 0.024).
    took = any(t.term in DRIFT_TERMS for t in d.named)
    other = (d.before.drift_detected and not took) or d.after.drift_detected
    other = other or any(st.law_failed for st in d.steps)
    if not weak(float(d.final.p_value), alpha, other):
        return d
    said = qualified_text(d.verdict, float(d.final.p_value), alpha)
    return d if said == d.verdict else replace(d, verdict=said)


def qualified_text(
    verdict: str, p_value: float, alpha: float, rate: float = math.nan, prefix: str = ""
) -> str:
    """``verdict`` whose "unexplained structure remains" (its headline or the clause after it, after
    ``prefix``) says "may remain (p = ...)" (:func:`remains`; the caller has found the evidence weak,
    :func:`weak`). One wording for diagnose (:func:`qualified`) and diagnose_across (across_checks.py)."""
    for c in clauses(verdict)[:2]:
        if c.startswith(prefix + REMAINS):
            said = c.replace(REMAINS, "unexplained structure " + remains(p_value, alpha, rate=rate), 1)
            i = verdict.find(c)
            return verdict[:i] + said + verdict[i + len(c) :]
    return verdict


#: The reading's words before the p-value (its parentheses keep the verdict's clauses whole).
WORDS = "weak evidence of what remains"


def reading_words(head: str) -> str:
    """The reading's words for a clause that carries the qualifier ("" when it does not)."""
    inner = of_headline(head)
    return f"{WORDS} ({inner})" if inner else ""


def status_words(readings: Sequence[Any]) -> str:
    """What :func:`.result.status_text` adds for a weak remainder ("" without one): "weak evidence of what
    remains: p = 0.016; a right model is flagged so in 5 % of cases"."""
    for r in readings:
        if getattr(r, "kind", "") == KIND:
            return f"{WORDS}: " + str(r.words)[len(WORDS) + 2 : -1]
    return ""

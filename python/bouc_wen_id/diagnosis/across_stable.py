"""``diagnose_across``'s conditions read with their stability checks (stability.py).

A condition's own diagnosis may name a term that its preprocessing variants do not all name: its checked
verdict (``Stability.verdict``) says it as an alternative, not a finding. ``diagnose_across`` given that
check (a :class:`~bouc_wen_id.diagnosis.stability.Stability` in ``per_condition``) lists only the
findings as the condition's own terms and the rest as its alternatives, so that the across result does not
name per condition what the condition's own verdict does not (the MR damper's 0.75 A level: degradation
named by its main run, in 2 of 4 preprocessing variants).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

from ..errors import InvalidParameterError
from .result import Diagnosis


def _n(v: float) -> Optional[float]:
    return v if math.isfinite(v) else None


@dataclass(frozen=True)
class ConditionResult:
    """The joint structure at one condition, beside its own diagnosis when that was given."""

    label: str
    condition: float
    experiments: int
    plain_chi2_dof: float
    final_chi2_dof: float
    final_p_value: float
    #: Median over the held-out folds: the plain model's NRMSE and the joint structure's.
    held_out_plain: float
    held_out_joint: float
    #: The per-condition diagnosis (when given): its named terms and its held-out NRMSE (median). Given with
    #: its stability check (a :class:`~bouc_wen_id.diagnosis.stability.Stability`), only the terms that are
    #: findings there: a term its main run named but the preprocessing variants do not all name is in
    #: ``per_level_alternatives`` (named in k of n runs: an alternative, not a finding), as the condition's
    #: own checked verdict says it.
    per_level_terms: Optional[tuple[str, ...]] = None
    held_out_per_level: float = math.nan
    per_level_alternatives: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        out = {k: _n(v) if isinstance(v, float) else v for k, v in self.__dict__.items()}
        out["per_level_terms"] = None if self.per_level_terms is None else list(self.per_level_terms)
        out["per_level_alternatives"] = list(self.per_level_alternatives)
        return out

    @property
    def per_level_text(self) -> str:
        """The condition's own structure: its terms, then its alternatives said as such ("-" when its own
        diagnosis was not given)."""
        if self.per_level_terms is None:
            return "-"
        own = ", ".join(self.per_level_terms) or "none"
        if self.per_level_alternatives:
            alts = self.per_level_alternatives
            said = "an alternative, not a finding" if len(alts) == 1 else "alternatives, not findings"
            own += f"; {', '.join(alts)}: {said}"
        return own


def unpacked(per_condition: Optional[Sequence[Any]], n: int) -> tuple[list[Any], list[Any]]:
    """(each condition's own diagnosis or None, its stability check or None) from ``per_condition`` (a
    Diagnosis, a Stability or None per condition; None: n Nones). Anything else is a named error."""
    from .stability import Stability

    if per_condition is None:
        return [None] * n, [None] * n
    own: list[Any] = []
    checks: list[Any] = []
    for i, x in enumerate(per_condition):
        if isinstance(x, Stability):
            own.append(x.main)
            checks.append(x)
        elif x is None or isinstance(x, Diagnosis):
            own.append(x)
            checks.append(None)
        else:
            raise InvalidParameterError(
                f"per_condition[{i}]: a Diagnosis, its Stability or None, not {type(x).__name__}"
            )
    return own, checks


def split(d: Diagnosis, check: Any) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(the terms ``d`` names that are findings, those that are alternatives) under ``check`` (its
    Stability, or None: every named term a finding). A check that compared no variant (every variant
    failed) revises nothing, as its verdict."""
    named = tuple(t.term for t in d.named)
    if check is None or not check.checked:
        return named, ()
    alternatives = set(check.alternatives)
    return (
        tuple(t for t in named if t not in alternatives),
        tuple(t for t in named if t in alternatives),
    )


def checked(a: Any, checks: Sequence[Any]) -> Any:
    """``a`` (an AcrossDiagnosis run with the conditions' own diagnoses) with each condition's own terms
    read against its stability check (``checks``: a Stability or None per condition of ``a``, in its
    order), as ``diagnose_across`` given the checks in ``per_condition`` lists them; nothing refitted. A
    check whose main run is not the diagnosis the condition was compared with cannot be read there: a named
    error."""
    from dataclasses import replace

    if len(checks) != len(a.conditions):
        raise InvalidParameterError(f"{len(checks)} stability checks for {len(a.conditions)} conditions")
    out = []
    for c, st in zip(a.conditions, checks):
        if st is None or c.per_level_terms is None:
            out.append(c)
            continue
        main = sorted(t.term for t in st.main.named)
        if main != sorted((*c.per_level_terms, *c.per_level_alternatives)):
            raise InvalidParameterError(
                f"condition {c.label}: the stability check's main run names {main}, the condition's own "
                f"diagnosis {sorted((*c.per_level_terms, *c.per_level_alternatives))}"
            )
        terms, alts = split(st.main, st)
        out.append(replace(c, per_level_terms=terms, per_level_alternatives=alts))
    return replace(a, conditions=tuple(out))

"""Both drift terms at once: the record needs the rival drift term beside the named one.

The drift stage (:func:`.drift.compare`) names one drift term, strength (nu) or stiffness (eta)
degradation, and tests the other given it (a partial F on the two-column fit in the period blocks). When
that test passes, the record needs both: the summary said so, the verdict did not (review 34, problem 4:
strength 0.085 with stiffness 0.05 named only delta_eta = 0.0545 +- 0.0012, 3.8 se off, and blamed the rest
on "physics outside the library"). Here both are said, in the summary's note and in the verdict, with the
two-column fit's values (first order, in the period blocks); the steady fit is corrected for the named
term only, so the verdict says that the structure left may be the rival's.
"""

from __future__ import annotations

import math
from typing import Optional

from .drift import DegradationTest
from .result import TERM_LABELS, term_symbol_unit


def needs_both(deg: Optional[DegradationTest], named: bool, alpha: float) -> bool:
    """Whether the named drift term's rival passes its partial F-test given it (the record needs both)."""
    return bool(
        deg is not None
        and named
        and deg.rival is not None
        and math.isfinite(deg.rival_p_adjusted)
        and deg.rival_p_adjusted < alpha
    )


def _joint_values(deg: DegradationTest, units: tuple[str, str]) -> str:
    """': fitted together in the period blocks (first order), delta_eta = .. +- .. and delta_nu = ..'."""
    assert deg.rival is not None
    if len(deg.joint) != 2 or not all(math.isfinite(v) for v in deg.joint):
        return ""
    parts = []
    for term, v, se in zip((deg.term, deg.rival.term), deg.joint, deg.joint_se):
        sym, unit = term_symbol_unit(term, *units)
        e = f" ± {se:.3g}" if math.isfinite(se) else ""
        parts.append(f"{sym} = {v:.4g}{e} {unit}".rstrip())
    return f": fitted together in the period blocks (first order), {' and '.join(parts)}"


def note(deg: Optional[DegradationTest], named: bool, alpha: float, units: tuple[str, str]) -> Optional[str]:
    """The summary's note when the record needs both drift terms (None otherwise)."""
    if not needs_both(deg, named, alpha):
        return None
    assert deg is not None and deg.rival is not None
    return (
        f"the period record also needs {deg.rival.term} beside {deg.term} (partial F, adjusted p = "
        f"{deg.rival_p_adjusted:.2g}){_joint_values(deg, units)}; both may act, and only {deg.term} is "
        "modelled"
    )


def text(deg: Optional[DegradationTest], named: bool, alpha: float, units: tuple[str, str]) -> str:
    """The verdict's clause when the record needs both drift terms ('' otherwise)."""
    if not needs_both(deg, named, alpha):
        return ""
    assert deg is not None and deg.rival is not None
    rival, term = TERM_LABELS.get(deg.rival.term, deg.rival.term), TERM_LABELS.get(deg.term, deg.term)
    return (
        f"; the period record needs {rival} beside {term}{_joint_values(deg, units)} (the second's partial F "
        f"given the first, adjusted p = {deg.rival_p_adjusted:.2g}); the steady fit is corrected for {term} "
        f"only, so structure left over may be {rival}'s"
    )


__all__ = ["needs_both", "note", "text"]

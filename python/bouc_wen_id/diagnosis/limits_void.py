"""Detection limits on a model that fails its adequacy test are no limits (review 35, problem 2).

The limits (limits.py) are each first-step candidate's value detected with 50 % / 90 % power, worked out on
the step's starting model. When the final model still fails its adequacy test (p below alpha:
"unexplained", or "partly explained" with a failing fit), the misfit that no tested term explains sits in
that model's residual, and a term it hides is not excluded below any value: reviewer 35's cu_h3 (a drive
with a 3 % third harmonic and a viscous term on u, c = 0.01) was "unexplained" while its summary printed
"viscous damping on the measured input u |c| < 0.0049; 90 %: 0.0056". :func:`void` says when; the
summary, the report and the JSON say the limits are void then, without their values as limits.
"""

from __future__ import annotations

from typing import Any

from . import adequacy
from .adequacy import DEFAULT_ALPHA as DEFAULT_ALPHA  # carry_refresh reads it here


def void(d: Any) -> bool:
    """Whether ``d``'s detection limits are void: its final model fails its adequacy test by the one rule
    every statement of adequacy follows (adequacy.final_passes: ``alpha`` with named terms, ``alpha / 2``
    for the plain model's global test; a "partly explained" verdict whose final model passes, a term left
    out as not physical, keeps them); review 36's null_spk (p = 0.042) read "adequate" with its limits and
    then called them void at ``alpha``."""
    return bool(d.limits) and not adequacy.final_passes(d)


def reason(d: Any) -> str:
    """Why they are void (the final model's test), in words."""
    f = d.final
    return (
        f"void: the model they are computed on fails its adequacy test (final chi2/dof = "
        f"{f.cost / max(f.dof, 1):.3g}, p = {f.p_value:.2g}), so a term the misfit hides is not excluded "
        "below any value"
    )


def summary_lines(d: Any) -> list[str]:
    """The summary's lines on the detection limits (none without limits)."""
    if not d.limits:
        return []
    if void(d):
        return ["", f"detection limits: {reason(d)}"]
    head = "detection limits (first step: the value detected with 50 % / 90 % power):"
    named = {n.term: n for n in getattr(d, "named", ())}
    lines = []
    for lim in d.limits:
        tail = lim.summary_tail() + (_named_tail(named.get(lim.term)) if named else "")
        lines.append(f"  {lim}; 90 %: {lim.limit_90:.2g}{tail}")
    return ["", head, *lines]


def _named_tail(n: Any) -> str:
    """Beside the limit of a term the verdict names: its value there (review 36b: "|c| < 0.0026" printed
    under a named c = 0.007918 read as a bound on it)."""
    if n is None:
        return ""
    return (
        f"; named in the verdict: {n.symbol} = {n.value:.4g} ± {n.standard_error:.2g} {n.unit}".rstrip()
        + " (the limit is what the plain model's first step could detect)"
    )

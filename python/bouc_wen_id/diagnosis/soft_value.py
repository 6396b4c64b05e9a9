"""A named term's value beside mu held at its bracket's lower end (review 47 failure 1).

When the final fit holds the hysteresis exponent at the lower end of its bracket (mu = 1; the identification
assumes mu >= 1, :mod:`.bounds_said`) and the final model passes, its terms are named (an adequate final
model within the bracket stands), but their values are read through a loop that may be softer than mu = 1
allows: on a mu = 0.75 element under AR(1) noise the asymmetry was named 0.161 +- 0.0025 against a truth of
0.12 (z 16.6) and the pinching 0.59 +- 0.011 against 0.68 (z -7.7), each a plain "explained". The model
cannot fit mu < 1 (its sensitivities are unbounded there), so the bias cannot be measured; what can be is
how far each named value moves when mu is held one step inside the bracket (:data:`MU_STEP`): the final
model refitted with mu >= :data:`MU_STEP`. A term whose value moves by more than :data:`MOVES_SE` of its
standard error depends on the exponent beyond its noise, and the verdict says both values and that a loop
as much softer may move it about as far the other way (a linear reading: on review 47's mu = 0.75 element
the asymmetry read 0.161 at mu = 1 and 0.206 at 1.25, so about 0.116 at 0.75; its truth was 0.120), or,
when it moves by more than half itself, that the exponent sets it as much as the data do. A term whose
value does not move is not caveated (the value does not lean on mu), nor is anything said when mu is inside
its bracket: a caveat that fires on every case would be noise.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit, AugParams, fit_augmented
from ..errors import BoucWenIdError, BudgetExceededError
from . import free_dc
from .bounds_said import SOFTER
from .drift import DRIFT_TERMS
from .fitting import Scale, physical, stall_rules
from .result import NamedTerm

#: mu's lower end for the refit: one step inside the bracket (a quarter of the way from 1 to the classic 2).
MU_STEP = 1.25
#: A value that moves by more than this many of its standard errors depends on the exponent.
MOVES_SE = 2.0
#: A move of at most this share of the value is read linearly (a loop as much softer: as far the other way).
NEAR = 0.5
#: The words that open the clause (tests and callers find it by them).
MARK = "values read with mu held at the lower end of its bracket"


def refit(
    exps: Sequence[AugExperiment], final: AugFit, substeps: int, mu_lo: float = MU_STEP
) -> Optional[AugFit]:
    """The final model refitted on ``exps`` with mu held at least at ``mu_lo`` (each free DC free, as
    :func:`.fitting.fit_from`); None when the fit fails."""

    def inner(e: Sequence[AugExperiment], start: AugParams, n: int, m: int) -> Optional[AugFit]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            stall = stall_rules(e, start)  # fitting._fit_from's, with mu held at mu_lo
            return fit_augmented(e, start, max_iter=m, substeps=n, mu_lo=mu_lo, stall=stall)

    start = replace(final.params, mu=max(float(final.params.mu), mu_lo * (1.0 + 1e-6)))
    try:
        fit = free_dc.fit(exps, start, substeps, 200, inner)
    except BudgetExceededError:
        raise
    except BoucWenIdError:
        return None
    return fit if fit is not None and math.isfinite(fit.cost) else None


def moved(named: Sequence[NamedTerm], fit: Optional[AugFit], s: Scale) -> tuple[tuple[NamedTerm, float], ...]:
    """The steady named terms (a drift term's test is on the drift, not on the loop's shape) whose value in
    ``fit`` (the refit at :data:`MU_STEP`) lies more than :data:`MOVES_SE` of their standard error away."""
    if fit is None:
        return ()
    out = []
    for t in named:
        if t.term in DRIFT_TERMS or t.term not in fit.params.terms:
            continue
        v, _ = physical(fit, s, t.term)
        if math.isfinite(v) and abs(v - t.value) > MOVES_SE * t.standard_error:
            out.append((t, v))
    return tuple(out)


def _other_way(value: float, at_step: float, mu: float) -> str:
    """The linear reading a loop as much softer gives (``value`` moved back by what ``at_step`` moved it),
    said only when the move is at most :data:`NEAR` of the value; a larger one (a fit that went elsewhere
    with mu held inside, where the linear reading would turn the sign) is said as such."""
    if abs(at_step - value) <= NEAR * abs(value):
        return (
            f"; a loop as much softer, mu = {2 * mu - MU_STEP:g}, may move it about as far the other way, to "
            f"about {2 * value - at_step:.4g}"
        )
    return ": far enough that the value is set by the exponent as much as by the data"


def text(
    held: Any,
    status: str,
    named: Sequence[NamedTerm],
    exps: Sequence[AugExperiment],
    final: AugFit,
    s: Scale,
    substeps: int,
) -> str:
    """The clause on the named values when ``held`` (:class:`.bounds_said.Beyond`) says the final fit holds
    mu at its lower end and the verdict names terms that :func:`.bounds_said.apply` left named; ``""`` when
    mu is inside its bracket, nothing is named, or no named value moves with mu beyond its noise."""
    if held is None or held.mu_face != "lower" or status not in ("explained", "partly explained"):
        return ""
    steady = tuple(t for t in named if t.term not in DRIFT_TERMS and math.isfinite(t.standard_error))
    if not steady:
        return ""
    got = moved(steady, refit(exps, final, substeps), s)
    if not got:
        return ""
    each = "; ".join(
        f"{t.label} {t.symbol} = {t.value:.4g} at mu = {held.mu:.3g}, {v:.4g} with mu held at {MU_STEP:g} "
        f"({abs(v - t.value) / t.standard_error:.0f} se away{_other_way(t.value, v, held.mu)})"
        for t, v in got
    )
    one = len(got) == 1
    return (
        f"; {MARK} (mu = {held.mu:.3g}; the identification's range is mu >= 1): the loops may be {SOFTER}, "
        f"and the named value{'' if one else 's'} depend{'s' if one else ''} on the exponent beyond "
        f"{'its' if one else 'their'} standard error, so read {'it' if one else 'them'} as conditional on "
        f"mu: {each}"
    )


__all__ = ["MARK", "MOVES_SE", "MU_STEP", "NEAR", "moved", "refit", "text"]

"""When a reading beyond its physical range decides the verdict (review 35m, F6 and F9; issue 18: "a value
outside its physical range is never named: ... report 'not physical' and what that suggests", and "nothing
false said").

Two questions :mod:`.bounds_said` asks of a first-step candidate refused only by its bound:

- **Does it fit clearly better than the final model?** (:func:`clearly_better`). The tie margin of
  :func:`.bounds_said._tie` is the noise of one improvement (``sd ~ 2 sqrt(Delta C s2)``): it grows with the
  misfit; two fits of the *same* data are compared on the difference of their costs, whose noise is
  ``2 e . (y_A - y_B)``, of sd ``2 sqrt(D s2)`` with ``D`` the chi-square distance between the two fitted
  models (:func:`.design_twin.distance`). A negative stiffness on u at k = -0.0479 fitted 39 chi2 better than
  the three physical stand-ins the selection kept (sensor lag + Dahl on x), inside the tie margin of 73 but
  far beyond its own noise; the verdict said "explained by" the stand-ins on that noise draw and named
  the stiffness's reading on another. The difference is beyond chance when it exceeds both
  :data:`.select.TIE_SD` sd of that noise and the chi-square quantile an F test of one parameter calls
  chance at the step's level (times the residual variance when above 1).
- **Has it an exact physical twin?** (:func:`physical_twin`). At one frequency a stiffness on x and an
  inertia on x are the same function (``m xddot = -m w^2 x``): a negative stiffness is a positive mass. The
  verdict then says the physical reading first, with the one beyond its range as its alternative, not a
  P-Delta mechanism alone (F9: m_x = 0.006 at 3 rad/s read "k = -0.0445 ... P-Delta or wrong sign" while
  inertia on x at m = +0.00495 fitted identically; the across verdict named the inertia).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from .design_twin import EXACT, _limit, distance, separating_text
from .fitting import Scale, physical
from .result import NamedTerm, term_symbol_unit
from .select import TIE_SD, Step, Trial, _separating, at_null, place_admissible


def clearly_better(
    exps: Sequence[AugExperiment], better: AugFit, worse: AugFit, dof: int, level: float
) -> bool:
    """Whether ``better`` fits ``exps`` by more than chance over ``worse`` (module docstring): the cost
    difference above :data:`.select.TIE_SD` times ``2 sqrt(D s2)`` and above ``s2`` times the chi-square
    quantile of one degree of freedom at ``level``; False when either cannot be computed."""
    diff = worse.cost - better.cost
    if not (math.isfinite(diff) and diff > 0.0 and 0.0 < level < 1.0):
        return False
    d = distance(exps, better, worse)
    if not math.isfinite(d):
        return False
    s2 = max(1.0, better.cost / dof) if dof > 0 else 1.0
    # scipy.special, not scipy.stats: the package's import must not load scipy.optimize (test_tfit)
    from scipy.special import chdtri  # type: ignore[import-untyped]

    chance = float(chdtri(1, level)) * s2
    return diff > max(TIE_SD * 2.0 * math.sqrt(d * s2), chance)


@dataclass(frozen=True)
class PhysicalTwin:
    """A physical candidate whose fit alone gives the same averaged periods as a reading beyond its range."""

    named: NamedTerm  #: the twin with its value in physical units
    trial: Trial
    #: Why the selection did not name it ("" when no reason is recorded on its trial).
    reason: str
    exact: bool  #: the same function numerically, not only within the noise
    separating_experiment: str


def _reason(tr: Trial) -> str:
    if tr.held_out is not None and not tr.held_out.improves:
        return "its held-out prediction was worse than the plain model's"
    if not tr.law_holds:
        return "its value differs between experiments"
    return ""


def physical_twin(
    exps: Sequence[AugExperiment],
    st: Step,
    tr: Trial,
    level: float,
    s: Scale,
    units: tuple[str, str],
    substeps: int,
) -> Optional[PhysicalTwin]:
    """The closest candidate of step ``st`` that passed its F test at ``level`` with a physical value away
    from its null and whose fit is within the noise of ``tr``'s (:func:`.design_twin._limit`), or None."""
    if tr.fit is None:
        return None
    limit = _limit(exps, tr.fit, tr.cost)
    best: Optional[tuple[float, Trial]] = None
    for o in st.trials:
        f = o.fit
        if o.term == tr.term or f is None or o.term not in f.params.terms:
            continue
        if not (math.isfinite(o.p_adjusted) and o.p_adjusted < level and abs(o.cost - tr.cost) < limit):
            continue
        if not place_admissible([f], o.term) or at_null(f, o.term):
            continue
        dist = distance(exps, tr.fit, f)
        if dist < limit and (best is None or dist < best[0]):
            best = (dist, o)
    if best is None:
        return None
    dist, o = best
    assert o.fit is not None
    sep = separating_text(exps, o.fit, tr.fit, substeps, _separating)  # this module's name: tests patch it
    v, se = physical(o.fit, s, o.term)
    sym, unit = term_symbol_unit(o.term, *units)
    return PhysicalTwin(NamedTerm(o.term, sym, v, se, unit), o, _reason(o), dist <= EXACT, sep)


def removes(tr: Any, no_excess: bool) -> str:
    """What a candidate would remove alone, its parenthesis left open after the adjusted p: its share of the
    excess, or, when the step's cost shows no excess over its dof (``no_excess``: the model fails the
    adequacy test on a coloured noise's statistic, adequacy_chi2.py, and the share is read on that
    statistic, excess_share.py), the chi-square it removes - review 43 d6r: a negative damping "would remove
    100 % of the excess" while the model it would give stayed at chi2/dof 1.44 on the adequacy test."""
    what = (
        f"would lower the fit's chi2 by {tr.improvement:.3g} alone, where that chi2 shows no excess over its "
        "dof (the misfit is in the adequacy test's statistic, which weighs the noise harmonic by harmonic)"
        if no_excess
        else f"would remove {100 * tr.share:.0f} % of the excess alone"
    )
    return f"{what} (p adj = {tr.p_adjusted:.2g}"


def twin_text(twin: PhysicalTwin, beyond: Any, suggests: str, no_excess: bool = False) -> str:
    """The physical twin said first (its value, share, p and why it is not named), the reading beyond its
    range (``beyond``: a NamedTerm) as its alternative with what such a value suggests."""
    tr = twin.trial
    why = f"; not named: {twin.reason}" if twin.reason else ""
    how = "exactly" if twin.exact else "within the noise"
    sep = f"; to separate them: {twin.separating_experiment}" if twin.separating_experiment else ""
    return (
        f"{twin.named} {removes(tr, no_excess)}"
        f"{why}); in this design it gives the same averaged periods ({how}) as {beyond}, beyond its "
        f"physical range ({suggests}){sep}"
    )


__all__ = ["PhysicalTwin", "clearly_better", "physical_twin", "removes", "twin_text"]

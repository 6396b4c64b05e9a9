"""The size at which a candidate is *named at its place*, not only detected by its F-test (issue 18).

A detection limit (limits.py) is the value whose unabsorbed trace its own F-test sees with 90 % power. It
is not the size at which the verdict names the term: the first step names the candidate that fits best, so
a rival whose unabsorbed trace is nearly the same function takes the term's place as often as noise favours
it. At one frequency inertia is exactly a stiffness of ``-m omega^2`` at the same place (review 34, problem
6: one frequency, six amplitudes, a spring on x at 1.2x its stated 90 % value named in 1 of 4 seeds; the
others "adequate", "unexplained", inertia on u), and a spring on x is close to a spring or a dashpot on u.

For the term ``T`` at its 90 % value, with unabsorbed trace ``r_T`` (the plain model's Jacobian projected
out, limits.py), and a rival ``R`` with unabsorbed trace ``r_R`` (at any value: a one-parameter term's trace
is linear in it), the share ``c2 = (r_T . r_R)^2 / (|r_T|^2 |r_R|^2)`` of T's trace that R takes leaves
``(1 - c2) lam_T`` between their fits. In the plane of the two traces (``cos theta = sqrt(c2)``, the data's
mean at ``L = sqrt(lam_T / s2)`` along T's), R fits better where the data's direction is nearer R's line:
beyond one of the two bisectors of the lines, at distances ``L sin(theta / 2)`` and ``L cos(theta / 2)``
from the mean, so T fits better with probability ``1 - Phi(-L sin(theta/2)) - Phi(-L cos(theta/2))`` (0.5 for
a twin). T is named only if its test passes and it beats every
rival: :func:`named_size` finds the value at which ``P_detect x prod_R P_win(R)`` reaches 90 %
(``lam`` grows as ``v^2``; ``P_detect = Phi((sqrt(lam) - sqrt(thr)) / sqrt(s2))``, the F-test's threshold
``thr``). An exact twin (``c2 = 1``) wins half the time at any size: no such value (inf), and the verdict
says which rival it cannot be told from.

What this leaves out: the held-out, share and law tests (each costs some power; the measured named rates
are in docs/diagnosis.md, "Named at the stated size"), pairs of rivals taking the trace together, and the
rival's value: one confined to ``>= 0`` that takes the trace only with a negative value fails its range
check and is never in the step's order of passed candidates (select.py), so it is left out (an inertia on x
with a negative mass, the exact twin of a spring on x at one frequency; one frequency, six amplitudes:
stiffness on u, whose exact twin is a negative inertia on u, named in 6 of 10 draws at its 90 % value),
though the verdict may then report it beyond its range when the term itself fails its held-out test.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .result import TERM_LABELS

#: Probability of naming at which :attr:`Separation.named_90` is quoted.
NAMED_POWER = 0.9
#: Share of the term's unabsorbed trace a rival takes above which the two are twins of the design (exact
#: ties only: a share of 1 - 1e-6 still separates at a thousand times the value).
TWIN_SHARE = 1.0 - 1e-9
#: The value :func:`named_text` quotes beside the 90 % one when it is this much larger.
NAMED_SAID = 1.25
#: Why a candidate whose F-test passed is not named when its value failed its range or null check: no
#: detection of the term (resolution.detected_text says it apart).
NOT_PASSED = "its value is outside its physical range or at its null value"
#: Largest factor on the 90 % value searched for the named size (beyond it: inf).
FACTOR_MAX = 1e4


@dataclass(frozen=True)
class Separation:
    """The closest rival of one candidate and the value at which it is named with 90 % probability."""

    #: The rival whose unabsorbed trace shares most of the term's ("" when no rival).
    rival: str
    #: That share, 0-1 (``c2`` in the module docstring).
    share: float
    #: Scaled value (the term's own scale, as limits.py's) at which it is named with 90 %; inf: never (a
    #: twin, or beyond :data:`FACTOR_MAX` times the 90 % value).
    named_90: float

    @property
    def twin(self) -> bool:
        return self.share >= TWIN_SHARE


def named_text(lim: Any) -> str:
    """What the 90 % value does not promise (named_limit.py): the value at which the term passes its test and
    fits better than every rival with 90 %, when a rival shares enough of its trace to need more; never, for
    a twin. Not "named": the held-out and law tests come after (docs/diagnosis.md, "Named at the stated
    size": inertia on x at two frequencies, 0 of 10 named at that value, its held-out worse)."""
    if not (math.isfinite(lim.limit_90) and lim.rival) or math.isnan(lim.named_90):
        return ""
    rival = TERM_LABELS.get(lim.rival, lim.rival)
    if not math.isfinite(lim.named_90):
        return (
            f"; detected but not separable from {rival} with these experiments (the same averaged periods: "
            "either may take the fit)"
        )
    if lim.named_90 <= NAMED_SAID * lim.limit_90:
        return ""
    return (
        f"; fits better than {rival} (which takes {100 * lim.rival_share:.2g} % of its trace) with "
        f"{100 * NAMED_POWER:.0f} % probability only above {lim.named_90:.2g} (a better fit, not a "
        "separation: the verdict's alternatives say whether the two are told apart)"
    )


def why_not_named(trial: Any, chosen: str = "") -> str:
    """Why a first-step candidate whose own F-test passed was not named (select.py's gates after the F-test),
    in a few words; ``chosen``: the candidate the step chose instead ("" for none), which later checks
    (bounds_said, across_bounds) may drop: not said "named" (review 35m, F2)."""
    if chosen and chosen != trial.term and trial.held_out is None and trial.law_holds and trial.passed:
        who = TERM_LABELS.get(chosen, chosen)
        return f"the first step chose {who} instead (which the final verdict may drop)"
    if not trial.passed:
        return NOT_PASSED
    if trial.held_out is not None and not trial.held_out.improves:
        return "its held-out prediction was worse than the plain model's"
    if not trial.law_holds:
        return f"its value differs between experiments (law test p = {trial.law_p_value:.2g})"
    return "another candidate was tried first and the step ended there"


def _phi(x: float) -> float:
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def naming_probability(x: float, lam90: float, thr: float, s2: float, shares: Mapping[str, float]) -> float:
    """Probability that the term at ``x`` times its 90 % value (where its unabsorbed size is ``lam90``) passes
    its test at threshold ``thr`` and fits better than every rival (``shares``: each rival's ``c2``)."""
    lam = lam90 * x * x
    sd = math.sqrt(max(s2, 1e-300))
    p = _phi((math.sqrt(lam) - math.sqrt(max(thr, 0.0))) / sd)
    big = math.sqrt(lam) / sd
    for c2 in shares.values():
        c = math.sqrt(min(max(c2, 0.0), 1.0))
        # the rival wins where the data's direction is nearer its line than the term's: beyond either
        # bisector, at distances L sin(theta / 2) and L cos(theta / 2) from the term's mean (cos theta = c)
        p *= max(1.0 - _phi(-big * math.sqrt((1.0 - c) / 2.0)) - _phi(-big * math.sqrt((1.0 + c) / 2.0)), 0.0)
    return p


def shares_of(
    r_t: np.ndarray, rivals: Mapping[str, np.ndarray], one_sided: Collection[str] = ()
) -> dict[str, float]:
    """Each rival's share ``c2`` of ``r_t`` (each rival's trace drawn at a value in its range); rivals with
    no trace, and those in ``one_sided`` (confined to ``>= 0``) that would take it only with a negative value
    (refused by their bound: they do not take the term's place, select.py), left out."""
    nt = float(r_t @ r_t)
    out: dict[str, float] = {}
    if not nt > 0.0:
        return out
    for k, r in rivals.items():
        nr = float(r @ r)
        dot = float(r_t @ r)
        if not (nr > 0.0 and math.isfinite(nr)) or (k in one_sided and dot < 0.0):
            continue
        out[k] = min(dot * dot / (nt * nr), 1.0)
    return out


def named_size(
    v90: float, lam90: float, thr: float, s2: float, shares: Mapping[str, float], power: float = NAMED_POWER
) -> float:
    """The value (same unit as ``v90``) at which :func:`naming_probability` reaches ``power``; inf when it
    does not within :data:`FACTOR_MAX` (a twin wins half the time at any size)."""
    if not (math.isfinite(v90) and v90 > 0.0 and lam90 > 0.0):
        return math.inf

    def p(x: float) -> float:
        return naming_probability(x, lam90, thr, s2, shares)

    if p(FACTOR_MAX) < power:
        return math.inf
    lo, hi = 1e-3, FACTOR_MAX
    if p(lo) >= power:
        return lo * v90
    for _ in range(80):  # bisection in log x
        mid = math.sqrt(lo * hi)
        if p(mid) >= power:
            hi = mid
        else:
            lo = mid
        if hi / lo < 1.001:
            break
    return hi * v90


def separation(
    r_t: np.ndarray,
    rivals: Mapping[str, np.ndarray],
    v90: float,
    lam90: float,
    thr: float,
    s2: float,
    one_sided: Collection[str] = (),
) -> Separation:
    """:class:`Separation` of the term whose unabsorbed trace at its 90 % value ``v90`` is ``r_t`` (its
    unabsorbed size there ``lam90``, the target limits.py solved for) from the other candidates' traces
    (:func:`shares_of`)."""
    shares = shares_of(r_t, rivals, one_sided)
    if not shares:
        return Separation("", 0.0, v90)
    rival = max(shares, key=lambda k: shares[k])
    return Separation(rival, shares[rival], named_size(abs(v90), lam90, thr, s2, shares))


__all__ = [
    "NAMED_POWER",
    "NOT_PASSED",
    "Separation",
    "naming_probability",
    "named_size",
    "named_text",
    "separation",
    "shares_of",
    "why_not_named",
]

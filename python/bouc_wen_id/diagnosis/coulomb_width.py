"""The dry friction's smoothing width, profiled (review 40: a library term right only at the bench's width).

The Coulomb terms are ``f tanh(v / (eps Vmax))`` (on u or on x). With ``eps`` fixed at 1 % of the peak
velocity, a bolted joint whose friction turns over 0.1-0.5 % or 4 % of it (review 40's own simulator, first-
order G, three amplitudes) was "unexplained" - the term's law failed - and at 2 % a series dashpot stood in
for it: the term was right only at the width the bench's generator uses. Real dry friction has its own width
(the contact's pre-sliding travel over the velocity), so the candidate's fit profiles it: the fit is redone
from its own estimate at each width of :data:`WIDTHS` and the best is refined by a golden-section search on
``log eps`` between its neighbours; the candidate keeps the width of the smallest cost (one setting for the
model's dry friction, at either place: ``AugParams.smoothing``, which later fits from it carry). The width
is one more estimated parameter: the candidate's F test counts it (:func:`extra_dof`).

Below about ``pi / (2 P)`` (a quarter of a sample's phase step at ``P`` samples per period) the turn falls
between two samples and the width is not measured: the report says "below the sampling's resolution"
(:func:`width_text`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit, AugParams
from ..terms import COULOMB_SMOOTHING, COULOMB_SMOOTHING_MAX, TERMS, Coulomb

#: The widths the profile tries first (fractions of the peak velocity): a factor 4 apart, 0.25 % to 16 %.
WIDTHS = (0.0025, 0.01, 0.04, 0.16)

#: Golden-section steps on ``log eps`` between the best grid width's neighbours (a factor 16 -> about 1.5).
REFINE_STEPS = 4

#: Iterations of each width's refit from the candidate's estimate (a warm start).
REFIT_ITER = 30

#: Each width's refit starts from the fit of the nearest width already tried (on ``log eps``) rather than
#: from the candidate's own estimate at its width (docs/diagnosis-speed.md, session 48). False: always
#: from the candidate's estimate.
WARM_START = True


def is_dry_friction(term: str) -> bool:
    """Whether ``term`` is a Coulomb term (on u or on x)."""
    cls = TERMS.get(term)
    return cls is not None and issubclass(cls, Coulomb)


def has_dry_friction(par: AugParams) -> bool:
    return any(is_dry_friction(t) for t in par.terms)


def extra_dof(base: AugParams, fit: AugParams) -> int:
    """1 when ``fit`` adds the model's first dry friction to ``base`` (its width is then estimated too)."""
    return int(has_dry_friction(fit) and not has_dry_friction(base))


def profile(fit: AugFit, refit: Callable[[AugParams], Optional[AugFit]]) -> AugFit:
    """``fit`` (holding a dry friction) at the width of the smallest cost, each width's fit a warm refit from
    ``fit``'s estimate (``refit(start)``): each of :data:`WIDTHS`, then a golden-section search on
    ``log eps`` between the best one's neighbours; ``fit`` itself when no width does better. Searched
    whole again for every model that holds the friction: the width that fits it alone can be a factor 10
    from the one that fits it beside a damper (review 40's joint: 4 % alone, 0.1 % with the damper).

    ``fit`` itself, too, when the smallest cost is at the widest width (:data:`WIDTHS`' last, the search's
    upper edge): the cost still falls as the turn widens, so no width of a dry friction is found - the term
    stands in for a smooth force (a loop shape the model lacks) and a free width only lets it stand in
    better. Measured (session 42, tests/test_degradation_beside_drift.py's asymmetric degrading loop, no
    friction, records as they are): coulomb@x's cost fell monotonically to 16 % in every model holding it,
    and beside it a false output offset with Dahl friction on x passed its law (p 0.67 and 0.98; at the
    default width, 1.7e-9 and 2.2e-17): the offset took the loop's own centre, its predicted trend fell
    3x short and the fixed zero was said to drift."""
    tried: dict[float, Optional[AugFit]] = {fit.params.smoothing: fit}

    def at(eps: float) -> float:
        eps = float(eps)
        if eps not in tried:
            tried[eps] = refit(replace(_nearest(tried, eps, fit).params, smoothing=eps))
        f = tried[eps]
        return f.cost if f is not None and math.isfinite(f.cost) else math.inf

    costs = [at(e) for e in WIDTHS]
    k = min(range(len(WIDTHS)), key=lambda i: costs[i])
    lo, hi = math.log(WIDTHS[max(k - 1, 0)]), math.log(WIDTHS[min(k + 1, len(WIDTHS) - 1)])
    _golden(lambda s: at(math.exp(s)), lo, min(hi, math.log(COULOMB_SMOOTHING_MAX)), REFINE_STEPS)
    best = min((f for f in tried.values() if f is not None and math.isfinite(f.cost)), key=lambda f: f.cost)
    if best.params.smoothing >= WIDTHS[-1]:  # the cost still falls at the widest width: no turn found
        return fit
    return best if best.cost < fit.cost else fit


def _nearest(tried: dict[float, Optional[AugFit]], eps: float, fit: AugFit) -> AugFit:
    """The fit of the tried width nearest ``eps`` on ``log eps`` (``fit`` when none did fit): the warm start
    of the refit at ``eps`` (WARM_START; else ``fit`` itself)."""
    done = [(w, f) for w, f in tried.items() if f is not None and math.isfinite(f.cost) and w > 0.0]
    if not WARM_START or not done:
        return fit
    return min(done, key=lambda wf: abs(math.log(wf[0] / eps)))[1]


def _golden(f: Callable[[float], float], lo: float, hi: float, steps: int) -> None:
    """``steps`` golden-section steps of ``f`` on ``[lo, hi]`` (the values are kept by ``f`` itself)."""
    r = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    c, d = b - r * (b - a), a + r * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(steps):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - r * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + r * (b - a)
            fd = f(d)


def resolution(samples: Sequence[int]) -> float:
    """The smallest width the sampling resolves: a quarter of a sample's phase step, ``pi / (2 P)``, at the
    finest grid (the turn spans about ``eps`` rad of phase; narrower, it falls between two samples)."""
    return math.pi / (2 * max(max(samples), 1))


def width_text(eps: float, samples: Sequence[int]) -> str:
    """How the report says the fitted width: a percentage of the peak velocity, or below the sampling's
    resolution."""
    res = resolution(samples)
    if eps < res:
        return (
            f"smoothing eps = {100 * eps:.2g} % of the peak velocity, below the sampling's resolution "
            f"({100 * res:.2g} % at {max(samples)} samples per period): a sharp turn"
        )
    default = " (the default)" if eps == COULOMB_SMOOTHING else ""
    return f"smoothing eps = {100 * eps:.2g} % of the peak velocity{default}"


def text(named: Sequence[Any], fit: AugFit, exps: Sequence[AugExperiment]) -> str:
    """The verdict's clause on the named dry friction's fitted width (empty when none is named)."""
    terms = [str(getattr(t, "term", "")) for t in named]
    if not any(is_dry_friction(t) for t in terms) or not has_dry_friction(fit.params):
        return ""
    samples = [e.ybar.size for e in exps]
    return f"; the dry friction's turn: {width_text(fit.params.smoothing, samples)} (fitted)"


def settings(fit: AugFit) -> dict[str, float]:
    """``{"coulomb_smoothing": eps}`` when the fit holds a dry friction (the diagnosis's settings)."""
    return {"coulomb_smoothing": fit.params.smoothing} if has_dry_friction(fit.params) else {}


__all__ = [
    "settings",
    "text",
    "REFINE_STEPS",
    "WIDTHS",
    "extra_dof",
    "has_dry_friction",
    "is_dry_friction",
    "profile",
    "resolution",
    "width_text",
]

"""The order selection: which candidate is chosen, why (the text), and the resonances no point pins down."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Union

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ._result import OrderCandidate

FloatArray = NDArray[np.float64]

#: Candidates within this much of the lowest information criterion are "about as good" (a difference
#: below 2 is not evidence, Burnham and Anderson 2002, section 2.6); the simplest of them is chosen.
PARSIMONY = 2.0
#: A pinned candidate more than this above the best of all is refuted by the data (Burnham and Anderson
#: 2002: "essentially no support"), so unpinned resonances are no longer set aside in its favour.
DECISIVE = 10.0
#: What the selection table says of a candidate set aside for an unpinned resonance.
UNPINNED = "resonance not pinned down"
#: A complex pole pair with damping ratio below 1/sqrt(2) has a peak in |G(j omega)|; the peak is pinned
#: down only if a point lies inside its half-power band ``omega_n (1 +- zeta)``.
PEAK_DAMPING = 1.0 / math.sqrt(2.0)


def _eligible(rows: list[OrderCandidate], key: list[float]) -> tuple[list[int], int, float]:
    """The candidates the selection chooses from, how many unpinned ones were set aside, and by how much
    the best pinned candidate trails the best of all (inf when there is none).

    A candidate whose fitted resonance falls where no point pins it down is set aside (a narrow peak
    slipped between two points buys chi-square the data cannot confirm), unless every candidate with a
    pinned resonance (or none) is decisively worse, by more than ``DECISIVE``: then the data confirm a
    resonance even if they do not pin its peak, and setting it aside would return a model its own
    residuals refute (a resonant G tested an octave apart, its band edge 0.014 rad/s from a point).
    """
    finite = [i for i, k in enumerate(key) if math.isfinite(k)]
    pinned = [i for i in finite if rows[i].error != UNPINNED]
    if not finite:
        return [], 0, math.inf
    trail = min(key[i] for i in pinned) - min(key[i] for i in finite) if pinned else math.inf
    if trail <= DECISIVE:
        return pinned, len(finite) - len(pinned), trail
    return finite, 0, trail


def _select(rows: list[OrderCandidate], key: list[float]) -> int:
    """Index of the chosen candidate, or -1: among the eligible ones (:func:`_eligible`), the fewest
    parameters within ``PARSIMONY`` of the lowest criterion (ties: the lower)."""
    ok, _, _ = _eligible(rows, key)
    if not ok:
        return -1
    low = min(key[i] for i in ok)
    near = [i for i in ok if key[i] <= low + PARSIMONY]
    return min(near, key=lambda i: (rows[i].parameters, key[i]))


def _shapes(order: Union[None, int, tuple[int, int]], max_order: int) -> list[tuple[int, int]]:
    def bad() -> InvalidParameterError:
        return InvalidParameterError(f"order must be None, n or (m, n) with 0 <= m <= n <= 8, got {order!r}")

    if order is None:
        return [(m, n) for n in range(max_order + 1) for m in range(n + 1)]
    if isinstance(order, (int, np.integer)) and not isinstance(order, bool):
        if not 0 <= order <= 8:
            raise bad()
        return [(m, int(order)) for m in range(int(order) + 1)]
    if (
        isinstance(order, Sequence)
        and len(order) == 2
        and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in order)
    ):
        m, n = int(order[0]), int(order[1])
        if not 0 <= m <= n <= 8:
            raise bad()
        return [(m, n)]
    raise bad()


def _explain(rows: list[OrderCandidate], key: list[float], best: int, criterion: str, forced: bool) -> str:
    """Why the candidate ``best`` was chosen, in one sentence."""
    r = rows[best]
    what = f"m = {r.m}, n = {r.n}, " + ("delay fitted" if r.delay else "no fitted delay")
    if forced:
        return f"{what}: given by order=/delay=, not selected"
    name = criterion.upper()
    ok, set_aside, trail = _eligible(rows, key)
    others = sorted((key[i], i) for i in ok if i != best)
    if not others:
        return f"{what}: the only candidate the points support"
    low = min(key[i] for i in ok)
    if key[best] > low:
        head = (
            f"{what}: the fewest parameters ({rows[best].parameters}) within {PARSIMONY:g} of the lowest "
            f"{name} ({key[best] - low:.3g} above it)"
        )
    else:
        head = f"{what}: lowest {name} of {len(ok)} candidates"
    runner_key, runner_i = others[0]
    runner = rows[runner_i]
    gap = runner_key - key[best]
    strength = "decisive" if gap > 10 else ("strong" if gap > 6 else ("positive" if gap > 2 else "weak"))
    text = (
        f"{head}; the next (m = {runner.m}, n = {runner.n}, delay {'fitted' if runner.delay else 'none'}) is "
        f"{gap:.3g} {'higher' if gap >= 0 else 'lower'} "
        f"({strength if gap >= 0 else 'but has more parameters'})"
    )
    if set_aside:
        text += f"; {set_aside} candidate(s) set aside: a resonance no point pins down"
    elif math.isinf(trail) and any(rows[i].error == UNPINNED for i in ok):
        text += "; every candidate's resonance falls where no point pins it down"
    elif any(rows[i].error == UNPINNED for i in ok):
        text += (
            "; candidates whose resonance no point pins down were kept: the best without one is "
            f"decisively worse ({trail:.3g} higher)"
        )
    return text


def _resonance_warnings(den: FloatArray, omega: FloatArray) -> list[str]:
    """Warnings for each under-damped pole pair of ``den`` whose half-power band holds none of ``omega``."""
    out = []
    for p in np.roots(den):
        if p.imag <= 0.0:
            continue
        wn = abs(p)
        zeta = -p.real / wn
        if zeta >= PEAK_DAMPING:
            continue
        lo, hi = wn * (1.0 - zeta), wn * (1.0 + zeta)
        if np.any((omega >= lo) & (omega <= hi)):
            continue
        where = "between two tested frequencies" if omega[0] < wn < omega[-1] else "outside the tested band"
        out.append(
            f"a resonance at {wn:.4g} rad/s (damping {zeta:.3g}) lies {where}, with no point in its "
            f"half-power band [{lo:.4g}, {hi:.4g}] rad/s: its peak is not pinned down; test a frequency there"
        )
    return out

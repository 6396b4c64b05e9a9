"""Whether mu held at its bracket's lower end is the loops' exponent or a loop that changes with the rate
(review 47 failure 4).

A final fit holding mu at the lower end of its bracket (mu = 1) leads the verdict with "the loops may be
softer than mu = 1 allows" (:mod:`.bounds_said`). A rate-dependent loop width on a mu = 1.5 element
(review 47, ``rate-30-K-1``: a 12-frequency sweep at one amplitude) was said so too: the experiments fitted
together pull mu to its end because no one loop shape fits every frequency, not because each loop is soft.
The two are told apart by fitting the plain model to the lower and the upper half of the frequencies apart,
each half holding the same drive amplitudes (a fixed amplitude: what changes between them is the rate):
when a half holds mu clearly inside its bracket (at least :data:`MU_CLEAR`, not on its face), the lower end
is not where every loop's exponent is: the pull toward it changes with frequency at a fixed amplitude, and
the verdict says the loop's shape changes with frequency (a rate dependence, outside the model) instead of
pointing at the exponent (``rate-30-K-1``: the slower half holds mu = 1.42, the plant's 1.5; the faster one
stays at 1). When both halves stay at the end (a mu = 0.75 element: every loop is soft), or the halves
share no amplitude, nothing changes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from .bounds_said import Beyond, held_mu
from .fitting import fit_from, subset

#: A half's mu at least this far inside the bracket (and off its face) is not the lower end.
MU_CLEAR = 1.1
#: The halves' fits start here (not on the face, where a fit may stay).
MU_START = 1.5


def halves(exps: Sequence[AugExperiment]) -> Optional[tuple[list[int], list[int]]]:
    """The experiments at the lower and the upper half of the distinct frequencies, when there are at least
    two and the halves share a drive amplitude (to 1e-6); None otherwise."""
    freqs = sorted({round(float(e.frequency), 9) for e in exps})
    if len(freqs) < 2:
        return None
    cut = freqs[(len(freqs) - 1) // 2]
    lo = [i for i, e in enumerate(exps) if round(float(e.frequency), 9) <= cut]
    hi = [i for i, e in enumerate(exps) if round(float(e.frequency), 9) > cut]

    def amps(ix: list[int]) -> set[float]:
        return {float(np.round(np.log(abs(exps[i].amplitude)), 6)) for i in ix}

    return (lo, hi) if amps(lo) & amps(hi) else None


def _half_fit(
    exps: Sequence[AugExperiment], final: AugFit, keep: list[int], substeps: int
) -> Optional[AugFit]:
    sub, par = subset(exps, final.params.only(()), keep)
    return fit_from(sub, replace(par, mu=max(float(par.mu), MU_START)), substeps)


def clause(exps: Sequence[AugExperiment], final: AugFit, substeps: int) -> str:
    """The rate reading (``""`` when it does not hold): a half of the frequencies fitted apart by the plain
    model holds mu clearly inside its bracket (the other may stay at its lower end)."""
    split = halves(exps)
    if split is None:
        return ""
    said = []
    for keep in split:
        f = _half_fit(exps, final, keep, substeps)
        if f is None:
            return ""
        h = held_mu(f)
        w = sorted(float(exps[i].frequency) for i in keep)
        band = f"{w[0]:.3g}" if w[0] == w[-1] else f"{w[0]:.3g}-{w[-1]:.3g}"
        inside = not h.mu_face and h.mu >= MU_CLEAR
        said.append((inside, f"at {band} rad/s {'hold' if len(keep) > 1 else 'holds'} mu = {h.mu:.3g}"))
    if not any(inside for inside, _ in said):
        return ""
    where = " and those ".join(
        f"{t}{' (inside its bracket)' if ok else ' (its lower end)'}" for ok, t in said
    )
    return (
        "the loop's shape changes with frequency at a fixed drive amplitude (a rate-dependent loop, outside "
        f"the model), not an exponent below 1: fitted apart, the experiments {where}"
    )


def mark(
    held: Optional[Beyond], judged: str, exps: Sequence[AugExperiment], final: AugFit, substeps: int
) -> Any:
    """``held`` with :attr:`.bounds_said.Beyond.rate` set when the verdict would point at the exponent (mu
    held at its lower end with a misfit said, :func:`.bounds_said.apply`) and the rate reading holds."""
    if held is None or held.mu_face != "lower" or judged == "adequate":
        return held
    if judged == "explained" and not held.targeted_soft:
        return held  # an adequate final model stands: no soft-loop clause to replace
    said = clause(exps, final, substeps)
    return replace(held, rate=said) if said else held


__all__ = ["MU_CLEAR", "MU_START", "clause", "halves", "mark"]

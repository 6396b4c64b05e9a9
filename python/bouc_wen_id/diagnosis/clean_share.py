"""The share of the excess named terms remove on the clean-input experiments, when some inputs are not sines.

An actuator that clips puts the input's harmonics through G at frequencies above the tested band, which the
model cannot carry (its latent ``x`` is a sine) and no device term explains: on a resonant G they dwarf a
device's own misfit. The law test already compares such a design's clean experiments alone
(:func:`.law.law_rows`, at least :data:`.law.MIN_CLEAN` of them); the share that decides "explained in part"
was still the pooled one (review 33 ``clip_cu``: viscous damping on u, 10x, two of five inputs clipped, a
resonant G with delay; the term's law held on the three clean experiments (p = 0.49) and, diagnosed alone,
they are explained by it; pooled it removed 13 % of the excess, the clipped experiments' input harmonics
the rest, and the verdict was "unexplained"; the same clipping on a null through the same G is
"unexplained" too, so the clipped part is the drive's, not the damping's).

:func:`share` is the share of the clean experiments' excess the final model removes; the diagnosis takes
the larger of it and the pooled share to decide "explained in part" (never "explained": the final model
still fails over every experiment), and :func:`text` says on which experiments the share was taken.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..augmented import AugExperiment, AugFit
from . import free_dc
from .gate import explained_fraction
from .law import MIN_CLEAN


def clean(exps: Sequence[AugExperiment]) -> list[int]:
    """The experiments with a pure-sine input, when at least :data:`MIN_CLEAN` have one and some do not;
    empty otherwise (every input a sine: the pooled share is the clean one)."""
    idx = [i for i, e in enumerate(exps) if not e.waveform.size]
    return idx if MIN_CLEAN <= len(idx) < len(exps) else []


def _cost(e: AugExperiment, y: np.ndarray) -> float:
    r = free_dc.centred(e, np.asarray(e.ybar) - np.asarray(y))
    return float(e.weight * np.sum(r * r))


def share(
    plain_exps: Sequence[AugExperiment], plain: AugFit, exps: Sequence[AugExperiment], final: AugFit
) -> float:
    """The share of the clean experiments' excess (:func:`clean`) the ``final`` model (on ``exps``) removes
    from the ``plain`` model's (on ``plain_exps``, the same experiments), each experiment's weighted
    residual sum of squares, the clean samples less each experiment's own |G| and phase and its free DC;
    NaN when there is no such subset or the fits give no outputs."""
    idx = clean(exps)
    outs_p, outs_f = getattr(plain, "outputs", None), getattr(final, "outputs", None)
    if not idx or outs_p is None or outs_f is None or len(plain_exps) != len(exps):
        return math.nan
    sub = [exps[i] for i in idx]
    before = sum(_cost(plain_exps[i], outs_p[i]) for i in idx)
    after = sum(_cost(exps[i], outs_f[i]) for i in idx)
    dof = sum(e.ybar.size for e in sub) - 2 * len(sub) - free_dc.spent(sub)
    if not math.isfinite(before + after):
        return math.nan
    return explained_fraction([(before, float(dof), after)])


def naming_share(pooled: float, clean_share: float) -> float:
    """The share that decides "explained in part": the larger of the pooled and the clean-input one."""
    return max(pooled, clean_share) if math.isfinite(clean_share) else pooled


def text(
    status: str, named: Sequence[object], pooled: float, clean_share: float, exps: Sequence[object]
) -> str:
    """The verdict's word when the clean experiments' share decided "explained in part": on which
    experiments, and how much of the pooled excess; empty otherwise."""
    if status != "partly explained" or not named or not math.isfinite(clean_share) or clean_share <= pooled:
        return ""
    idx = clean(exps)  # type: ignore[arg-type]
    return (
        f"; on the {len(idx)} experiments whose input is a sine the named terms remove "
        f"{100 * clean_share:.0f} % of the excess (over all {len(exps)}, {100 * pooled:.0f} %): the rest "
        "sits in the experiments whose input is not a sine (below)"
    )


__all__ = ["clean", "naming_share", "share", "text"]

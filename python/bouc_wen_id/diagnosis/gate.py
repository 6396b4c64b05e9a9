"""The plain model's gate and the explained fraction: one code for :func:`.run.diagnose` and
:func:`.across.diagnose_across` (issue 18: the house says the same thing whichever path the user takes).

Copies of these rules in the joint path drifted from the single-group one (the joint path tested the plain
model at ``alpha`` where diagnose tests it at ``alpha / 2``, and ignored the law-failed candidates that keep
diagnose from "adequate"); both paths now call these functions.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

#: The "adequate" verdict's words, both paths'.
ADEQUATE = "adequate: the plain Wiener-Bouc-Wen model fits at the noise floor"


def plain_passes(p_value: float, alpha: float, moved: bool = False) -> bool:
    """The plain model's global test at ``alpha / 2`` (the other ``alpha / 2`` is the targeted step's:
    select.py's docstring, design.md 10.3); ``moved``: the loop drifts or degradation is named, and the
    plain (steady) model cannot be the answer."""
    return not moved and math.isfinite(p_value) and p_value >= 0.5 * alpha


#: The share of ``alpha`` the targeted step after a named term gives its candidates' F-tests (Bonferroni
#: over them, as the plain model's targeted step shares ``alpha / 2``); after_named.py's docstring says why.
AFTER_NAMED_SHARE = 0.1


def targeted_level(alpha: float, after_named: bool = False) -> float:
    """The level of a targeted step's candidates (before Bonferroni over them): ``alpha / 2`` on the plain
    model (the other half is its global test's), ``AFTER_NAMED_SHARE * alpha`` on a model with named terms
    (after_named.py)."""
    return (AFTER_NAMED_SHARE if after_named else 0.5) * alpha


#: Why the targeted step was not run (the plain model passed the global test on a floored noise).
NO_TARGETED_STEP = (
    "the targeted candidate tests (effects below the global test's reach) were not run: the noise floor of "
    "some experiment is not measured noise (quantisation or numerical accuracy), and an effect below the "
    "global test cannot be told from that error"
)


def plain_gate(
    p_values: Sequence[float], alpha: float, moved: Sequence[bool], measured_noise: Sequence[bool]
) -> tuple[bool, bool]:
    """``(passes, targeted)`` over one or several sets of experiments (one per condition): the plain model
    passes its gate at every set (:func:`plain_passes`, with that set's ``moved``), and the targeted step
    runs only when it passes and every set's noise floor is measured noise. The targeted step hunts effects
    below the global test's reach; where the error is a repeated quantisation pattern or the model's own
    precision (``measured_noise`` False: settling._noise_floors set the floor), such effects cannot be told
    from that error, and the step is not run (:data:`NO_TARGETED_STEP` says so)."""
    passes = all(plain_passes(p, alpha, m) for p, m in zip(p_values, moved, strict=True))
    return passes, passes and all(measured_noise)


def plain_adequate(passes: bool, has_terms: bool, steps: Sequence[Any]) -> bool:
    """The plain model is "adequate": its gate passed (:func:`plain_passes`), nothing was added, and no
    candidate's tests passed with a law that failed (select.law_test: structure the plain model leaves and no
    term explains, even when the global test accepted it)."""
    return passes and not has_terms and not any(st.law_failed for st in steps)


def explained_fraction(parts: Iterable[tuple[float, float, float]]) -> float:
    """The share of the excess the final model removes, over ``parts`` of ``(cost before, its dof, cost
    after)``: the plain model's and the final's (one per condition across conditions; the drift space's too
    when degradation is named). The excess is each part's ``C - dof`` when positive; capped at 1 (a model
    below the noise floor fitted some noise too); 0 without excess."""
    excess = gain = 0.0
    for before, dof, after in parts:
        excess += max(before - dof, 0.0)
        gain += before - after
    return min(gain / excess, 1.0) if excess > 0 else 0.0


__all__ = [
    "ADEQUATE",
    "AFTER_NAMED_SHARE",
    "targeted_level",
    "NO_TARGETED_STEP",
    "plain_gate",
    "plain_passes",
    "plain_adequate",
    "explained_fraction",
]

"""The named terms' values from the clean-input experiments alone, when some inputs are not sines.

The model's latent ``x`` is a sine at every experiment; an actuator that clips drives the device with the
input's harmonics too, and G carries them to the output at frequencies above the tested band, which no
term represents. A term fitted over every experiment takes part of them up: review 33 ``clip_cu``
(viscous damping on u, 10x, two of five inputs clipped, a resonant G with delay) named c = 0.006228 ±
4.48e-05 against a true 0.006044, 4.1 standard errors off, although the law test (:func:`.law.law_rows`)
and the share that decides "explained in part" (:mod:`.clean_share`) already took the clean experiments
alone. A value quoted with its standard error must be one the model can represent: the final model is
refitted on the clean experiments (at least :data:`.law.MIN_CLEAN`, the set :func:`.clean_share.clean`
gives, every shared parameter and each experiment's own G free, from the final fit's estimates), and
each named term's value and standard error are that refit's. The input's own term (``distortion``) acts
only where the input is not a sine and keeps its pooled value. The verdict says which experiments the
values come from and which were left out, and gives the pooled value without a standard error, as the
pooled one; when the refit fails the pooled values stay and the verdict says they include the clipped
experiments.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Optional

from ..augmented import AugExperiment, AugFit
from ..terms import Distortion
from .clean_share import clean
from .fitting import Scale, fit_from, physical, subset
from .result import ModelSummary, NamedTerm

#: A replaced value within this many of its standard errors of zero is not told from zero on the clean
#: experiments alone (said: what named the term sits in the others).
WEAK_SE = 2.0


@dataclass(frozen=True)
class CleanValues:
    """Which experiments the named values come from, and the pooled values they replaced.

    ``kept``: the clean experiments' sources (empty: every input a sine, nothing replaced); ``left``: the
    others'; ``pooled``: the pooled terms whose values were replaced; ``failed``: the refit on the clean
    experiments failed (the pooled values stand)."""

    kept: tuple[str, ...] = ()
    left: tuple[str, ...] = ()
    pooled: tuple[NamedTerm, ...] = ()
    failed: bool = False

    def text(self, status: str, named: Sequence[NamedTerm]) -> str:
        """The verdict's clause on where the values it quotes (``named``: the named terms and those left
        unnamed for a value outside their range) come from ("" when every input is a sine, the verdict is
        "adequate", or nothing the refit replaced is quoted)."""
        if not self.kept or status == "adequate":
            return ""
        names = {t.term for t in named}
        if self.failed:
            if not names - {Distortion.kind}:
                return ""
            return (
                f"; the values named are fitted over all {len(self.kept) + len(self.left)} experiments, "
                f"those whose input is not a sine ({_list(self.left)}) included: the refit on the "
                f"{len(self.kept)} whose input is a sine did not converge, and the harmonics of a clipped "
                "or distorted drive, which the model does not carry, may pull the values beyond their "
                "standard errors"
            )
        pooled = [t for t in self.pooled if t.term in names]
        if not pooled:
            return ""
        was = ", ".join(f"{t.symbol} = {t.value:.4g}" for t in pooled)
        return (
            f"; the values named are fitted on the {len(self.kept)} experiments whose input is a sine "
            f"({_list(self.kept)}) alone: the {len(self.left)} whose input is not ({_list(self.left)}: a "
            "clipped or distorted drive) are left out of them: their input's harmonics reach the output "
            "through G where the model's sine input does not, and can pull a value fitted on them (over all "
            f"{len(self.kept) + len(self.left)}, pooled: {was})" + _weak_text(named, pooled)
        )


def _weak_text(named: Sequence[NamedTerm], pooled: Sequence[NamedTerm]) -> str:
    """The clause on replaced terms whose clean value is within :data:`WEAK_SE` standard errors of zero."""
    terms = {t.term for t in pooled}
    weak = [t for t in named if t.term in terms and abs(t.value) < WEAK_SE * t.standard_error]
    if not weak:
        return ""
    said = ", ".join(f"{t.label} ({t.symbol} = {t.value:.3g} ± {t.standard_error:.3g})" for t in weak)
    one = len(weak) == 1
    return (
        f"; on them alone {said} {'is' if one else 'are'} not told from zero: what named "
        f"{'it' if one else 'them'} sits in the experiments whose input is not a sine"
    )


def _list(names: Sequence[str]) -> str:
    return ", ".join(names) if len(names) <= 6 else ", ".join(names[:5]) + f" and {len(names) - 5} more"


def refit(fsx: Sequence[AugExperiment], final: AugFit, substeps: int) -> Optional[AugFit]:
    """The final model refitted on the clean experiments (:func:`.clean_share.clean`) without the input's
    own term; None when there is no such subset, no other term, or the refit fails."""
    idx = clean(fsx)
    if not idx:
        return None
    sub, par = subset(fsx, final.params, idx)
    par = par.only(t for t in par.terms if t != Distortion.kind)
    if not par.terms:
        return None
    fit = fit_from(sub, par, substeps)
    return fit if fit is not None and math.isfinite(fit.cost) else None


def summary(
    pooled: ModelSummary, fsx: Sequence[AugExperiment], final: AugFit, s: Scale, substeps: int
) -> tuple[ModelSummary, CleanValues]:
    """``pooled`` with its terms' values and standard errors from :func:`refit` (the input's own term and
    a term the refit left undetermined keep theirs), and where they come from."""
    idx = clean(fsx)
    if not idx or not final.params.terms:
        return pooled, CleanValues()
    kept = tuple(fsx[i].source for i in idx)
    left = tuple(e.source for i, e in enumerate(fsx) if i not in idx)
    fit = refit(fsx, final, substeps)
    if fit is None:
        return pooled, CleanValues(kept, left, failed=True)
    terms, replaced = [], []
    for t in pooled.terms:
        if t.term in fit.params.terms:
            v, se = physical(fit, s, t.term)
            if math.isfinite(v) and math.isfinite(se):
                replaced.append(t)
                t = replace(t, value=v, standard_error=se)
        terms.append(t)
    return replace(pooled, terms=tuple(terms)), CleanValues(kept, left, tuple(replaced))


__all__ = ["CleanValues", "refit", "summary"]

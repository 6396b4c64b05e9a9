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
from ..terms import TERMS, Distortion
from .clean_share import clean
from .fitting import Scale, at_a_limit, fit_from, physical, subset
from .result import ModelSummary, NamedTerm

#: A replaced value within this many of its standard errors of zero is not told from zero on the clean
#: experiments alone (said: what named the term sits in the others).
WEAK_SE = 2.0


@dataclass(frozen=True)
class CleanValues:
    """Which experiments the named values come from, and the pooled values they replaced.

    ``kept``: the clean experiments' sources (empty: every input a sine, nothing replaced); ``left``: the
    others'; ``pooled``: the pooled terms whose values were replaced; ``failed``: the refit on the clean
    experiments failed (the pooled values stand); ``undetermined``: terms the clean experiments do not
    determine (their pooled values stand, said)."""

    kept: tuple[str, ...] = ()
    left: tuple[str, ...] = ()
    pooled: tuple[NamedTerm, ...] = ()
    failed: bool = False
    undetermined: tuple[str, ...] = ()

    def text(self, status: str, named: Sequence[NamedTerm]) -> str:
        """The verdict's clause on where the values it quotes (``named``: the named terms and those left
        unnamed for a value outside their range) come from ("" when every input is a sine, the verdict is
        "adequate", or nothing the refit replaced is quoted)."""
        if not self.kept or status == "adequate":
            return ""
        names = {t.term for t in named}
        # nothing named (unexplained): the values are the tested terms', which the verdict does not quote
        quoted = status in ("explained", "partly explained")
        what = "the values named" if quoted else "the tested terms' values"
        if self.failed:
            if not names - {Distortion.kind}:
                return ""
            return (
                f"; {what} are fitted over all {len(self.kept) + len(self.left)} experiments, "
                f"those whose input is not a sine ({_list(self.left)}) included: the refit on the "
                f"{len(self.kept)} whose input is a sine failed or did not determine them, and the "
                "harmonics of a clipped or distorted drive, which the model does not carry, may pull the "
                "values beyond their standard errors"
            )
        pooled = [t for t in self.pooled if t.term in names]
        if not pooled:
            return ""
        loose = [t for t in named if t.term in self.undetermined]
        one = len(loose) == 1
        lost = (
            f"; on them alone {', '.join(t.label for t in loose)} {'is' if one else 'are'} not determined "
            f"(refitted without): what named {'it' if one else 'them'} sits in the experiments whose input "
            f"is not a sine, and {'its value' if one else 'their values'} above {'is' if one else 'are'} "
            "pooled"
            if loose
            else ""
        )
        was = ", ".join(f"{t.symbol} = {t.value:.4g}" for t in pooled)
        if not quoted:  # say them: the verdict names none of them
            clean = {t.term for t in pooled}
            what += (
                " (not named: "
                + ", ".join(
                    f"{t.label} {t.symbol} = {t.value:.4g} ± {t.standard_error:.2g}"
                    for t in named
                    if t.term in clean
                )
                + ")"
            )
        return (
            f"; {what} are fitted on the {len(self.kept)} experiments whose input is a sine "
            f"({_list(self.kept)}) alone: the {len(self.left)} whose input is not ({_list(self.left)}: a "
            "clipped or distorted drive) are left out of them: their input's harmonics reach the output "
            "through G where the model's sine input does not, and can pull a value fitted on them (over all "
            f"{len(self.kept) + len(self.left)}, pooled: {was})" + _weak_text(named, pooled) + lost
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


def _undetermined(sub: Sequence[AugExperiment], fit: AugFit) -> set[str]:
    """The terms the clean experiments do not determine: a two-term element at one of its limits (both
    members: :func:`.fitting.at_a_limit`), else every term whose standard error is not finite."""
    par = fit.params
    at_limit = {t for t in par.terms if TERMS[t].companion and at_a_limit(sub, fit, t)}
    if at_limit:
        return at_limit | {TERMS[t].companion for t in at_limit}
    return {t for t in par.terms if not math.isfinite(fit.standard_error(t))}


def refit(
    fsx: Sequence[AugExperiment], final: AugFit, substeps: int
) -> Optional[tuple[AugFit, tuple[str, ...]]]:
    """The final model refitted on the clean experiments (:func:`.clean_share.clean`) without the input's
    own term, and the terms left out because the clean experiments do not determine them
    (:func:`_undetermined`: refitted once without them); None when there is no such subset, no term to
    refit, or the refit fails or still leaves a term undetermined."""
    idx = clean(fsx)
    if not idx:
        return None
    sub, par = subset(fsx, final.params, idx)
    par = par.only(t for t in par.terms if t != Distortion.kind)
    out: tuple[str, ...] = ()
    for _ in range(2):
        if not par.terms:
            return None
        fit = fit_from(sub, par, substeps)
        if fit is None or not math.isfinite(fit.cost):
            return None
        bad = _undetermined(sub, fit)
        if not bad:
            return fit, out
        out += tuple(t for t in par.terms if t in bad)
        par = par.only(t for t in par.terms if t not in bad)
    return None


def summary(
    pooled: ModelSummary, fsx: Sequence[AugExperiment], final: AugFit, s: Scale, substeps: int
) -> tuple[ModelSummary, CleanValues]:
    """``pooled`` with its terms' values and standard errors from :func:`refit` (the input's own term and
    the terms the clean experiments do not determine keep theirs), and where they come from."""
    idx = clean(fsx)
    if not idx or not final.params.terms:
        return pooled, CleanValues()
    kept = tuple(fsx[i].source for i in idx)
    left = tuple(e.source for i, e in enumerate(fsx) if i not in idx)
    got = refit(fsx, final, substeps)
    if got is None:
        return pooled, CleanValues(kept, left, failed=True)
    fit, undetermined = got
    terms, replaced = [], []
    for t in pooled.terms:
        if t.term in fit.params.terms:
            v, se = physical(fit, s, t.term)
            replaced.append(t)
            t = replace(t, value=v, standard_error=se)
        terms.append(t)
    return replace(pooled, terms=tuple(terms)), CleanValues(kept, left, tuple(replaced), False, undetermined)


__all__ = ["CleanValues", "refit", "summary"]

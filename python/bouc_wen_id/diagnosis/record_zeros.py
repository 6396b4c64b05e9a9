"""An output zero that differs between recordings: each recording's DC left free (issue 18, review 41).

A sensor re-zeroed between recordings, or a zero that moved between them, gives each recording its own
output offset. One offset then fits nearly all the misfit but its law (one value for every experiment) fails,
and a term whose own DC differs from experiment to experiment was named in its place: offsets of
0.0173/0.0172/0.0168 (a spread of 3 %, plain model otherwise exact) read "explained in part by: asymmetry
delta = -0.057" (84 % of the excess, final chi2/dof 19), and beside a damper on u put the damping on x, 63 %
high (review 41, a simulator of its own, first-order G). docs/diagnosis.md promised such a set is "reported
as loop centres that differ, not as one output offset".

:func:`triggered`: a step's output offset fitted more of the misfit than the term it named (or it
named none) and was refused only for its law, and the diagnosis is not adequate. The set is then diagnosed
again with each experiment's DC free about their common one (:func:`freed`: the averaged period's DC weighs
nothing, as under a wandering baseline, ``free_dc.py``), so a term is named on the loop's shape (harmonics
1..) and the common DC is still fitted (an offset can be named). A first diagnosis that passed its adequacy
test is kept (a loop whose own DC differs - an asymmetry - explains the DCs with one value); else
:func:`chosen` takes the freed one when its final model fits better per degree of freedom (the DCs are
spent: ``free_dc.spent``). The verdict then says the recordings' zeros differ, by how much against the
noise, and that an experiment's own DC (an asymmetry's) cannot be read from them; a named offset's standard
error is the spread of the recordings' centres (:func:`.data.common_centre`), as under a wander
(``baseline.adjusted``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..terms import Offset
from .data import DiagExperiment, common_centre
from .drift import DRIFT_TERMS
from .result import Diagnosis

#: The output offset's kind (the terms registry's).
OFFSET = Offset.kind


@dataclass(frozen=True)
class RecordZeros:
    """The recordings' own zeros: each one's residual DC under the plain model (``centres``), their common
    part and its standard error (the centres' spread over sqrt(m)), and the DC's noise sd (``noise``)."""

    centres: tuple[float, ...]
    noise: float
    centre: float
    centre_se: float
    centre_p: float
    #: the common zero stands out of the recordings' spread (:func:`.data.common_centre`'s t-test): only then
    #: is the set diagnosed with the zeros free (the common DC fitted, the DCs about it free)
    kept: bool = True
    per_record: bool = True  # read by baseline.removed: the records are left as they are

    def note(self) -> str:
        return (
            "the recordings' output zeros differ (residual DC of each under the plain model: "
            f"{self._list()}; their spread {self.spread():.3g}, {self.spread() / self.noise:.3g} times the "
            "averaged DC's noise sd): each experiment's DC was left free about their common one, and the "
            "terms were named on the loop's shape (harmonics 1 and up)"
        )

    def clause(self) -> str:
        return (
            f"; the recordings' output zeros differ ({self._list()}, spread {self.spread():.3g}, "
            f"{self.spread() / self.noise:.3g} x the noise: a sensor re-zeroed or a zero that moved between "
            "recordings, or loop centres that differ): each recording's DC was left free, so an experiment's "
            "own DC (an asymmetry's) is not read from them"
        )

    def spread(self) -> float:
        return float(np.std(self.centres, ddof=1)) if len(self.centres) > 1 else 0.0

    def _list(self) -> str:
        return "/".join(f"{c:.4g}" for c in self.centres)


def triggered(d: Diagnosis) -> bool:
    """Whether a step of ``d`` refused an output offset for its law alone while it fitted more of the
    misfit than the term named there (or nothing was named), in a diagnosis that is not adequate."""
    if d.status in ("adequate", "explained") or not d.steps or len(d.experiments) < 2:
        return False
    if d.settings.get("common_dc") is not None:  # already freed (a wander, or this module's own run)
        return False
    if any(t.term in DRIFT_TERMS for t in (*d.named, *d.partial)):
        # A degrading loop moves its own centre within and between records (loop_centre.py): its DCs are
        # the loop's, not the zeros'.
        return False
    for step in d.steps:
        if OFFSET not in step.law_failed:
            continue
        costs = {t.term: t.cost for t in step.trials}
        chosen = costs.get(step.chosen, math.inf) if step.chosen else math.inf
        if costs.get(OFFSET, math.inf) < chosen:
            return True
    return False


def zeros_of(d: Diagnosis, level: float) -> RecordZeros:
    """The recordings' zeros read off ``d``'s plain model (each experiment's residual DC) and their common
    part's t-test at ``level``."""
    return zeros_from(d.experiments, d.plain.outputs, level)


def zeros_from(exps: Sequence[DiagExperiment], outputs: Sequence[Any], level: float) -> RecordZeros:
    """The recordings' zeros: each experiment's residual DC under its plain model's ``outputs`` (units of
    y) and their common part's t-test at ``level`` (:func:`zeros_of`; diagnose-across per condition)."""
    centres, noise = [], []
    for e, out in zip(exps, outputs):
        centres.append(float(np.mean(e.ybar - np.asarray(out))))
        noise.append(math.sqrt(e.noise_var / (e.periods * e.ybar.size)))
    c, se, p, kept = common_centre(centres, level)
    return RecordZeros(tuple(centres), float(np.mean(noise)), c, se, p, kept)


def freed(exps: Sequence[DiagExperiment]) -> list[DiagExperiment]:
    """``exps`` with each one's DC set, not measured (``DiagExperiment.baseline_removed``): the fits leave it
    free (``free_dc.py``), the adequacy and drift tests give it no weight. The noise floors are unchanged
    (the records are as they were)."""
    out = []
    for e in exps:
        k = e.ybar.size // 2 + 1
        hv = np.array(e.harmonic_var, dtype=np.float64) if e.harmonic_var.size else np.full(k, e.noise_var)
        hv[0] = math.inf
        out.append(replace(e, harmonic_var=hv))
    return out


def chosen(first: Diagnosis, second: Diagnosis) -> Diagnosis:
    """The diagnosis to report: the freed one (``second``) when its final model fits better per degree of
    freedom than ``first``'s (which :func:`triggered` found not adequate), else ``first``."""
    per_dof = [x.final.cost / max(x.final.dof, 1) for x in (first, second)]
    return second if per_dof[1] < per_dof[0] else first


def resolved(d: Diagnosis, level: float, rerun: Callable[[Any], Diagnosis]) -> Diagnosis:
    """``d``, or the diagnosis with the recordings' zeros free (``rerun(zeros)``) when :func:`triggered`."""
    if not triggered(d):
        return d
    zeros = zeros_of(d, level)
    if not zeros.kept:
        # No common zero stands out of the recordings' spread (resets of both signs about ~0): that is the
        # loop centres' case (fit_notes.centre_text, centre_only.py), said as centres that differ, with a
        # common DC that cannot be told from a device offset - not one offset whose value moved.
        return d
    return chosen(d, rerun(zeros))


__all__ = ["RecordZeros", "triggered", "zeros_of", "zeros_from", "freed", "chosen", "resolved"]

"""When most recordings drift, the drift is the finding: the verdict says so first.

Experiments whose loop still drifts from period to period (settling.py's ``_unsettled``) are left out of the
naming, and the settled ones are diagnosed alone (run.py). When those are most of the recordings, a verdict
on the few settled ones read as the verdict on the whole set: review 36 (problem 2) had an output gain
drifting by +3 % over each record called "adequate: the plain Wiener-Bouc-Wen model fits at the noise
floor" on 2 of 6 recordings, and by -3 % "explained by: stiffness degradation", with "recording 0,
recording 1, recording 2, recording 5 left out (not settled, or a drifting sensor)" as the verdict's last
clause. The few settled recordings of a drifting set are no evidence that the rest is fine: they are those
whose drift fell under the per-experiment test.

So when more than half of the experiments drift, the verdict leads with the drift (which, by how much per
period, and what it can be: a transient not yet settled, an output gain or zero drifting over the record,
degradation the drift test does not name; a drifting gain said as the reading when gain_drift.py found it
fits), the status is "unexplained", nothing is named, and the settled ones' diagnosis follows as a hint.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

import numpy as np

from .data import DiagExperiment
from .drift import DegradationTest
from .drift_said import firm
from .locate import _trend
from .result import TERM_LABELS, Diagnosis

#: Kill switch (tests compare with and without).
ENABLED = True


def most(n_drifting: int, n: int) -> bool:
    """Whether the drifting experiments are most of them (the verdict would rest on a minority)."""
    return ENABLED and 2 * n_drifting > n


def rate(e: DiagExperiment) -> float:
    """The relative change of ``e``'s fundamental per period (least-squares trend; NaN: too short)."""
    amp = np.abs(np.asarray(e.h1))
    if amp.size < 3 or not float(np.mean(amp)) > 0:
        return float("nan")
    return _trend(amp / float(np.mean(amp)))[0]


def reading(deg: Optional[DegradationTest]) -> str:
    """What the drift fits, when the drift test ran on the whole set: a drifting output gain as well as a
    degradation term (gain_drift.py), or '' (no reading beyond the list of causes)."""
    if deg is None or not deg.gain_alternative:
        return ""
    term = TERM_LABELS.get(deg.term, deg.term)
    return (
        f"; the drift fits an output gain drifting over each record (a sensor's gain, e.g. with temperature) "
        f"as well as {term} does ({term}'s test given the gain drift: adjusted p = "
        f"{deg.gain_p_adjusted:.2g}): "
        f"{term} is not named"
    )


def head(exps: Sequence[DiagExperiment], drifting: Sequence[int], ps: Sequence[float] = ()) -> str:
    """The verdict's first clause: the recordings drift, k of n, each by how much per period; "may drift"
    with each one's adjusted p (``ps``, settling.drift_p) when some is not firm (drift_said.FIRM)."""
    moves = ", ".join(f"{exps[i].source} {100 * rate(exps[i]):+.2g} %" for i in drifting)
    verb = "may drift" if any(not firm(p) for p in ps) else "drift"
    evidence = (
        f"; trend test, Holm over the records: adjusted p = {', '.join(f'{p:.2g}' for p in ps)}" if ps else ""
    )
    return (
        f"the recordings {verb} from period to period, {len(drifting)} of {len(exps)} (the fundamental per "
        f"period: {moves}{evidence}): a transient not yet settled, an output gain or zero drifting over the "
        "record (a sensor's calibration, e.g. with temperature), or degradation the drift test does not "
        "name; nothing is named from the few settled ones"
    )


def verdict_of(
    d: Diagnosis,
    exps: Sequence[DiagExperiment],
    drifting: Sequence[int],
    deg: Optional[DegradationTest],
    ps: Sequence[float] = (),
) -> Diagnosis:
    """``d`` (the diagnosis of the settled experiments) restated with the drift first: status "unexplained",
    its named terms kept as partial (a hint), its verdict after the drift's clause."""
    kept = [e.source for i, e in enumerate(exps) if i not in drifting]
    verdict = head(exps, drifting, ps) + reading(deg) + f"; on {', '.join(kept)} alone: {d.verdict}"
    return replace(d, status="unexplained", verdict=verdict, named=(), partial=(*d.named, *d.partial))


__all__ = ["ENABLED", "head", "most", "rate", "reading", "verdict_of"]

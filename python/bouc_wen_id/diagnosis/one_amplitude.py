"""A loop-shape term named from a design that cannot test the amplitude law (issue 18, task family39).

With one amplitude per frequency a loop-shape term (pinching, dry friction on u or x, play) and a loop of
another hysteresis family (a distribution of stops, Iwan; a Prandtl-Ishlinskii operator) are the same few
harmonics of each experiment: only a second amplitude at a frequency separates them, where Bouc-Wen's
loop with the term follows its amplitude law and the other family's loop follows its own
(studies/outside_design.py: Iwan loops named "explained by pinching" alone at p 0.54 on three frequencies
at one amplitude). The law test across experiments (:func:`.select.law_test`) compares the term's one value
between experiments of different frequencies only, which says nothing of the amplitude law.

So when such a term is named and no frequency of the design carries two distinct amplitudes, the verdict
says so in a clause (:func:`text`) whose mark (:data:`ONE_AMPLITUDE_MARK`) the headline carries as a rival
reading (:mod:`.readings`: the printed status gains "not the only reading"); the term stays named, with its
value. The clause names the separating experiment: a second amplitude, half the design's largest, at one of
its frequencies. Dahl friction carries its own family caveat (:func:`.caveats.family_text`) and is not
repeated here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..terms import TERMS, Coulomb, Pinching, Place, Play

#: The loop-shape terms (code names) whose identification rests on the amplitude law.
LOOP_SHAPE = (Pinching.kind, Coulomb.kind, Coulomb.at(Place.X).kind, Play.kind)
#: The words that mark the caveat in a verdict and its headline (the bench reads them: benches/diagnosis.py).
ONE_AMPLITUDE_MARK = "would look the same on one amplitude"
#: Two amplitudes at one frequency are distinct when they differ by more than this fraction of the larger.
REL_TOL = 0.05


def _levels(exps: Sequence[Any]) -> dict[float, list[float]]:
    """Each frequency of ``exps`` (rounded to 6 significant digits) -> its experiments' amplitudes."""
    out: dict[float, list[float]] = {}
    for e in exps:
        f, a = float(e.frequency), float(e.amplitude)
        if not (math.isfinite(f) and math.isfinite(a)):
            raise ValueError(f"experiment with frequency {f} and amplitude {a}: both must be finite")
        out.setdefault(float(f"{f:.6g}"), []).append(abs(a))
    return out


def _distinct(amps: Sequence[float]) -> int:
    """How many of ``amps`` differ from each other by more than :data:`REL_TOL` of the larger."""
    kept: list[float] = []
    for a in sorted(amps):
        if not kept or a - kept[-1] > REL_TOL * a:
            kept.append(a)
    return len(kept)


def untested(exps: Sequence[Any]) -> bool:
    """Whether no frequency of ``exps`` carries two distinct amplitudes: the amplitude law is untested."""
    return bool(exps) and all(_distinct(a) < 2 for a in _levels(exps).values())


def text(named: Sequence[Any], exps: Sequence[Any]) -> str:
    """The verdict's clause for the loop-shape terms among ``named`` when ``exps`` cannot test their
    amplitude law (:func:`untested`); empty otherwise."""
    return _clause(named, exps) if untested(exps) else ""


def across_text(named: Sequence[Any], by_condition: Sequence[Sequence[Any]]) -> str:
    """:func:`text` for the diagnosis across conditions (:mod:`.across_verdict`): the clause when at no
    condition a frequency carries two distinct amplitudes (``by_condition``: each condition's experiments).
    Two amplitudes at two conditions do not test the law: the term's value is free per condition, so the
    condition may have moved it."""
    if not by_condition or not all(untested(exps) for exps in by_condition):
        return ""
    return _clause(named, [e for exps in by_condition for e in exps])


def _clause(named: Sequence[Any], exps: Sequence[Any]) -> str:
    """The clause of :func:`text` for the loop-shape terms among ``named``, its amplitude law untested on
    ``exps`` (the caller's check); empty when none is named."""
    shape = [t for t in named if t.term in LOOP_SHAPE]
    if not shape or not exps:
        return ""
    labels = " and ".join(TERMS[t.term].place_label() for t in shape)
    top = max(abs(float(e.amplitude)) for e in exps)
    f = float(max(exps, key=lambda e: abs(float(e.amplitude))).frequency)
    return (
        f"; {labels}: a loop of another family (distributed stops, Prandtl-Ishlinskii) {ONE_AMPLITUDE_MARK} "
        f"(each frequency recorded at one amplitude, largest U = {top:.3g}: the amplitude law that tells "
        f"Bouc-Wen's loop with this term from theirs is untested), record a second amplitude, e.g. "
        f"U = {top / 2:.3g} at omega = {f:.3g} rad/s"
    )


def reading_words(clause: str) -> str:
    """The headline's words for a :func:`text` clause: the rival reading and the separating experiment."""
    i = clause.find("record a second amplitude")
    tail = clause[i:] if i >= 0 else "record a second amplitude"
    return f"or a loop of another family (distributed stops, Prandtl-Ishlinskii) {ONE_AMPLITUDE_MARK}: {tail}"

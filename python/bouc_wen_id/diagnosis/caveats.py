"""What a verdict must say about the design behind it (issue 18: "verdicts that depend on the design say so").

- :func:`alternatives_text`: a named term the experiments cannot tell from a rival (one amplitude per
  frequency, or G nearly flat over the band, cannot separate a spring on x from one on u) is reported with
  its rival in the one-line verdict, not only in the summary's alternatives.
- :func:`below_saturation`: when every experiment stays below the hysteresis' saturation, a spring on x
  trades with |G| and could not show; the notes say so (benches/diagnosis_designs.py measured a 30x spring
  on x "adequate" on such a design).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS, Play, StiffnessX
from .masing import Separation, masing_text, separation
from .result import NamedTerm
from .select import LAW_ALPHA, Alternative


def below_saturation(sx: Sequence[AugExperiment], fit: AugFit) -> list[str]:
    """A note when every experiment stays below the hysteresis' saturation (``fit``'s latent amplitudes
    ``|x_i| = |g_i| U_i`` under ``w_u = (beta + gamma)^(-1/mu)``, alpha = 1; the final fit's, so that a spring
    on x, which lifts them, is seen): there the loop is nearly linear and a spring on x trades with |G|, so
    the design could not show one (a 30x spring on x over three frequencies at 0.3 of saturation gave
    "adequate"). Not from a fit stopped on a face of its admissible range (``fit.active``: mu at its lower
    bound, ``|gamma| = beta``): there ``beta + gamma`` is whatever the stall left (a spring on x absorbed as a
    nearly linear loop, ``beta + gamma`` near 0, put experiments at 1-8 times saturation at 0.12-0.35 of it,
    review 31a), so the level it reads is no level of the data."""
    if fit.active:
        return []
    levels = latent_levels(sx, fit)
    if not levels or max(levels) >= 1.0:
        return []
    return [
        "every experiment stays below the hysteresis' saturation (latent amplitude, as the fitted model sees "
        f"it, {min(levels):.2g}-{max(levels):.2g} of its saturation level): the loop is nearly linear there, "
        "and a spring across the hysteretic element (on x) trades with |G|, so it could neither show nor be "
        "told from |G|; an experiment past saturation (1.5-3 times that level) would separate them"
    ]


def latent_levels(sx: Sequence[AugExperiment], fit: AugFit) -> list[float]:
    """Each experiment's latent amplitude ``|g_i| U_i`` over the saturation level ``w_u = (beta +
    gamma)^(-1/mu)`` (alpha = 1), as ``fit`` sees it; empty when the element has no saturation level."""
    par = fit.params
    if not par.beta + par.gamma > 0:
        return []
    w_u = float((par.beta + par.gamma) ** (-1.0 / par.mu))
    return [abs(float(g)) * e.amplitude / w_u for e, g in zip(sx, par.gains)]


def rivals_of(
    alternatives: Sequence[Alternative], named: Sequence[str]
) -> tuple[dict[str, list[str]], list[Alternative]]:
    """The rivals of the ``named`` terms (code names) among ``alternatives``: ``({term: [rival, ...]},
    by_law)``, ``by_law`` the alternatives passed over for their law only, though they fit at least as
    well (select.preferred_by_fit: the law, not the fit, told them apart, so each gets its own clause with
    the law's p)."""
    kinds = set(named)
    rivals: dict[str, list[str]] = {}
    by_law: list[Alternative] = []
    for a in alternatives:
        if a.term not in kinds:
            continue
        if math.isfinite(a.law_p_value):
            by_law.append(a)
        elif a.rival not in rivals.setdefault(a.term, []):
            rivals[a.term].append(a.rival)
    return {t: rs for t, rs in rivals.items() if rs}, by_law


def alternatives_text(alternatives: Sequence[Alternative], named: Sequence[NamedTerm]) -> str:
    """The verdict's word on a named term the data cannot tell from a rival (issue 18: "never one of them
    silently"): a design with one amplitude per frequency, or G nearly flat over the band, cannot separate a
    spring on x from one on u, and the one-line verdict named one place only."""
    rivals, by_law = rivals_of(alternatives, [t.term for t in named])

    def label(kind: str) -> str:
        return TERMS[kind].place_label() if kind in TERMS else kind

    text = ""
    if rivals:
        what = "; ".join(" or ".join(label(k) for k in (t, *rs)) for t, rs in rivals.items())
        text += (
            f"; the experiments cannot tell apart: {what} (alternatives, each with the experiment that would "
            "separate them)"
        )
    for a in by_law:
        text += (
            f"; {label(a.term)} is named over {label(a.rival)}, which fits at least as well but whose value "
            f"differs between experiments (law p = {a.law_p_value:.2g}; the law test refuses a true term in "
            f"{100 * LAW_ALPHA:g} % of cases): an alternative, with the experiment that would separate them"
        )
    return text


def unphysical_places_text(steps: Sequence[Any], named: Sequence[NamedTerm]) -> str:
    """The verdict's word on a named term's other place that fits about as well only with a value outside
    its physical range (a step's ``unphysical_places``, :func:`.select.place_alternatives`): not an
    alternative, and said so (where x lags u by about pi, viscous damping on x fits as well as on u with
    a negative damping). Empty when there is none."""
    kinds = {t.term for t in named}
    said: list[tuple[str, str]] = []
    for st in steps:
        for rival in getattr(st, "unphysical_places", ()):
            if st.chosen in kinds and (st.chosen, rival) not in said:
                said.append((st.chosen, rival))
    return "".join(
        f"; {TERMS[r].place_label()} fits about as well as {TERMS[t].place_label()} only with "
        f"{TERMS[r].unphysical or 'a value outside its physical range'}: not physical, so no alternative"
        for t, r in said
    )


#: The words that mark the family caveat in a verdict (the bench reads them: benches/diagnosis.py).
FAMILY_MARK = "a Dahl-like friction loop"


def caveats_of(
    named: Sequence[NamedTerm], sx: Sequence[AugExperiment], fit: AugFit, exps: Sequence[Any], alpha: float,
    substeps: int,
) -> str:  # fmt: skip
    """:func:`family_text` for one group: its latent levels, and when a spring on x is named from a design
    with an experiment below saturation, whether that design separates it from a Prandtl-Ishlinskii loop
    (:func:`.masing.separation`; ``exps``' periods name the separating experiment)."""
    from .rate_rival import rate_text

    return family_text(
        named, latent_levels(sx, fit), masing_separation(named, sx, fit, exps, alpha, substeps)
    ) + rate_text(named, sx, fit, substeps)


def masing_separation(
    named: Sequence[Any], sx: Sequence[AugExperiment], fit: AugFit, exps: Sequence[Any], alpha: float,
    substeps: int,
) -> Optional[Separation]:  # fmt: skip
    """:func:`.masing.separation` of one group's final ``fit`` when a spring on x is among ``named`` and some
    experiment lies below saturation (its latent level, :func:`latent_levels`); None otherwise (every
    experiment saturating: no design of such loops separates them, said without a measure)."""
    levels = latent_levels(sx, fit)
    if not (any(t.term == StiffnessX.kind for t in named) and levels and min(levels) < 1.0):
        return None
    return separation(sx, fit, [float(getattr(e, "periods", math.nan)) for e in exps], alpha, substeps)


def joint_separation(seps: Sequence[tuple[str, Optional[Separation]]]) -> tuple[str, Optional[Separation]]:
    """The one separation that decides the Masing caveat of a structure named at several conditions (each
    ``(label, sep)``, :func:`masing_separation` of its design): a condition whose data point to a loop of
    another family (its test rejecting, the largest z) first; else one whose design separates them with a
    quiet test (the structure is one across the conditions, and there it was told from such a loop: no
    caveat); else the strongest too-weak design (the largest noncentrality), with its separating experiment.
    ``("", None)`` when no condition has an experiment below saturation."""
    have = [(w, s) for w, s in seps if s is not None]
    refused = [(w, s) for w, s in have if s.refused]
    if refused:
        return max(refused, key=lambda ws: ws[1].z)
    quiet = [(w, s) for w, s in have if s.separable]
    if quiet:
        return quiet[0]
    finite = [(w, s) for w, s in have if math.isfinite(s.lam)]
    if finite:
        return max(finite, key=lambda ws: ws[1].lam)
    return have[0] if have else ("", None)


def family_text(
    named: Sequence[NamedTerm],
    levels: Optional[Sequence[float]] = None,
    sep: Optional[Separation] = None,
    where: str = "",
) -> str:
    """The verdict's word when Dahl friction is named: what it stands for and what the data could not
    exclude (issue 18: a name users can trust blind), and play's equivalence (:func:`play_text`, when
    every experiment reverses from saturation: each of ``levels``, :func:`latent_levels`, at least 1;
    None: not known, said), and a spring on x's Masing caveat (:func:`masing.masing_text`, under the same
    condition; None: not said; or, with an experiment below saturation, when ``sep`` finds the design too
    weak to separate them; ``where``: the condition whose design ``sep`` measured, across conditions). Empty
    when none of them is named."""
    saturated = levels is None or (len(levels) > 0 and min(levels) >= 1.0)
    dahl = [t for t in named if t.term in TERMS and TERMS[t.term].companion]
    # A spring on x from saturating loops may be a Prandtl-Ishlinskii loop's elastic part (masing.py).
    before = play_text(named, saturated) + masing_text(named, saturated and levels is not None, sep, where)
    if not dahl:
        return before
    where = " or ".join(TERMS[t.term].place_label() for t in dahl)
    return before + (
        f"; {where} names {FAMILY_MARK} (a smooth parallel loop that turns after each reversal and "
        "saturates): its branch shape passed its test, but a distribution of stops (Iwan, "
        "Prandtl-Ishlinskii, Masing) or another Dahl exponent fits such loops too; what separates them is "
        "the branch over a wider range of travel: experiments at several amplitudes from well below the "
        "turning travel to 3x it (Dahl approaches its level exponentially, stops reach theirs at a finite "
        "travel)"
    )


#: The words that mark play's equivalence caveat in a verdict.
PLAY_MARK = "a dwell after each reversal"


def play_text(named: Sequence[NamedTerm], saturated: bool = True) -> str:
    """The verdict's word when play is named: a backlash on the measured output draws the same loop.

    After a reversal from saturation the element's branch leaves with one slope at every experiment, so a
    backlash of half-width c on the output dwells exactly as a play of half-width c / slope on x: at
    saturating amplitudes no test of the dwell's shape tells them apart (session 28: a flat, sharply
    resolved dwell at x's turn, dwell slope -0.0017 +- 0.0036, on the blind bench's output backlash). Only
    reversals from different levels of w (amplitudes around and below saturation) separate them, where
    the equivalent play would change with the amplitude and its law test would refuse it. So the clause
    is said only when ``saturated`` (every experiment's latent amplitude at or past the saturation level,
    :func:`latent_levels`): with an experiment below it, the separating experiment has been run."""
    if not saturated or not any(t.term == Play.kind for t in named):
        return ""
    label = Play.place_label()
    return (
        f"; {label} names {PLAY_MARK}: a backlash on the measured output (a dead band in the sensor or "
        "its linkage) dwells alike when every reversal starts from saturation; what separates them is "
        "experiments at amplitudes around and below saturation (a play keeps its width in x, an output "
        "backlash in y)"
    )

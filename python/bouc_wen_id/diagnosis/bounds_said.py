"""What the verdict says of values held at an admissible bound (issue 18: "a value outside its physical range
is never named: fit within the admissible range, or report 'not physical' and what that suggests").

Two cases, one job: a misfit whose best reading lies beyond a range the model keeps, said in the verdict's
headline rather than left to stand-ins.

- **A candidate beyond its physical range** (:func:`refused_by_bound`): a first-step candidate that passes
  every test of the step (F test at the step's level, a material share, its value away from its null) but
  whose value lies outside the term's physical range (a negative stiffness) is refused by the selection
  (:func:`.select._admissible`). When it removes most of the excess (at least
  :data:`.run.PARTLY_EXPLAINED_FRACTION`) and no less than the final model does (within the tie margin of
  :func:`.select._tied`), the verdict says its value, the share it would remove and what such a value
  suggests (the registry's ``beyond``); when it removes clearly more than the terms the selection kept
  within the ranges, those are stand-ins for it and are not named (review 34 problem 1: k_u = -0.0447
  removed 95 % at p adj 1e-50; the verdict named sensor lag + Dahl on x at 65 %). The detection limits do not
  state ``|k| < limit`` for such a term (:mod:`.limits`): it was refused by its bound, not undetected.
- **The hysteresis exponent at an end of its bracket** (:func:`apply`): the final fit held at mu's bracket
  end (the core's ``mu=lower`` / ``mu=upper`` face) means the loops ask for a shape the model cannot draw
  (the identification assumes mu >= 1, ``identify``'s mu_bracket refuses lo < 1; the core's right-hand side
  takes ``sgn(w) |w|^mu`` and is finite at w = 0 for any mu > 0, but its sensitivities carry
  ``mu |w|^(mu - 1)`` (rust/steady.rs, rust/series_loop.rs), unbounded at every zero of w below mu = 1, so
  the bracket is not extended); a misfit then is read against a misspecified hysteresis, and the verdict
  says so first: the terms that fit part of it are conditional on it and may stand in for that shape
  (review 34 problem 2: mu = 0.5 named viscous + Coulomb + Dahl on x on a null and never mentioned mu), so
  they are not named: said as fitted with mu held there, their values without standard errors (review 36
  problem 3). On the targeted path too (:func:`targeted`, :func:`targeted_across`): when the plain model
  passed its global test (a coloured noise's larger level) and the targeted step found the terms with the
  plain and final fits' mu at the lower end, an adequate final model is no finding either (review 47 failure
  1: mu = 0.75 under AR(1) noise of 0.95 named stiffness@x + play "explained", no word of mu).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

from ..augmented import AugFit
from ..terms import TERMS
from .bounds_clear import PhysicalTwin, clearly_better, physical_twin, removes, twin_text
from .drift import DRIFT_TERMS
from .fitting import Scale, physical
from .result import NamedTerm, Status, term_symbol_unit
from .select import MATERIAL_SHARE, TIE_SD, Step, Trial, _admissible, at_null, away_from_null, dof_of

#: Share of the excess a candidate beyond its range must remove to be said ("most of the excess").
MOST = 0.5


def refused_by_bound(tr: Trial, level: float) -> bool:
    """Whether ``tr`` passed its step's tests at ``level`` (F test, material share, away from its null) and
    was refused only because its value lies outside the term's physical range."""
    f = tr.fit
    if f is None or not (math.isfinite(tr.p_adjusted) and tr.p_adjusted < level):
        return False
    if not (tr.share >= MATERIAL_SHARE) or _admissible(f, tr.term) or at_null(f, tr.term):
        return False
    return away_from_null(f, tr.term, level)


def _tie(better: float, worse: float, cost: float, dof: int) -> bool:
    """Whether improvements ``better`` >= ``worse`` (chi-square) are within :data:`.select.TIE_SD` of the
    larger's noise (:func:`.select._tied`'s rule: sd ~ 2 sqrt(Delta C s2), s2 the residual variance)."""
    s2 = max(1.0, cost / dof) if dof > 0 else 1.0
    return better - worse <= TIE_SD * 2.0 * math.sqrt(max(better, 0.0) * s2)


@dataclass(frozen=True)
class Beyond:
    """The out-of-range candidates the verdict says (best first), whether they remove clearly more than the
    final model, and the final fit's mu face."""

    #: (the term with its value in physical units, its trial), best first; empty when none is said.
    found: tuple[tuple[NamedTerm, Trial], ...] = ()
    #: The best of them removes clearly more than the final model (beyond the tie margin).
    beats_final: bool = False
    #: "lower" / "upper": the final fit held at that end of mu's bracket; "" inside.
    mu_face: str = ""
    mu: float = math.nan
    #: Per entry of ``found``, its exact physical twin in the step (:func:`.bounds_clear.physical_twin`).
    twins: tuple[Optional[PhysicalTwin], ...] = ()
    #: The final model's improvement when the best removes at least as much, but not clearly more (NaN
    #: otherwise): those that do are rival readings of what is named (:data:`BEYOND_MARK`).
    rivals_final: float = math.nan
    #: The first step's cost showed no excess over its dof (:func:`.bounds_clear.removes`): no share said.
    no_excess: bool = False
    #: The terms were found by the targeted step (the plain model passed its global test) with the plain
    #: fit's mu, and the final's, at the lower end: an adequate final model is then no finding (review 47
    #: failure 1: mu = 0.75 under AR(1) noise named stiffness@x + play "explained").
    targeted_soft: bool = False
    #: The halves of the frequencies, fitted apart, each hold mu inside its bracket (:mod:`.soft_rate`'s
    #: clause; "" otherwise): the lower end is a loop changing with the rate, not a softer exponent.
    rate: str = ""


def held_mu(fit: AugFit) -> Beyond:
    """``fit``'s mu face (the core's ``mu=lower`` / ``mu=upper``; "" inside its bracket) and its mu."""
    faces = [a.partition("=")[2] for a in getattr(fit, "active", ()) if a.startswith("mu=")]
    mu = getattr(getattr(fit, "params", None), "mu", math.nan)  # a stub without params: inside
    return Beyond(mu_face=faces[0] if faces else "", mu=float(mu))


def across_text(groups: Sequence[Any], status: str) -> str:
    """The clause on mu held at its bracket's end at the conditions of :func:`.across.diagnose_across`
    (each condition's final fit, ``g.current``; ``""`` when none or the verdict is adequate)."""
    if status == "adequate":
        return ""
    said = [(g.label, held_mu(g.current)) for g in groups]
    return "".join(f"; at {label}: {_mu_text(b).removeprefix('; ')}" for label, b in said if b.mu_face)


def targeted_across(groups: Sequence[Any], steps: Sequence[Any]) -> bool:
    """:func:`targeted`'s mark at the conditions of :func:`.across.diagnose_across`: the joint first step was
    the targeted one and every condition's plain fit (``g.plain``) and final fit (``g.current``) hold mu at
    its lower end; the joint structure is then said as stand-ins, not named (review 47 failure 1)."""
    lower = all(held_mu(g.plain).mu_face == "lower" == held_mu(g.current).mu_face for g in groups)
    return bool(steps) and bool(steps[0].targeted) and bool(groups) and lower


def found(
    steps: Sequence[Step],
    alpha: float,
    final: AugFit,
    s: Scale,
    units: tuple[str, str],
    exps: Sequence[Any],
    substeps: int = 0,
    plain: Optional[AugFit] = None,
) -> Beyond:
    """The candidates of the first step refused only by their bound that remove most of the excess and no
    less than the final model (``final``, its cost on the steps' experiments ``exps``) within the tie
    margin, each with its physical twin if any, and ``final``'s mu face. The best beats the final model
    when it removes more beyond the tie margin or beyond the noise of the two fits' difference
    (:func:`.bounds_clear.clearly_better`, review 35m F6). ``plain``: the plain fit, for :func:`targeted`'s
    mark (review 47: mu held at its lower end on the targeted path)."""
    if plain is not None:
        return targeted(found(steps, alpha, final, s, units, exps, substeps), steps, plain)
    face, mu = held_mu(final).mu_face, float(final.params.mu)
    if not steps:
        return Beyond(mu_face=face, mu=mu)
    st = steps[0]
    level = 0.5 * alpha if st.targeted else alpha
    imp_final = st.before_cost - final.cost
    # Most of the excess, or (beside named terms) at least what the final model removes: review 35m F6's
    # k = -0.015 removed 44 % alone, more than the Dahl friction on x named "explained by" (32 %).
    hits = sorted(
        (
            tr
            for tr in st.trials
            if refused_by_bound(tr, level)
            and (tr.share >= MOST or (bool(final.params.terms) and tr.improvement >= imp_final))
        ),
        key=lambda t: t.cost,
    )
    if not hits:
        return Beyond(mu_face=face, mu=mu)
    best, dof = hits[0], dof_of(exps, final)
    if best.improvement < imp_final and not _tie(imp_final, best.improvement, final.cost, dof):
        return Beyond(mu_face=face, mu=mu)  # the final model removes clearly more: no reading of it
    assert best.fit is not None
    clear = not _tie(best.improvement, imp_final, best.cost, dof)
    beats = bool(final.params.terms) and (clear or clearly_better(exps, best.fit, final, dof, level))
    keep = [tr for tr in hits if _tie(best.improvement, tr.improvement, best.cost, st.before_dof)]
    out = []
    twins = []
    for tr in keep:
        assert tr.fit is not None
        v, se = physical(tr.fit, s, tr.term)
        sym, unit = term_symbol_unit(tr.term, *units)
        out.append((NamedTerm(tr.term, sym, v, se, unit), tr))
        twins.append(physical_twin(exps, st, tr, level, s, units, substeps))
    beats = beats and best.improvement > imp_final
    rivals = bool(final.params.terms) and not beats and best.improvement >= imp_final
    rival = imp_final if rivals else math.nan
    return Beyond(tuple(out), beats, face, mu, tuple(twins), rival, st.before_cost <= st.before_dof)


def targeted(b: Beyond, steps: Sequence[Step], plain: AugFit) -> Beyond:
    """``b`` marked :attr:`Beyond.targeted_soft` when the first step was the targeted one (the plain model
    passed its global test) and both the plain fit (``plain``) and the final one hold mu at its lower end."""
    soft = bool(steps) and steps[0].targeted and b.mu_face == "lower" and held_mu(plain).mu_face == "lower"
    return replace(b, targeted_soft=True) if soft else b


def _suggests(term: str) -> str:
    cls = TERMS[term]
    return cls.beyond or cls.unphysical or "a value outside its physical range"


def _found_text(b: Beyond, fraction: float, kept: Sequence[NamedTerm]) -> str:
    ranges, what, instead = _found_parts(b, fraction, kept)
    return f"not explained{ranges}: {what}{instead}; "


#: The words that open the verdict when mu is held at the lower end of its bracket beside a candidate beyond
#: its range (:func:`apply`): the loop's shape leads, the out-of-range value follows as its possible stand-in.
SOFT_HEAD = "not explained: the loops may be"


def _soft_head(b: Beyond) -> str:
    """The headline when the final fit holds mu at the lower end of its bracket and a candidate beyond its
    range is what would explain most (mu41; review 40 item 2: a mu = 0.7 loop through a resonant G led with
    a 48-se negative mass and "an input recorded with the wrong sign or scale")."""
    if b.rate:  # review 47 failure 4: the structure is the rate's (soft_rate.py)
        return f"not explained: {b.rate}; "
    return f"{SOFT_HEAD} {SOFTER}, a shape outside the model (mu held at {b.mu:.3g}, its lower end); "


def _stand_in_text(b: Beyond, fraction: float, kept: Sequence[NamedTerm]) -> str:
    """The out-of-range candidates said after the mu clause, as what may stand in for the loop's shape."""
    _, what, instead = _found_parts(b, fraction, kept)
    return f"; beyond a term's physical range, what may stand in for that shape: {what}{instead}"


def _found_parts(b: Beyond, fraction: float, kept: Sequence[NamedTerm]) -> tuple[str, str, str]:
    """(" within the terms' physical ranges" or "", the candidates said, the kept terms' clause or "")."""
    twins = (*b.twins, *(None,) * (len(b.found) - len(b.twins)))
    what = "; ".join(
        twin_text(tw, t, _suggests(t.term), b.no_excess)
        if tw is not None
        else f"{t} {removes(tr, b.no_excess)}), beyond its physical range: {_suggests(t.term)}"
        for (t, tr), tw in zip(b.found, twins)
    )
    labels = ", ".join(t.label for t in kept)
    instead = (
        f"; the terms the selection kept within the ranges ({labels}) remove {100 * fraction:.0f} % of the "
        "excess and stand in for it, not named"
        if kept
        else ""
    )
    # A physical reading fits as well (review 35m F9): the misfit is not beyond the ranges, only not named.
    ranges = "" if all(tw is not None for tw in twins) else " within the terms' physical ranges"
    return ranges, what, instead


#: The words that open the clause on a reading beyond its range that fits as well as the named terms
#: (:mod:`.readings` puts "or a reading beyond a term's physical range" in the headline).
BEYOND_MARK = "a reading beyond its physical range fits as well as the named terms"


def _rival_text(b: Beyond, named: Sequence[NamedTerm]) -> str:
    """Review 35m F6, condition 2: a negative stiffness on u fitted 6 chi2 better than the Dahl friction on x
    named "explained by", within chance, and was said only in the detection limits. One whose physical
    twin is a named term is design_twin.py's (one frequency: a negative stiffness on x is the named inertia
    on x)."""
    kinds = {t.term for t in named}
    twins = (*b.twins, *(None,) * (len(b.found) - len(b.twins)))
    items = []
    for (t, tr), tw in zip(b.found, twins):
        if tr.improvement < b.rivals_final or (tw is not None and tw.named.term in kinds):
            continue
        more = tr.improvement - b.rivals_final
        how = f"{more:.3g} chi-square more than they do" if more >= 0.05 else "as much as they do"
        if tw is not None:  # its physical twin first, the reading beyond its range as its alternative (F9)
            items.append(
                f"{twin_text(tw, t, _suggests(t.term), b.no_excess)}; it removes {how}, within chance"
            )
        else:
            items.append(f"{t} (removes {how}, within chance; {_suggests(t.term)})")
    return f"; {BEYOND_MARK}: {'; '.join(items)}" if items else ""


#: The loop shape the lower end of mu's bracket stands for: mu < 1 turns more gradually after a reversal.
SOFTER = "softer than mu = 1 allows (mu < 1: turning more gradually after a reversal)"

#: The words that open the mu clause (:func:`_mu_text`; :mod:`.readings` puts a qualifier in the headline).
MU_MARK = "the hysteresis exponent is held at the"


def _mu_text(b: Beyond) -> str:
    # Not "the loops ask for mu < 1": a true mu = 1 (the classic Bouc-Wen) sits at the same end whenever
    # something else is missing (review of the merge: slack and a rate-dependent loop at mu = 1).
    # The lower end is where the fit is pulled toward mu < 1: a loop that turns more gradually after a
    # reversal, i.e. softer, not sharper (a larger mu sharpens the knee; review 40 item 2: mu = 0.7 was said
    # "sharper").
    if b.rate:  # the halves fitted apart hold mu inside: a rate-dependent loop (soft_rate.py)
        return (
            f"; {MU_MARK} {b.mu_face} end of its bracket (mu = {b.mu:.3g}) by the frequencies fitted "
            "together: a term that fits part of the misfit may stand in for a loop that changes with the "
            "rate; the verdict is conditional on it"
        )
    beyond = SOFTER if b.mu_face == "lower" else "beyond what its bracket allows"
    return (
        f"; {MU_MARK} {b.mu_face} end of its bracket (mu = {b.mu:.3g}; the identification's range is "
        f"mu >= 1): either the true exponent is there, or the loops are {beyond} and a term that fits part "
        "of the misfit may stand in for that shape; the verdict is conditional on it"
    )


#: What remains said after :func:`_soft_head` when the terms came from the targeted step (the plain model
#: passed its global test, so no share of an excess is said): where the misfit was found.
TARGETED_BODY = "a misfit the global test did not flag, found by the targeted step (the terms below)"

#: The words that open the clause on the terms fitted with mu held at its bracket's end (:func:`_held_text`).
HELD_MARK = "fitted with mu held at the"


def _held_text(named: Sequence[NamedTerm], face: str, rate: bool = False) -> str:
    """The terms the selection kept beside mu held at its bracket's ``face``, said as stand-ins: their values
    without their standard errors (those assume the hysteresis is right; review 36 problem 3: mu = 0.6 with
    a spring on x named k at 2.6x the truth, 48 se, and a play and a viscous damping that are not there)."""
    what = ", ".join(f"{t.label} {t.symbol} = {t.value:.4g} {t.unit}".rstrip() for t in named)
    shape = f"a loop {SOFTER}" if face == "lower" else "a loop shape beyond mu's bracket"
    shape = "a loop that changes with the rate" if rate else shape
    return (
        f"; {HELD_MARK} {face} end of its bracket, not named: {what} (values without their standard errors, "
        f"which assume the hysteresis is right; they may stand in for {shape})"
    )


def apply(
    b: Optional[Beyond],
    status: Status,
    named: Sequence[NamedTerm],
    terms: Sequence[NamedTerm],
    fraction: float,
) -> tuple[Status, tuple[NamedTerm, ...], str, str]:
    """``(status, named, head, tail)``: the verdict's status and named terms after the values held at a bound,
    with the clause that leads the verdict (``head``) and the one that closes it (``tail``). "Unexplained",
    the named terms demoted to stand-ins, when a candidate beyond its range removes clearly more than the
    final model's ``terms`` (which remove ``fraction`` of the excess); one that only ties with the final model
    is not said (a design twin's tie is design_twin.py's). A final fit holding mu at its bracket's end with a
    misfit left (not "explained": an adequate final model within the bracket stands, its fit note says the
    face) is said in a clause after the headline, whose qualifiers then say the verdict is conditional on it;
    the terms the selection kept are then not named: the status is "unexplained" and a clause says them as
    fitted with mu held there, their values without standard errors (review 36 problem 3: mu = 0.6 with a
    spring on x named k at 2.6x the truth, 48 se, beside a play and a viscous damping on x that are not
    there). This also demotes real data's terms when mu is held there (the MR damper at 0, 0.5, 0.75 A:
    its viscous damping is then said as fitted with mu at 1, not as a finding).
    """
    named = tuple(named)
    if b is None or status == "adequate":
        return status, named, "", ""
    # After the headline, not before it: the headline keeps what is named (the MR damper's viscous damping
    # and asymmetry), with "conditional on mu ..." among its qualifiers (readings.py).
    # An adequate final model stands, unless its terms came from the targeted step with mu at the lower end
    # (review 47 failure 1): the plain model passed too, and the terms may stand in for a softer loop.
    mu = _mu_text(b) if b.mu_face and (status != "explained" or b.targeted_soft) else ""
    if b.found and (b.beats_final or not terms):
        if mu and b.mu_face == "lower":  # the loop's shape leads, the out-of-range value is its stand-in
            return "unexplained", (), _soft_head(b), mu + _stand_in_text(b, fraction, terms)
        return "unexplained", (), _found_text(b, fraction, terms), mu
    steady = tuple(t for t in named if t.term not in DRIFT_TERMS)
    if mu and steady:  # review 36 problem 3: stand-ins for the loop's shape, not findings
        # a drift term stays: its test is on the period-to-period drift, not on the loop's shape
        kept = tuple(t for t in named if t.term in DRIFT_TERMS)
        head = (
            _soft_head(b) if b.targeted_soft and not kept else ""
        )  # the loop's shape leads (no misfit left)
        return (
            ("partly explained" if kept else "unexplained"),
            kept,
            head,
            mu + _held_text(steady, b.mu_face, bool(b.rate)),
        )
    # One that removes less than the final model is not said (review of the merge: a 56 % negative
    # stiffness beside an inertia that explains 100 %, P-Delta "suggested"; an exact tie is a design twin,
    # said by design_twin.py with the experiment that separates them); one that removes as much or more,
    # within chance, is a rival reading of what is named.
    rival = _rival_text(b, named) if b.found and named and math.isfinite(b.rivals_final) else ""
    if mu and b.mu_face == "lower" and not named:  # review 43 d5: a mu = 0.8 null led "unexplained
        return status, named, _soft_head(b), rival + mu  # structure remains", the reason in a later bullet
    return status, named, "", rival + mu


__all__ = [
    "BEYOND_MARK",
    "Beyond",
    "across_text",
    "apply",
    "found",
    "held_mu",
    "refused_by_bound",
    "HELD_MARK",
    "MOST",
    "SOFT_HEAD",
    "SOFTER",
    "targeted",
    "targeted_across",
    "TARGETED_BODY",
]

"""The place of a term chosen per condition, fitted and tested jointly (review 36b, problem 1).

:mod:`.across_moved` (``found``) finds a term at another place at the conditions where the joint
candidate (one place shared by every condition) is beyond its range. Here the two places are put
together as one joint structure with the place free per condition (the sibling's fit where the shared
place is beyond its range, the shared place's fit elsewhere; values per condition) and tested as the across
path tests a candidate: the combined F test against the model it was fitted on
(:func:`.select.pooled_f`,
at the step's level), a physical value away from its null wherever it is present, the law test at each
condition (Bonferroni), the held-out cost summed over the conditions, and against each single-place joint
fit kept within the physical ranges (the shared place with the term at its null where its value is beyond
range, the sibling likewise): the conditions where that fit holds no term are nested in the mixed one, so
the combined F over them says whether the free place is needed. When all pass, the term is named with its
place per condition. A condition where both places fit with physical values and their costs differ by less
than the F test's critical value at that level cannot separate them: both are said as alternatives there,
with the experiment that separates them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

from ..terms import TERMS
from .across_types import _median
from .fitting import physical
from .law import element_law_test
from .result import term_symbol_unit
from .select import LAW_ALPHA, NOISE_FLOOR, _admissible, at_null, away_from_null, dof_of, held_out, pooled_f


@dataclass(frozen=True)
class PlaceFree:
    """The joint fit with the place per condition and its tests."""

    places: tuple[str, ...]
    p_value: float
    p_against: tuple[float, ...]  # against each single-place joint fit kept within range
    law_p: float
    held_out_before: float
    held_out_after: float
    physical: bool
    undecided: tuple[int, ...]  # conditions where both places fit alike

    @property
    def named(self) -> bool:
        held = not math.isfinite(self.held_out_before) or self.held_out_after < self.held_out_before
        law = not math.isfinite(self.law_p) or self.law_p >= LAW_ALPHA
        return (
            self.physical and law and held and all(p < self._level for p in (self.p_value, *self.p_against))
        )

    _level: float = 0.01
    held_tested: bool = True  # False when the user turned the held-out test off (``held_out_test``)
    held_out_nrmse: tuple[float, ...] = ()  # each condition's median held-out NRMSE (its table's column)


def _chosen(places: Sequence[str], tr: Any, sib: Any) -> list[Any]:
    """Each condition's fit at its place: ``sib``'s where the place is the sibling's, ``tr``'s elsewhere."""
    return [sib.fits[i] if t == sib.term else tr.fits[i] for i, t in enumerate(places)]


def _base_cost(f: Any, imp: float) -> float:
    return float(f.cost) + float(imp)


def _against(
    groups: Sequence[Any], mixed: Sequence[Any], single: Any, base: Sequence[float], q: int
) -> float:
    """The combined F p of the mixed fit against ``single`` kept within the physical ranges (its term at
    its null where beyond range: the base model, nested in the mixed fit), over the conditions where the
    two differ. Where ``single`` is physical and at the other place, the two fits are of the same size and
    not nested: their cost difference is held to the same statistic (a difference beyond its critical
    value), never below 0."""
    imp, c1, d1 = [], [], []
    for i, (g, f) in enumerate(zip(groups, mixed)):
        s = single.fits[i]
        inside = s is not None and _admissible(s, single.term)
        if inside and s is f:
            continue  # the same fit at the same place
        imp.append((s.cost if inside else base[i]) - f.cost)
        c1.append(f.cost)
        d1.append(dof_of(g.sx, f))
    if not imp:
        return 1.0
    return pooled_f(imp, c1, d1, q)[1]


def fit(
    groups: Sequence[Any], tr: Any, sib: Any, out: Sequence[int], level: float, held: bool = True
) -> Optional[PlaceFree]:
    """The place-free joint structure of ``tr`` (shared place) and ``sib`` (its other place, at the
    conditions ``out``), tested; None when a fit is missing. Without ``held`` (the user's ``held_out_test``
    off) no held-out cost is computed nor required, as the joint selection's (across_step._accepts)."""
    k = len(groups)
    if len(tr.fits) < k or len(sib.fits) < k:
        return None
    places = tuple(sib.term if i in out else tr.term for i in range(k))
    mixed = _chosen(places, tr, sib)
    imps = [sib.improvements[i] if i in out else tr.improvements[i] for i in range(k)]
    if any(f is None for f in mixed):
        return None
    base = [_base_cost(f, a) for f, a in zip(mixed, imps)]
    q = 2 if TERMS[tr.term].companion else 1  # a two-term element adds two values
    d1 = [dof_of(g.sx, f) for g, f in zip(groups, mixed)]
    p = pooled_f(imps, [f.cost for f in mixed], d1, q)[1]
    s2 = [max(f.cost / max(d, 1), NOISE_FLOOR) for f, d in zip(mixed, d1)]
    phys = all(
        _admissible(f, t) and not at_null(f, t) and away_from_null(f, t, level, s)
        for f, t, s in zip(mixed, places, s2)
    )
    laws = [element_law_test(g.sx, f, t, g.substeps) for g, f, t in zip(groups, mixed, places)]
    laws = [v for v in laws if math.isfinite(v)]
    law_p = min(1.0, min(laws) * len(laws)) if laws else math.nan
    before = after = 0.0
    nrmse: list[float] = []
    for g, f in zip(groups, mixed) if held else ():
        ho = held_out(g.sx, g.plain, f, g.substeps, g.cache)
        nrmse.append(math.nan if ho is None else _median(ho.nrmse_after))
        if ho is not None:
            before += sum(ho.cost_before)
            after += sum(ho.cost_after)
    against = tuple(_against(groups, mixed, t, base, q) for t in (tr, sib))
    undecided = _undecided(groups, tr, sib, level, q)
    return PlaceFree(
        places,
        p,
        against,
        law_p,
        before if before > 0 else math.nan,
        after,
        phys,
        undecided,
        level,
        held,
        tuple(nrmse),
    )


def _undecided(groups: Sequence[Any], tr: Any, sib: Any, level: float, q: int) -> tuple[int, ...]:
    """The conditions where both places fit with physical values away from their null and their costs
    differ by less than the F test's critical value (q parameters at ``level``)."""
    from scipy.special import fdtri  # type: ignore[import-untyped]

    out = []
    for i, g in enumerate(groups):
        a, b = tr.fits[i], sib.fits[i]
        if a is None or b is None:
            continue
        d = max(dof_of(g.sx, a), 1)
        s2 = max(a.cost / d, b.cost / d, NOISE_FLOOR)
        ok = all(
            _admissible(f, t) and not at_null(f, t) and away_from_null(f, t, level, s2)
            for f, t in ((a, tr.term), (b, sib.term))
        )
        if ok and abs(a.cost - b.cost) < q * s2 * float(fdtri(q, d, 1.0 - level)):
            out.append(i)
    return tuple(out)


def status(pf: PlaceFree, groups: Sequence[Any], alpha: float, sib: Any, tr: Any) -> str:
    """ "explained" when the named place-free structure passes its adequacy test at every condition by
    :mod:`.adequacy`'s one rule (:func:`.adequacy.passes`: a named model at ``alpha``, not drifting; a loop
    drifting from period to period there, ``moved``, is left beyond the steady terms named across), "partly
    explained" otherwise."""
    from .across_adequacy import p_of
    from .adequacy import passes

    fits = _chosen(pf.places, tr, sib)
    ok = all(passes(p_of(g, f), alpha, True, bool(getattr(g, "moved", False))) for g, f in zip(groups, fits))
    return "explained" if ok else "partly explained"


def conditions(pf: PlaceFree, groups: Sequence[Any], conds: Sequence[Any], sib: Any, tr: Any) -> list[Any]:
    """Each condition's result (``conds``, :class:`.across_stable.ConditionResult`) with its final chi2/dof,
    adequacy p and held-out NRMSE (when tested) those of the named place-free structure."""
    from dataclasses import replace

    from .across_adequacy import chi2
    from .locate import adequacy_p

    out = []
    for i, (g, c, f) in enumerate(zip(groups, conds, _chosen(pf.places, tr, sib))):
        d = dof_of(g.sx, f)
        hj = pf.held_out_nrmse[i] if i < len(pf.held_out_nrmse) else c.held_out_joint
        out.append(
            replace(
                c,
                final_chi2_dof=chi2(g, f) / max(d, 1),
                final_p_value=adequacy_p(chi2(g, f), d, g.noise_dof),  # diagnose's statistic (colour)
                held_out_joint=hj,
            )
        )
    return out


def text(pf: PlaceFree, groups: Sequence[Any], tr: Any, sib: Any, units: tuple[str, str]) -> str:
    """The naming (or why not) of the place-free structure, with its tests; each place's value in its own
    unit (``units``: the output's and the input's, :func:`.result.term_symbol_unit`: a term on u has u's)."""

    def one(term: str, v: float) -> str:
        sym, unit = term_symbol_unit(term, *units)
        return f"{TERMS[term].acts_on.label} {sym} = {v:.4g} {unit}".rstrip()

    def vals(term: str, fits: Sequence[Any]) -> str:
        sym, unit = term_symbol_unit(term, *units)
        idx = [i for i, t in enumerate(pf.places) if t == term]
        labels = ", ".join(str(groups[i].label) for i in idx)
        v = ", ".join(f"{physical(fits[i], groups[i].scale, term)[0]:.4g}" for i in idx)
        return f"{TERMS[term].acts_on.label} at {labels} ({sym} = {v} {unit})".replace(" )", ")")

    name = TERMS[TERMS[tr.term].base_kind].label
    ho = (
        f", held-out cost {pf.held_out_before:.4g} -> {pf.held_out_after:.4g}"
        if math.isfinite(pf.held_out_before)
        else ("" if pf.held_tested else "; held-out cost not tested (the held-out test turned off)")
    )
    tests = (
        f"fitted jointly with the place free per condition: p = {pf.p_value:.2g}; against one place shared "
        f"by every condition within the physical ranges p = {pf.p_against[0]:.2g} "
        f"({TERMS[tr.term].acts_on.label}), "
        f"{pf.p_against[1]:.2g} ({TERMS[sib.term].acts_on.label}); law p = {pf.law_p:.2g}{ho}"
    )
    head = f"{name}, its place per condition: {vals(sib.term, sib.fits)}; {vals(tr.term, tr.fits)}"
    said = f"named: {head} ({tests})" if pf.named else f"{head} - not named ({tests})"
    for i in pf.undecided:
        a = physical(tr.fits[i], groups[i].scale, tr.term)[0]
        b = physical(sib.fits[i], groups[i].scale, sib.term)[0]
        said += (
            f"; at {groups[i].label} the two places fit alike "
            f"({one(tr.term, a)}, {one(sib.term, b)}): either, as alternatives - a drive above G's "
            f"band (where G's gain and phase change) or beyond the loop's saturation separates them"
        )
    return said


__all__ = ["PlaceFree", "fit", "conditions", "status", "text"]

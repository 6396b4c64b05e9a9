"""Two large terms at once: the pair step of the forward selection (issue 18).

The forward selection (:func:`.select.forward_select`) adds one candidate per step. When two library terms
are missing at once, each one alone absorbs part of the other's misfit with a value that differs between
experiments, so each fails its law (:func:`.select.law_test`) and the step ends without a name: the
README's three-term plant (viscous damping, play and a sensor lag) was "unexplained". Only then (a step
that named nothing while some candidate's law failed; never the targeted first step, never a step that
named a term) the best :data:`POOL` candidates that passed their own tests are fitted in pairs, and the
best of them with each candidate that did not pass alone (the README plant's play and sensor lag remove
nothing alone while viscous damping, 96 % of the excess, is missing), the second term added to the first's
fit by the same machinery that fits one term (``fit_term``: the memoised :func:`.fitting.fit_with` with its
wide restarts), and a pair is named only when

1. the pair improves on the step's model by its joint F test (Bonferroni over every pair of the step's
   candidates) and **each member is significant given the other**: its own nested F test against the model
   of the other member alone, at the step's level after Bonferroni over the candidates (the single-term
   test), a material share of the excess the other leaves, a physical value away from its null (the
   Wald test at the step's level, :func:`.select.away_from_null`). A rival single term that matches the
   pair's gain leaves one member with no gain of its own, so this test is also the rule against a
   single-term rival;
2. **each member's law holds** in the pair's fit (:func:`.select.element_law_test`, at
   :data:`.select.LAW_ALPHA`): one value for every experiment, the claim a single term must meet;
3. the pair improves the held-out fit (leave-one-experiment-out, as a single term must).

The pairs that pass 1 are taken by cost; the first that passes 2 and 3 is named. A rival pair (or a single
term whose law held) whose improvement is within the chosen pair's uncertainty (:func:`.select._tied`) and
whose laws hold, or one that fits at least as well and was passed over for its law only (p above
:data:`.select.PREFERRED_LAW_FLOOR`), is reported as alternatives of the members it replaces, with the
experiment that would separate them. Physics outside the library stays "unexplained" when no pair of
library terms fits it with one value each (the law of a stand-in still fails beside another stand-in).

**Where it runs.** A candidate that did not pass alone is fitted beside the lead (and tried as a third
term) only where the lead alone removes at least :data:`OTHERS_SHARE` (half) of the step's excess. Such a
candidate is a large term only when the lead's misfit hides it: fitted alone, it bends to a misfit larger
than its own. Unhidden (its signature apart from the lead's), its gain beside the lead is its gain alone,
and it fails alone yet passes beside a lead of share s only when that gain lies between 10 % of the
excess the lead leaves and 10 % of the whole: a window of s/10 of the excess, under 5 % of it for a lead
under half. Beside a weak lead these fits named only stand-ins (the
real-data microwire, a magnetic core, had stiffness, Coulomb friction and inertia on x named through one
such pairing, lead 34 % of the excess, in 2 of its 4 preprocessing variants) and cost most of the step's
time (22-29 fits). The sets the pair step names on simulated plants had leads of 57 % (a reviewer's
stiffness and viscous damping on x, the stiffness removing 0.4 % alone: the nearest to the bound), 87 % (play
with a sensor lag) and 96-97 % (the README's plants); the revisit (:mod:`.revisit`) keeps every candidate,
its own gate already asking a lead of half the excess.

**A lead held on a face.** Where the lead's own fit still sits on a face of its admissible range (``active``:
mu at its bound, ``beta = |gamma|``) with a reduced chi-square above :data:`HELD_CHI2`, its share is no
measure of what it leaves hidden: the range holds the hysteresis where the missing term would let it go,
and the failed-alone candidates are fitted beside it whatever its share (:func:`held_lead`). Review 38's
isolator past saturation (Bouc-Wen with stiffness 0.5 and viscous damping 0.02 on x, first-order G, U 1.5
and 3): the plain fit and viscous damping's sat on mu = 1, the damping removed 49 % of the excess and the
stiffness 0.1 % (every start, wide or at the true hysteresis, returned to the same face: not a start
problem), so no set was fitted and the verdict was "unexplained"; the stiffness fitted beside the damping
reaches k 0.4986, c 0.01996, beta/gamma 0.6/0.4, mu 1.50, chi2/dof 0.97. Such a candidate is admitted as the
term that frees the hysteresis from the face, so a set holding it is kept only where its own fit is interior,
no face of the hysteresis' range active (:func:`off_face`): the isolator's pair is (chi2/dof 0.97, law p
0.80/0.73), while on the real-data microwire (a Jiles-Atherton core, outside the library) the lead, stiffness
on x, was held on beta = |gamma| (34-38 % of the excess, chi2/dof 837-2292 under the "early" and "half
harmonics" variants) and every set beside it stayed there (the triple with Coulomb friction and inertia on x
named at chi2/dof 391 without the check); review 38's Jiles-Atherton core (d3, d3ar, lead play on
beta = |gamma|) likewise. On the MR damper's 0.5 A level (lead 12 %) the check refuses the Dahl friction on x
that moved the hysteresis from mu = 1 to beta = |gamma|, and with it the triples built on it: the rule costs
9 s of CPU there (21 -> 30 s); with that set kept and its 12 triples fitted it cost 51 s.

**A member at its limit.** A two-term member (Dahl friction) refused beside its partner at its spring or
dry-friction limit, or with its level not told from its null (a Dahl near its spring limit: its friction
level runs off with a se to match), stands for the simpler term its fit leans to
(:func:`.fitting.nearer_limit`: the spring where ``sigma A / Fc`` is below 1, dry friction above), and that
pair is fitted in its place, at the same place, and judged by the same rules (:func:`_in_place`; only for
that refusal of that member, so a Dahl refused for a small share does not bring a spring in). Review 43's
Kelvin element on x (d2: stiffness 0.03 and viscous damping 0.0002 s on x, resonant G with a delay): the
lead, Dahl friction on x, took the spring (sigma 0.0299) beside the damping and was refused for its null;
the spring beside the damping was never fitted and the verdict was "unexplained".

**A partner refused alone.** A member's share is what it removes of the excess its partner alone leaves
above the degrees of freedom. Where that partner alone was refused (its law failed, or its value left its
range) its cost explains nothing: a single value bent to the misfit can fall below the dof (review 43's
d2fw, viscous damping on x alone at 2524 over 2536 dof while a spring on x was missing, its law p 6e-18),
and the member beside it, a drop of 106 for one parameter, had a share of 0 and could never be named: the
pair was refused because the term that needed it fits too well when its law is ignored. There the excess
the partner leaves is counted as at least the chi-square's own spread ``sqrt(2 dof)``: the noise floor is
known to no better, so a cost below it is not an excess explained. The 10 % rule then asks the member to
move the cost by a tenth of that spread at least (7 on 2500 dof), still material against what a noise
floor can tell, while the member's F test (Bonferroni over the candidates) carries the significance; where
the partner alone leaves more than the spread the rule is unchanged.

The same rules run once more, from an earlier model, in :mod:`.revisit`: where a single term was named and
a later step's best candidate, removing most of what is left, fails its law (stiffness and viscous damping
on u through a G without delay were named viscous damping on x), sets that could replace the named term
are fitted from the model before it. Where a step's law-failed candidates stay unnamed, the verdict says
what this step did there (:func:`refusal_text`).

The rules read the experiments only through :class:`Rules` (the degrees of freedom, the nested F test, a
member's physical range, its law, the held-out cost, the separating experiment): :func:`pair_step` takes
either a set of experiments (one set: :func:`.run.diagnose`) or a :class:`Rules` of its own, as
:mod:`.across_pairs` gives one for several conditions at once (:func:`.across.diagnose_across`).

``ENABLED`` switches the path off (then a step whose candidates all fail their laws ends as before).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS, Distortion
from . import excess_share
from .fitting import at_a_limit, nearer_limit
from .select import (
    BOUNDARY_TERMS,
    LAW_ALPHA,
    MATERIAL_SHARE,
    PREFERRED_LAW_FLOOR,
    Alternative,
    FoldCache,
    HeldOut,
    Trial,
    _admissible,
    _separating,
    _tied,
    at_null,
    away_from_null,
    dof_of,
    element_law_test,
    f_test,
    held_out,
    memo_fit_with,
    siblings,
)

#: Whether a step whose candidates all failed their laws tries pairs of them (module docstring).
ENABLED = True
#: The best this many candidates (by cost) that passed their own tests are paired with each other (3 pair
#: fits); the best of them is also paired with every candidate that did not pass alone.
POOL = 3
#: Whether a step whose pairs all fail their laws tries the best pair with a third term (module docstring).
TRIPLES = True
#: The candidates that did not pass alone are paired with the lead (and tried as a third term) only where
#: the lead alone removes at least this share of the excess (module docstring, "Where it runs").
OTHERS_SHARE = 0.5


#: Why a member at its limit, or with its level not told from its null, is refused (after its label): the
#: refusals :func:`_in_place` answers with the simpler term.
AT_LIMIT = "sits at its spring or dry-friction limit, which the simpler term states"
NOT_AWAY = "'s value is not told from its null beside"


#: The faces of the hysteresis' admissible range (the core's ``Constraint`` names, ``fit.active``); a term's
#: own null (``"play=0"``) is not one of them.
SHAPE_FACES = frozenset({"beta=gamma", "mu=lower", "mu=upper"})

#: A lead whose fit stays on a face of :data:`SHAPE_FACES` with a reduced chi-square above this is held there
#: by a misfit it cannot draw alone: its share understates what a second term can free (module docstring,
#: "A lead held on a face").
HELD_CHI2 = 10.0


def _faces(fit: Any) -> list[str]:
    return sorted(SHAPE_FACES.intersection(getattr(fit, "active", ())))


def held_lead(rules: Any, fit: Any) -> bool:
    """Whether the lead's ``fit`` is held on a face of the hysteresis' range far from adequate
    (:data:`HELD_CHI2`): then the candidates that failed alone are fitted beside it whatever its share,
    kept only where their set leaves every face (:func:`off_face`; module docstring)."""
    cost = getattr(fit, "cost", math.nan)
    return bool(_faces(fit)) and math.isfinite(cost) and cost / max(rules.dof(fit), 1) > HELD_CHI2


def off_face(extra: set[str], sets: Sequence[PairTrial]) -> list[PairTrial]:
    """``sets`` with those holding a member of ``extra`` (candidates fitted only because the lead is held on
    a face, :func:`held_lead`) refused where their fit is not interior (any face of :data:`SHAPE_FACES`
    active): such a member was admitted as the term that frees the hysteresis from the face, and a set that
    leaves it held, there or on another face, holds no evidence for it (module docstring)."""
    out = []
    for p in sets:
        kept = _faces(p.fit) if p.fit is not None else []
        if p.refused or not kept or not extra & set(p.terms):
            out.append(p)
            continue
        on = ", ".join(k.replace("=", " = ") for k in kept)
        out.append(replace(p, refused=f"the hysteresis stays on a face of its range ({on})"))
    return out


class Rules:
    """What the pair rules ask of the experiments a set is tested on: here one set of experiments and
    :mod:`.select`'s functions (module docstring; :class:`.across_pairs.JointRules` for several conditions).
    ``per_set``: how many parameter sets one added term brings (1 here; the number of conditions across)."""

    per_set = 1
    #: The adequacy test's chi-square of a fit (adequacy_chi2.py), which a member's share is read on where
    #: the cost shows no excess (excess_share.py); None: such a share is 0.
    statistic: Optional[Callable[[Any], float]] = None

    def __init__(
        self,
        exps: Sequence[AugExperiment],
        substeps: int = 1,
        cache: Optional[FoldCache] = None,
        statistic: Optional[Callable[[Any], float]] = None,
    ) -> None:
        self.exps, self.substeps, self.cache, self.statistic = exps, substeps, cache, statistic

    def dof(self, fit: Any) -> int:
        return dof_of(self.exps, fit)

    def physical(self, fit: Any, term: str) -> bool:
        """In its physical range and not at its null value (the model without it)."""
        return _admissible(fit, term) and not at_null(fit, term)

    def at_limit(self, fit: Any, term: str) -> bool:
        """A two-term element (Dahl friction) at its spring or dry-friction limit at every experiment
        (:func:`.fitting.at_a_limit`): the simpler term says it with fewer parameters. A single Dahl fit there
        is refused (tried as that term); beside another member the joint refit can still drive it there
        (review 33: Dahl with fc 1.6 +- 0.55, its sigma the true spring, named with Coulomb friction)."""
        return at_a_limit(self.exps, fit, term)

    def away(self, fit: Any, term: str, level: float, s2: float) -> bool:
        return away_from_null(fit, term, level, s2)

    def limit_of(self, fit: Any, term: str) -> str:
        """The simpler term a two-term element's fit leans to (:func:`.fitting.nearer_limit`)."""
        return nearer_limit(self.exps, fit, term)

    def law(self, fit: Any, term: str) -> float:
        return element_law_test(self.exps, fit, term, self.substeps)

    def held_out(self, before: Any, after: Any) -> Optional[HeldOut]:
        return held_out(self.exps, before, after, self.substeps, self.cache)

    def separating(self, a: Any, b: Any) -> str:
        return _separating(self.exps, a, b, self.substeps)

    def fitter(self) -> Callable[[Any, str], Optional[Any]]:
        """The one-term fit a set's members are added by (a new memo of :func:`.select.memo_fit_with`)."""
        return memo_fit_with(self.exps, self.substeps)


def _rules(
    exps: Any,
    substeps: int = 1,
    cache: Optional[FoldCache] = None,
    statistic: Optional[Callable[[Any], float]] = None,
) -> Rules:
    return exps if isinstance(exps, Rules) else Rules(exps, substeps, cache, statistic)


@dataclass(frozen=True)
class PairTrial:
    """One pair of candidates fitted jointly on top of the step's model, with its tests."""

    terms: tuple[str, ...]
    cost: float
    improvement: float
    #: Each member's F-test p given the others, Bonferroni-adjusted over the step's candidates.
    member_p: tuple[float, ...]
    #: Each member's law p in the set's fit (empty: not run).
    law_p: tuple[float, ...] = ()
    held_out: Optional[HeldOut] = None
    #: Why it was not named ("" for the named pair; "not reached" when a better pair was named first).
    refused: str = ""
    fit: Optional[AugFit] = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        def n(v: float) -> Optional[float]:
            return v if math.isfinite(v) else None

        return {
            "terms": list(self.terms),
            "cost": n(self.cost),
            "improvement": n(self.improvement),
            "member_p_adjusted": [n(p) for p in self.member_p],
            "law_p_value": [n(p) for p in self.law_p],
            "held_out": None if self.held_out is None else self.held_out.to_dict(),
            "refused": self.refused,
        }


@dataclass(frozen=True)
class PairChoice:
    """The pair named at a step: ``trial`` is the step's chosen trial (its term the first member, its fit the
    pair's), ``terms`` both members, ``alternatives`` the rivals the data cannot tell from it."""

    trial: Trial
    terms: tuple[str, ...]
    alternatives: tuple[Alternative, ...]

    def unnamed(self, law_failed: Sequence[str]) -> list[str]:
        """The step's law-failed candidates less the pair's members (named: no stand-ins)."""
        return [t for t in law_failed if t not in self.terms]


def _as_trial(p: PairTrial) -> Trial:
    return Trial(p.terms[0], p.cost, p.improvement, math.nan, math.nan, math.nan, math.nan, True, fit=p.fit)


#: A model without one member: (its cost, its fit).
Without = dict[str, tuple[float, AugFit]]


def _member_tests(
    exps: Any,
    fit: AugFit,
    without: Without,
    level: float,
    n_cands: int,
    members: Sequence[str] = (),
    partner_refused: Collection[str] = (),
) -> tuple[tuple[float, ...], str]:
    """Each member's test given the others (rule 1 of the module docstring), ``without[m]`` the model of the
    others: (adjusted p's, why refused). ``partner_refused``: the members whose ``without`` model is a
    partner refused alone (its law, or its range): the excess it leaves is counted as at least the
    chi-square's own spread (module docstring, "A partner refused alone")."""
    r = _rules(exps)
    d1 = r.dof(fit)
    s2 = fit.cost / max(d1, 1)
    ps: list[float] = []
    why = ""
    for m, (c_other, f_other) in without.items():
        q = max(len(fit.params.terms) - len(f_other.params.terms), 1) * r.per_set
        _, p = f_test(c_other, fit.cost, d1, boundary=m in BOUNDARY_TERMS, q=q)
        padj = min(1.0, p * n_cands) if math.isfinite(p) else math.nan
        ps.append(padj)
        # Its share of the excess the others leave (what the next single step would ask of it).
        d_other = r.dof(f_other)
        floor = math.sqrt(2.0 * d_other) if m in partner_refused else 0.0
        read = None if r.statistic is None else (r.statistic(f_other), r.statistic(fit))
        share = excess_share.share(c_other, fit.cost, d_other, read, floor)  # the one convention
        given = " and ".join(_label(t) for t in (members or without) if t != m)
        if why:
            continue
        who = _label(m)
        if not r.physical(fit, m):
            why = f"{who} came out at its null or outside its physical range"
        elif r.at_limit(fit, m):
            why = f"{who} {AT_LIMIT}"
        elif not (math.isfinite(padj) and padj < level):
            why = f"{who} does not improve the fit significantly beside {given} (adjusted p = {padj:.2g})"
        elif share < MATERIAL_SHARE:
            why = (
                f"{who} removes only {100 * share:.2g} % of the misfit that {given} leaves (a named "
                f"term must remove at least {100 * MATERIAL_SHARE:g} %)"
            )
        elif not r.away(fit, m, level, s2):
            why = f"{who}{NOT_AWAY} {given}"
    return tuple(ps), why


def _joint(exps: Any, current: AugFit, f: AugFit, k: int, n_cands: int, level: float) -> str:
    """The set's joint F test against the step's model, Bonferroni over every set of ``k`` candidates."""
    r = _rules(exps)
    q = max(len(f.params.terms) - len(current.params.terms), 1) * r.per_set
    _, p = f_test(current.cost, f.cost, r.dof(f), q=q)
    return (
        ""
        if math.isfinite(p) and min(1.0, p * max(math.comb(n_cands, k), 1)) < level
        else f"the set together does not improve the fit significantly (joint p = {p:.2g})"
    )


def _no_fit(terms: tuple[str, ...]) -> PairTrial:
    return PairTrial(terms, math.nan, math.nan, tuple(math.nan for _ in terms), refused="no fit")


def _clash(t: str, terms: Sequence[str], fits: Sequence[AugFit]) -> bool:
    """One physics at two places, or one element's own parts."""
    return any(t in siblings(u) for u in terms) or any(t in f.params.terms for f in fits)


def fit_pairs(
    exps: Any,
    current: AugFit,
    pool: Sequence[Trial],
    others: Sequence[Trial],
    fit_term: Callable[[AugFit, str], Optional[AugFit]],
    level: float,
    n_cands: int,
    drive: Sequence[tuple[Trial, Trial]] = (),
    alone: Optional[Mapping[str, Trial]] = None,
) -> list[PairTrial]:
    """The pool's pairs, then the best with every other candidate (a second term too small to pass alone
    while the first absorbs part of it: the README plant's play beside its viscous damping), then the
    ``drive`` pairs (:func:`drive_pairs`) not among them, fitted and given rule 1 (module docstring). A
    member refused at its limit is replaced by that limit (:func:`_in_place`; ``alone``: every candidate's
    trial alone, by term)."""
    pairs = [(a, b) for i, a in enumerate(pool) for b in pool[i + 1 :]]
    pairs += [(pool[0], b) for b in others] if pool else []
    seen = {frozenset((a.term, b.term)) for a, b in pairs}
    pairs += [(a, b) for a, b in drive if frozenset((a.term, b.term)) not in seen]
    out: list[PairTrial] = []
    for a, b in pairs:
        assert a.fit is not None and b.fit is not None
        if _clash(b.term, [a.term], [a.fit]) or a.term in b.fit.params.terms:
            continue
        f = fit_term(a.fit, b.term)  # the second added to the better one's fit, by the one-term fit
        if f is None or not math.isfinite(f.cost):
            out.append(_no_fit((a.term, b.term)))
            continue
        out.append(_pair_trial(exps, current, a, b, f, level, n_cands, alone or {}))
        simpler = _in_place(exps, out[-1], a, b, alone or {})
        if simpler is not None and frozenset(t.term for t in simpler) not in seen:
            keep, limit = simpler
            seen.add(frozenset((keep.term, limit.term)))
            assert keep.fit is not None
            g = fit_term(keep.fit, limit.term)  # the simpler term in the refused member's place
            if g is None or not math.isfinite(g.cost):
                out.append(_no_fit((keep.term, limit.term)))
            else:
                out.append(_pair_trial(exps, current, keep, limit, g, level, n_cands, alone or {}))
    return out


def _refused_alone(exps: Any, tr: Trial, alone: Mapping[str, Trial]) -> bool:
    """Whether a candidate fitted alone was refused by its law or its range (its cost explains nothing)."""
    tr = alone.get(tr.term, tr)  # the step's trial, its law run (the order's copy may predate it)
    return not tr.law_holds or (tr.fit is not None and not _rules(exps).physical(tr.fit, tr.term))


def _pair_trial(
    exps: Any,
    current: AugFit,
    a: Trial,
    b: Trial,
    f: AugFit,
    level: float,
    n_cands: int,
    alone: Mapping[str, Trial],
) -> PairTrial:
    """The pair ``a``, ``b`` fitted as ``f`` with rule 1 (each member given the other alone, then jointly)."""
    assert a.fit is not None and b.fit is not None
    without = {a.term: (b.cost, b.fit), b.term: (a.cost, a.fit)}
    refused = [m.term for m, o in ((a, b), (b, a)) if _refused_alone(exps, o, alone)]
    ps, why = _member_tests(exps, f, without, level, n_cands, partner_refused=refused)
    why = why or _joint(exps, current, f, 2, n_cands, level)
    return PairTrial((a.term, b.term), f.cost, current.cost - f.cost, ps, refused=why, fit=f)


def _in_place(
    exps: Any, p: PairTrial, a: Trial, b: Trial, alone: Mapping[str, Trial]
) -> Optional[tuple[Trial, Trial]]:
    """(the kept member, the simpler term's trial alone) where ``p`` was refused for a two-term member (Dahl
    friction) at its limit or with its level not told from its null, and the simpler term its fit leans to
    (:func:`.fitting.nearer_limit`) was fitted alone and does not clash with the kept member; else None
    (module docstring, "A member at its limit")."""
    if not p.refused or p.fit is None:
        return None
    r = _rules(exps)
    for m, keep in ((a, b), (b, a)):
        why = p.refused.removeprefix(_label(m.term))
        if why == p.refused or not (why.startswith(NOT_AWAY) or why == f" {AT_LIMIT}"):
            continue  # refused for another reason, or for the other member
        limit_of = getattr(r, "limit_of", None)  # one set of experiments only (not across.py's rules)
        limit = alone.get(limit_of(p.fit, m.term)) if limit_of is not None else None
        if limit is None or limit.fit is None or not math.isfinite(limit.cost):
            continue
        assert keep.fit is not None
        if _clash(limit.term, [keep.term], [keep.fit]) or keep.term in limit.fit.params.terms:
            continue
        return keep, limit
    return None


def fit_triples(
    exps: Any,
    current: AugFit,
    base: PairTrial,
    cands: Sequence[Trial],
    pair_fits: dict[frozenset[str], PairTrial],
    fit_term: Callable[[AugFit, str], Optional[AugFit]],
    level: float,
    n_cands: int,
) -> list[PairTrial]:
    """``base`` (the best pair that passed rule 1 but whose law failed) with each other candidate: a third
    large term beside it (the README's sensor lag beside viscous damping and play). The third's own test
    given the pair runs first; the other two members' models are then fitted as pairs where not yet."""
    assert base.fit is not None
    alone = {tr.term: tr for tr in cands}
    out: list[PairTrial] = []
    for c in cands:
        assert c.fit is not None
        if c.term in base.terms or _clash(c.term, base.terms, [base.fit]):
            continue
        terms = (*base.terms, c.term)
        f = fit_term(base.fit, c.term)
        if f is None or not math.isfinite(f.cost):
            out.append(_no_fit(terms))
            continue
        _, why = _member_tests(exps, f, {c.term: (base.cost, base.fit)}, level, n_cands, terms)
        without: Without = {}
        for m in base.terms if not why else ():
            rest = [t for t in base.terms if t != m][0]
            got = pair_fits.get(frozenset({rest, c.term}))
            first = alone[rest].fit if rest in alone else None
            sub = got.fit if got is not None else None if first is None else fit_term(first, c.term)
            if sub is None or not math.isfinite(sub.cost):
                why = f"{m}: no fit without it"
                break
            without[m] = (sub.cost, sub)
        ps: tuple[float, ...] = tuple(math.nan for _ in terms)
        if not why:
            without[c.term] = (base.cost, base.fit)
            ps, why = _member_tests(exps, f, without, level, n_cands)
            why = why or _joint(exps, current, f, 3, n_cands, level)
        out.append(PairTrial(terms, f.cost, current.cost - f.cost, ps, refused=why, fit=f))
    return out


def _law(exps: Any, p: PairTrial, substeps: int) -> PairTrial:
    assert p.fit is not None
    r = _rules(exps, substeps)
    laws = tuple(r.law(p.fit, t) for t in p.terms)
    bad = [f"{_label(t)} (p = {v:.2g})" for t, v in zip(p.terms, laws) if math.isfinite(v) and v < LAW_ALPHA]
    return replace(
        p,
        law_p=laws,
        refused="law fails (its value differs between experiments): " + ", ".join(bad) if bad else "",
    )


def _label(term: str) -> str:
    """A term as the user reads it (its registry label and place)."""
    return TERMS[term].place_label() if term in TERMS else term


def _least(values: Sequence[float]) -> float:
    return min((v for v in values if math.isfinite(v)), default=math.nan)


def law_holds(p: PairTrial) -> bool:
    return not any(math.isfinite(v) and v < LAW_ALPHA for v in p.law_p)


def _rivals(
    exps: Any,
    chosen: PairTrial,
    tested: Sequence[PairTrial],
    singles: Sequence[Trial],
    substeps: int,
) -> list[Alternative]:
    """Rule of the alternatives (module docstring): each rival pair's differing members, and single terms
    whose law held, tied with the chosen pair, each against the member it would replace."""
    assert chosen.fit is not None
    r0 = _rules(exps, substeps)
    ct = _as_trial(chosen)
    dof = r0.dof(chosen.fit)
    out: list[Alternative] = []
    for r in tested:
        if r is chosen or r.fit is None or not math.isfinite(r.cost):
            continue
        by_law = (
            not law_holds(r) and r.cost <= chosen.cost and _least(r.law_p) >= PREFERRED_LAW_FLOOR
        )  # passed over for its law only, while it fits at least as well (select.preferred_by_fit)
        if not (
            by_law or (law_holds(r) and not r.refused.startswith("law") and _tied(ct, _as_trial(r), dof))
        ):
            continue
        sep = r0.separating(chosen.fit, r.fit)
        new = [t for t in r.terms if t not in chosen.terms]
        old = [t for t in chosen.terms if t not in r.terms]
        for t, rival in zip(old, new):
            out.append(Alternative(t, rival, math.nan, sep, _least(r.law_p) if by_law else math.nan))
    for s in singles:
        if s.fit is None or s.term in chosen.terms or not s.law_holds or not math.isfinite(s.law_p_value):
            continue
        if _tied(ct, s, dof):
            sep = r0.separating(chosen.fit, s.fit)
            out.append(Alternative(chosen.terms[0], s.term, math.nan, sep))
    return out


def _pick(
    exps: Any,
    current: AugFit,
    ranked: Sequence[PairTrial],
    done: dict[tuple[str, ...], PairTrial],
    substeps: int,
    held_out_test: bool,
    cache: Optional[FoldCache],
) -> Optional[PairTrial]:
    """The first of ``ranked`` (those that passed rule 1, by cost) whose laws hold and whose held-out cost is
    lower (rules 2 and 3); ``done`` records every one's tests."""
    r = _rules(exps, substeps, cache)
    for p in ranked:
        p = _law(r, p, substeps)
        done[p.terms] = p
        if not law_holds(p):
            continue
        assert p.fit is not None
        ho = r.held_out(current, p.fit) if held_out_test else None
        done[p.terms] = replace(p, held_out=ho)
        if ho is not None and not ho.improves:
            done[p.terms] = replace(p, held_out=ho, refused="it predicts held-out experiments no better")
            continue
        return done[p.terms]
    return None


def drive_pairs(order: Sequence[Trial], refused: Sequence[str]) -> list[tuple[Trial, Trial]]:
    """The input's own term (``distortion``, a candidate only where the inputs carry harmonics above their
    noise) beside every other candidate that passed its own test, the better of the two first.

    The drive's harmonics are a fact of the data, not one more physics: whatever the device adds, the model
    needs them beside it, so the pair of a physical term and the drive's term is tried whatever their ranks.
    Review 35's cu_h3fo (viscous damping on u, a 3 % third harmonic, first-order G): the drive's term ranked
    sixth and the viscous damping eighth of the candidates that passed alone, the pool of the best three
    held neither, and the step ended "unexplained".
    """
    ok = [tr for tr in order if tr.fit is not None and tr.term not in refused and math.isfinite(tr.cost)]
    own = next((tr for tr in ok if tr.term == Distortion.kind), None)
    if own is None:
        return []
    return [(own, tr) if own.cost <= tr.cost else (tr, own) for tr in ok if tr is not own]


def pair_step(
    exps: Any,
    current: Any,
    order: Sequence[Trial],
    tested: Sequence[Trial],
    refused: Sequence[str],
    fit_term: Callable[[Any, str], Optional[Any]],
    substeps: int,
    level: float,
    n_cands: int,
    held_out_test: bool = True,
    cache: Optional[FoldCache] = None,
    pool_size: int = POOL,
    others_share: Optional[float] = None,
    statistic: Optional[Callable[[Any], float]] = None,
) -> tuple[Optional[PairChoice], tuple[PairTrial, ...]]:
    """The pair (or triple) named at a step whose candidates (``order``: those that passed their own tests,
    best first) all failed their laws, or None; with every set tried (module docstring). The best
    ``pool_size`` of ``order`` are paired with each other (the revisit pairs more: revisit.py); the
    candidates of ``tested`` that did not pass alone only where the lead's share is ``others_share``
    (:data:`OTHERS_SHARE` when None) or more. ``exps``: the experiments, or the :class:`Rules` the sets
    are tested by (across_pairs.py). ``statistic``: :attr:`Rules.statistic`."""
    exps = _rules(exps, substeps, cache, statistic)
    pool = [tr for tr in order if tr.fit is not None and tr.term not in refused][:pool_size]
    passed = {tr.term for tr in order}
    others = [tr for tr in tested if tr.term not in passed and tr.fit is not None and math.isfinite(tr.cost)]
    least = OTHERS_SHARE if others_share is None else others_share
    held = bool(pool) and pool[0].share < least and held_lead(exps, pool[0].fit)
    if not (pool and (pool[0].share >= least or held)):  # a lead too small to hide a second term (docstring)
        others = []
    extra = {tr.term for tr in others} if held else set()
    alone = {tr.term: tr for tr in tested if tr.fit is not None}
    tried = fit_pairs(
        exps, current, pool, others, fit_term, level, n_cands, drive_pairs(order, refused), alone
    )
    tried = off_face(extra, tried) if extra else tried
    ranked = sorted((p for p in tried if not p.refused), key=lambda p: p.cost)
    done: dict[tuple[str, ...], PairTrial] = {p.terms: p for p in tried}
    chosen = _pick(exps, current, ranked, done, substeps, held_out_test, cache)
    if chosen is None and TRIPLES and ranked:  # the best pair's laws failed: a third large term beside it
        fits = {frozenset(p.terms): p for p in tried if p.fit is not None}
        tri = fit_triples(exps, current, ranked[0], [*pool, *others], fits, fit_term, level, n_cands)
        tri = off_face(extra, tri) if extra else tri
        done.update({p.terms: p for p in tri})
        ranked = sorted((p for p in tri if not p.refused), key=lambda p: p.cost)
        chosen = _pick(exps, current, ranked, done, substeps, held_out_test, cache)
    if chosen is None or chosen.fit is None:
        return None, tuple(done.values())
    # Rivals among the sets that passed rule 1: their laws (run for those a tie could make alternatives).
    dof = exps.dof(chosen.fit)
    for p in ranked:
        if p.terms != chosen.terms and not p.law_p and _tied(_as_trial(chosen), _as_trial(p), dof):
            done[p.terms] = _law(exps, p, substeps)
    rivals = [done[p.terms] for p in ranked if done[p.terms].law_p]
    alts = _rivals(exps, chosen, rivals, tested, substeps)
    pmin, lmin = _least(chosen.member_p), _least(chosen.law_p)
    trial = Trial(chosen.terms[0], chosen.cost, chosen.improvement, math.nan, pmin, pmin, math.nan, True,
                  chosen.held_out, chosen.fit, lmin)  # fmt: skip
    return PairChoice(trial, chosen.terms, tuple(alts)), tuple(done.values())


def text(steps: Sequence[Any]) -> str:
    """The verdict's clause for a step that named a pair: both were named together because neither fits
    alone with one value for every experiment."""
    named = [st.pair for st in steps if getattr(st, "pair", ()) and not _by_rival(st)]
    if not named:
        return ""
    what = "; ".join(" with ".join(TERMS[t].place_label() for t in p) for p in named)
    return (
        f"; named together: {what} (none alone fits with one value for every experiment; jointly each does, "
        "and each is significant given the others)"
    )


def _by_rival(st: Any) -> bool:
    """A set named in place of a single term whose law held (rival_revisit.py: said there, not here)."""
    return any(getattr(p, "by_rival", False) and p.refused == "" for p in getattr(st, "pairs", ()))


def refusal_text(steps: Sequence[Any]) -> str:
    """What the pair step did at the steps where candidates' laws failed: the set it named there, or how
    many sets it fitted and why the best was refused, or that it did not run (a step that names a single
    term never reaches it)."""
    if not ENABLED:
        return "the pair step is switched off"
    out = []
    for k, st in enumerate(steps, 1):
        tried = [p for p in getattr(st, "pairs", ()) if isinstance(p, PairTrial)]
        if not st.law_failed:
            continue
        if getattr(st, "pair", ()):
            who = " with ".join(TERMS[t].place_label() for t in st.pair)
            out.append(f"at step {k} the pair step named {who}, these not among them")
        elif tried:
            fitted = sorted((p for p in tried if math.isfinite(p.cost)), key=lambda p: p.cost)
            best = fitted[0] if fitted else tried[0]
            who = " with ".join(TERMS[t].place_label() for t in best.terms)
            out.append(
                f"at step {k} the pair step fitted {len(fitted)} sets and named none; the best, {who}: "
                f"{best.refused or 'not reached'}"
            )
        elif hasattr(st, "chosen") and st.chosen is None and not getattr(st, "targeted", False):
            # it ran and had no set to fit (OTHERS_SHARE)
            out.append(f"at step {k} the pair step fitted no set: {_none_to_fit(st)}")
        else:
            out.append(
                f"at step {k} the pair step did not run: it runs only where a step names no single term"
            )
    return "; ".join(out)


def _none_to_fit(st: Any) -> str:
    """Why a step that named nothing had no set to fit: the candidates that passed alone give no pair (one
    only, or one physics at two places), and the lead removes under :data:`OTHERS_SHARE` of the excess (the
    others are not fitted beside it)."""
    # By share, not cost: the joint steps' trials (across.py's JointTrial) carry no one cost.
    trials = [t for t in getattr(st, "trials", ()) if getattr(t, "passed", False) and math.isfinite(t.share)]
    passed = sorted(trials, key=lambda t: -t.share)
    if not passed:
        return "no candidate passed its own tests"
    label = TERMS[passed[0].term].place_label()
    many = "the candidates that passed alone give no pair (one physics at two places), and the lead,"
    who = f"only {label} passed alone, and it" if len(passed) == 1 else f"{many} {label},"
    return (
        f"{who} removes {100 * passed[0].share:.0f} % of the excess, under the {100 * OTHERS_SHARE:.0f} % "
        "beside which the candidates that failed alone are fitted (a term its misfit could hide)"
    )


__all__ = [
    "Rules",
    "refusal_text",
    "ENABLED",
    "POOL",
    "TRIPLES",
    "fit_triples",
    "PairTrial",
    "PairChoice",
    "pair_step",
    "fit_pairs",
    "law_holds",
    "text",
]

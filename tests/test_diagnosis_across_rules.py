"""``diagnose_across`` says what ``diagnose`` says: the single-group rules applied to the joint selection
(diagnosis/across.py, diagnosis/across_verdict.py; issue 18: the house says the same thing whichever path the
user takes).

The end-to-end cases are the main bench's (benches/generator.py: its own closed-form G and exact per-step
Dahl branch or sum of stops, not the library's simulator), given as two conditions: the same records twice,
so the joint selection sees what the single-group selection sees, and each rule is the one that decides.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_verdict as V
from bouc_wen_id.diagnosis import gate
from bouc_wen_id.diagnosis.across import TermAcross

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

DAHL_X = T.Dahl.at(T.Place.X)


def _twice(effect: str, size: float, seed: int, cands: list[str]) -> Any:
    case = gen.make_case("outside", effect, "", size, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across([case.recordings, case.recordings], [0.0, 1.0], candidates=cands)
        d = bw.diagnose(case.recordings, candidates=cands)
    return a, d


def test_a_term_needed_only_beside_dahl_is_not_named_across_and_the_verdict_says_why() -> None:
    """Dahl's exponent 2 at 30x (seed 61010, the case of tests/test_beside_dahl.py): before, the joint
    selection named Dahl friction and then pinching (its F test, law and held-out passing beside Dahl),
    though pinching's combined F test on the plain models gave p = 0.98. Now it is refused through
    beside.only_beside, recorded in the step and said in the verdict, as diagnose does on the same records."""
    pinch = T.Pinching.kind
    a, d = _twice("dahl_n2", 30.0, 61010, [DAHL_X.kind, pinch])
    assert pinch not in a.named, a.verdict
    assert a.named == (DAHL_X.kind, DAHL_X.companion), a.verdict
    first = {t.term: t for t in a.steps[0].trials}
    assert not first[pinch].p_value < 0.05  # no effect of its own on the plain models
    assert a.steps[1].chosen is None and a.steps[1].beside == (pinch,)
    later = {t.term: t for t in a.steps[1].trials}
    assert later[pinch].passed  # its in-sample tests passed beside the element: the rule refused it
    assert f"not named: {T.Pinching.place_label()} beside {DAHL_X.place_label()}" in a.verdict
    # diagnose, on the same records and candidates, refuses it too and says the same clause.
    assert pinch not in d.named_terms and d.steps[1].beside == (pinch,), d.verdict
    assert f"not named: {T.Pinching.place_label()} beside {DAHL_X.place_label()}" in d.verdict
    assert a.status == d.status, (a.verdict, d.verdict)
    assert "beside" in a.to_dict()["steps"][1] and "beside" in d.to_dict()["steps"][1]


def test_a_sum_of_stops_is_not_named_dahl_across_its_branch_shape_fails() -> None:
    """An Iwan loop (a sum of stops on x, seed 59003 at 30x): its values are one per experiment (the plain
    law test passed, p = 0.11, and the joint selection named Dahl friction), but its branch is not Dahl's.
    The element's whole claim (element_law_test: law and branch shape) refuses it, as in diagnose."""
    a, d = _twice("iwan", 30.0, 59003, [DAHL_X.kind])
    assert DAHL_X.kind not in a.named and not a.partial, a.verdict
    assert a.steps[0].law_failed == (DAHL_X.kind,)
    law_p = {t.term: t.law_p_value for t in a.steps[0].trials}[DAHL_X.kind]
    assert law_p < 0.01
    assert "a branch shape not its own" in a.verdict and "a branch shape not its own" in d.verdict
    assert DAHL_X.kind not in d.named_terms


def _fit(cost: float, terms: tuple[str, ...]) -> Any:
    return SimpleNamespace(cost=cost, params=SimpleNamespace(terms=terms, gains=(1.0, 1.0)))


def _groups(plain: float, final: float, terms: tuple[str, ...]) -> list[Any]:
    sx = [SimpleNamespace(ybar=np.zeros(256)) for _ in range(2)]
    return [
        SimpleNamespace(sx=sx, plain=_fit(plain, ()), current=_fit(final, terms), noise_dof=10**6)
        for _ in range(2)
    ]


def _term(kind: str, values: tuple[float, float]) -> TermAcross:
    return TermAcross(
        kind, T.TERMS[kind].place_label(), "c", "", values, (0.1, 0.1), (True, True), (0.0, 0.0), (), None
    )


def test_the_joint_structure_is_explained_only_when_it_passes_and_named_only_when_it_removes_most() -> None:
    """classify's rule, summed over the conditions: a final structure at the noise floor everywhere is
    "explained"; one that still fails but removes most of the excess "partly explained"; one that removes
    little leaves the structure unexplained and its terms tested, not named."""
    visc = _term(T.Viscous.kind, (0.5, 0.7))
    dof = 2 * 256 - (3 + 1 + 4)
    at_floor = _groups(5000.0, float(dof), (visc.term,))
    assert V.judged(at_floor, [visc], 0.05) == ("explained", [visc], [])
    excess = 5000.0 - (2 * 256 - (3 + 0 + 4))  # the plain model's, per condition
    most = _groups(5000.0, 5000.0 - 0.7 * excess, (visc.term,))
    assert V.judged(most, [visc], 0.05) == ("partly explained", [visc], [])
    little = _groups(5000.0, 5000.0 - 0.2 * excess, (visc.term,))
    status, named, partial = V.judged(little, [visc], 0.05)
    assert (status, named, partial) == ("unexplained", [], [visc])
    assert math.isclose(V.explained_fraction(little), 0.2, rel_tol=1e-9)
    head = V.head(status, partial, 2, V.explained_fraction(little))
    assert "unexplained structure remains" in head and "20 %" in head and visc.label in head


def test_a_non_physical_value_where_the_term_is_present_is_not_named() -> None:
    """run._judged's rule: a negative damping at a condition where the term is present stands in for physics
    placed elsewhere; it is reported as not physical, and the structure is at most partly explained."""
    visc = _term(T.Viscous.kind, (0.5, -0.2))
    off = _term(T.Offset.kind, (0.1, -0.1))  # an offset of either sign is physical
    dof = 2 * 256 - (3 + 2 + 4)
    g = _groups(5000.0, float(dof), (visc.term, off.term))
    status, named, partial = V.judged(g, [visc, off], 0.05)
    assert status == "partly explained" and named == [off] and partial == [visc]
    text = V.unphysical(partial)
    assert [t.term for t in text] == [visc.term] and text[0].value == -0.2
    # Absent where the value is negative: no claim is made there, so nothing unphysical is named.
    absent = TermAcross(
        visc.term, visc.label, "c", "", (0.5, -0.2), (0.1, 0.1), (True, False), (0.0, 1.0), (), None
    )
    assert V.unphysical([absent]) == []


def _joint(term: str, imp: tuple[float, float], cost: float) -> Any:
    fits = tuple(_fit(cost, (term,)) for _ in imp)
    return SimpleNamespace(term=term, improvements=imp, fits=fits, passed=True)


def test_a_rival_within_the_uncertainty_of_the_chosen_improvement_is_near_tied() -> None:
    """select._tied's rule on the sums: a rival 17 % short of the chosen term's summed improvement (outside
    the 10 % rule) is a near-tied reading when the difference is within 2 sd of the improvement, ``sd = 2
    sqrt(Delta C s2)``, s2 the chosen structure's pooled chi2/dof: at s2 = 4 it is (277 >= 200), at the
    noise floor it is not (139 < 200)."""
    g = _groups(5000.0, 5000.0, (T.Viscous.kind,))
    dof = 2 * 256 - (3 + 1 + 4)
    for s2, tie in ((4.0, True), (1.0, False)):
        chosen = _joint(T.Viscous.kind, (600.0, 600.0), s2 * dof)
        rival = _joint(T.Offset.kind, (500.0, 500.0), s2 * dof + 100.0)
        assert V.tied(g, chosen, rival) is tie
    # A rival whose fit failed at some condition is never a reading of the same misfit.
    broken = SimpleNamespace(term="offset", improvements=(600.0, 600.0), fits=(None, None), passed=False)
    assert not V.tied(g, _joint(T.Viscous.kind, (600.0, 600.0), 4.0 * dof), broken)


def _plain_at(p: float, noise_dof: int = 10**6) -> float:
    """The plain model's cost whose adequacy p-value is ``p`` (two conditions of 256 points, no term)."""
    from bouc_wen_id.diagnosis.locate import adequacy_p
    from scipy.optimize import brentq  # type: ignore[import-untyped]

    dof = 2 * 256 - (3 + 0 + 4)
    return float(brentq(lambda c: adequacy_p(c, dof, noise_dof) - p, 0.5 * dof, 3.0 * dof, xtol=1e-9))


def test_the_plain_model_is_judged_across_by_diagnose_s_gate_at_half_alpha() -> None:
    """diagnose accepts the plain model at alpha / 2 (the other half is the targeted step's); the joint path
    tested it at alpha and called "unexplained" a plain model diagnose calls "adequate" (p in [alpha/2,
    alpha)). Both paths now call gate.plain_passes; below alpha / 2 both refuse it."""
    for p, want in ((0.035, "adequate"), (0.02, "unexplained"), (0.3, "adequate")):
        cost = _plain_at(p)
        g = _groups(cost, cost, ())
        assert V.judged(g, [], 0.05, ())[0] == want, p
        assert gate.plain_passes(p, 0.05) is (want == "adequate")


def test_a_law_failed_candidate_keeps_the_plain_model_from_adequate_across() -> None:
    """run._diagnose_set's rule (gate.plain_adequate): a candidate whose tests passed but whose law failed
    is structure the plain model leaves and no term explains, even when the global test accepts the plain
    model."""
    cost = _plain_at(0.3)
    g = _groups(cost, cost, ())
    failed = SimpleNamespace(trials=(), chosen=None, law_failed=(DAHL_X.kind,), beside=(), targeted=False)
    clean = SimpleNamespace(trials=(), chosen=None, law_failed=(), beside=(), targeted=False)
    assert V.judged(g, [], 0.05, [clean])[0] == "adequate"
    assert V.judged(g, [], 0.05, [clean, failed])[0] == "unexplained"


def test_a_plain_p_between_half_alpha_and_alpha_gives_one_status_on_both_paths() -> None:
    """The reviewer's case (tests/test_power_resolution.py's own NumPy integrator of a delayed two-pole G,
    noise seed 7): the plain model's p lies in [alpha/2, alpha); diagnose says "adequate", and so does
    diagnose_across on the same records twice, with diagnose's adequate head."""
    tests = str(Path(__file__).resolve().parent)
    sys.path.insert(0, tests)
    pr: Any = importlib.import_module("test_power_resolution")
    y, a, om = pr._outputs(0.0)
    recs = pr._records(y, a, om, 7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recs, candidates=[T.Offset.kind])
        x = bw.diagnose_across([recs, recs], [0.0, 1.0], candidates=[T.Offset.kind])
    assert 0.025 <= d.plain.p_value < 0.05, d.plain.p_value
    assert d.status == x.status == "adequate", (d.verdict, x.verdict)
    assert gate.ADEQUATE in d.verdict and gate.ADEQUATE in x.verdict


def test_an_unexplained_head_lists_only_the_physical_tested_terms() -> None:
    """run._judged leaves a non-physical term out of "tested terms ... leave structure the library does not
    model" (it is said in its own "not physical" clause): a negative damping whose structure passes is not a
    term that leaves structure; the physical one that removes little still is."""
    visc = _term(T.Viscous.kind, (-0.5, -0.7))
    dof = 2 * 256 - (3 + 1 + 4)
    g = _groups(5000.0, float(dof), (visc.term,))
    status, named, partial = V.judged(g, [visc], 0.05)
    assert (status, named, partial) == ("unexplained", [], [visc])
    head = V.head(status, partial, 2, V.explained_fraction(g))
    assert "unexplained structure remains" in head and "tested terms" not in head, head
    assert [t.term for t in V.unphysical(partial)] == [visc.term]  # said by clauses' "not physical"
    off = _term(T.Offset.kind, (0.1, 0.2))
    head = V.head("unexplained", [visc, off], 2, 0.2)
    assert f"tested terms {off.label} remove 20 %" in head and visc.label not in head, head


def test_no_candidates_says_nothing_was_tested() -> None:
    """candidates=[] on a structure the plain model misses (the Iwan loop at 30x, seed 59003): nothing was
    tested, and the verdict says so rather than "no candidate passes"."""
    a, d = _twice("iwan", 30.0, 59003, [])
    assert a.status == d.status == "unexplained", (a.verdict, d.verdict)
    assert "no candidate tested" in a.verdict and "no candidate passes" not in a.verdict, a.verdict

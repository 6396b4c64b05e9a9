"""The headline never says more than the details allow (diagnosis/readings.py; review 33 ``pi_u_10``).

A Prandtl-Ishlinskii loop on u was headlined "explained by: viscous damping across the hysteretic element
(on x) c = ..." while only a detail clause said the viscous value did not refuse a rate-independent loop's
1/omega law. The rate caveat fires on any design whose frequencies are too close to tell the two laws apart:
here the library's own viscous damping on u, 1 % noise, recorded at two frequencies 11 % apart (and, as a
control, a factor 4 apart, where the values refuse the rival). A first-order G, not the bench's.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import caveats, law_chance, masing, rate_rival, readings, revisit
from bouc_wen_id.diagnosis.result import NamedTerm
from bouc_wen_id.diagnosis.select import Alternative
from bouc_wen_id.diagnosis.verdict_text import clauses, details, headline

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("diagnosis")

TWO_PI = 2.0 * math.pi
CANDS = [T.Viscous.kind, T.Stiffness.kind]


def _recs(seed: int, freqs: tuple[float, ...], c: float) -> list[bw.Recording]:
    """Viscous damping on u (``c``), two amplitudes at each frequency (Hz), 1 % noise, a first-order G."""
    lin = bw.TransferFunction([1.0], [0.08, 1.0])
    om = np.repeat(TWO_PI * np.array(freqs), 2)
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om, np.tile([0.8, 2.0], len(freqs)) / g, settle_periods=8, periods=12, samples_per_period=64,
        substeps=8, noise_sd=0.01, seed=seed,
    )  # fmt: skip
    plant = bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5), terms=(T.Viscous(c),))
    return bw.simulate(plant, plan)


CLOSE = (0.45, 0.5)  # frequencies 11 % apart: the viscous and the rate-independent law differ by 11 %
WIDE = (0.2, 0.8)  # a factor 4: the values refuse the rival


def _diagnose(recs: list[bw.Recording]) -> bw.Diagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs, candidates=CANDS)


@pytest.fixture(scope="module")
def close() -> list[bw.Diagnosis]:
    return [_diagnose(_recs(s, CLOSE, c)) for s, c in ((1, 0.0015), (2, 0.002))]


def test_the_rate_caveat_is_in_the_headline_and_the_status_says_it(close: list[bw.Diagnosis]) -> None:
    """Viscous damping named from two close frequencies: the detail clause says it may be a rate-independent
    loop; now the headline says so too, and the printed status is not the bare "explained". The status
    value itself (what code reads) and the clauses after the headline are unchanged."""
    d = close[0]
    assert d.named_terms == (T.Viscous.kind,), d.verdict
    assert d.status == "explained", d.verdict
    assert any(rate_rival.RATE_MARK in c for c in d.details), d.verdict  # the detail, as before
    assert rate_rival.RATE_MARK in d.headline and readings.SEE in d.headline, d.headline
    assert d.headline.startswith("explained by: viscous damping on the measured input u c = ")
    assert [r.kind for r in d.readings if r.rival] == ["rate"], d.readings
    assert d.status_text == f"explained ({readings.NOT_ONLY})"
    js = d.to_dict()
    assert js["status"] == "explained" and js["readings"][0]["kind"] == "rate"
    assert js["headline"] == d.headline and d.summary().startswith(f"Diagnosis: {d.headline}")


def test_a_design_that_separates_the_laws_keeps_a_bare_headline() -> None:
    """The same damping over frequencies a factor 4 apart: the values refuse the rate-independent law, no
    caveat anywhere, and the headline and status stay unqualified."""
    d = _diagnose(_recs(1, WIDE, 0.0015))
    assert d.named_terms == (T.Viscous.kind,) and d.status == "explained", d.verdict
    assert rate_rival.RATE_MARK not in d.verdict
    assert not d.readings and d.status_text == "explained" and readings.DASH not in d.headline


def test_diagnose_across_says_the_rate_caveat_as_each_level_does(close: list[bw.Diagnosis]) -> None:
    """The two close-frequency recordings as two conditions: diagnose says the rate caveat at each level;
    diagnose_across named the same damping without it (its verdict never ran the test). Now it says it,
    naming the conditions, in its details and its headline."""
    groups = [_recs(s, CLOSE, c) for s, c in ((1, 0.0015), (2, 0.002))]
    assert all(rate_rival.RATE_MARK in d.headline for d in close)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, [0.0, 1.0], candidates=CANDS, per_condition=close)
    assert a.named == (T.Viscous.kind,) and a.status == "explained", a.verdict
    said = [c for c in details(a.verdict) if rate_rival.RATE_MARK in c]
    assert len(said) == 1 and "at conditions 0, 1" in said[0], a.verdict
    assert rate_rival.RATE_MARK in headline(a.verdict) and [r.kind for r in a.readings] == ["rate"]
    assert a.to_dict()["status_text"] == f"explained ({readings.NOT_ONLY})"


def test_each_qualifying_clause_puts_its_words_in_the_headline_and_the_others_do_not() -> None:
    """Verdicts assembled from the modules' own clauses: the rival readings (rate, Dahl's family, play's
    backlash, a spring on x's Masing loop, a revisit's set, a rival the experiments cannot tell apart) and
    a limit of the evidence (law untested) reach the headline; law_chance's clause (said only when nothing
    is named), a place that fits only non-physically, and a verdict naming nothing do not. The clauses
    after the headline are unchanged."""
    visc = NamedTerm(T.Viscous.kind, "c", 0.002, 0.0002, "s")
    dahl = NamedTerm(T.Dahl.kind, "fc", 0.05, 0.01, "")
    play = NamedTerm(T.Play.kind, "c", 0.05, 0.01, "")
    head = "explained by: X"
    cases = {
        "rate": (rate_rival.clause(T.Viscous.kind, 0.3, [1.0, 1.2]), [T.Viscous.kind], rate_rival.RATE_MARK),
        "family": (caveats.family_text([dahl]), [T.Dahl.kind], caveats.FAMILY_MARK),
        "play": (caveats.play_text([play]), [T.Play.kind], caveats.PLAY_MARK),
        "masing": (
            masing.masing_text([NamedTerm(T.StiffnessX.kind, "k", 0.1, 0.01, "")], True, None),
            [T.StiffnessX.kind],
            masing.MASING_MARK,
        ),
        "law_untested": (f"; {visc.label}: law untested (carried by only 1 of the 4 experiments)", [], ""),
    }
    for kind, (clause, named, mark) in cases.items():
        assert clause.startswith("; "), kind
        v = head + clause
        rs = readings.of_verdict(v, named or [T.Viscous.kind], [])
        assert [r.kind for r in rs] == [kind], (kind, rs)
        got = readings.headlined(v, rs)
        assert headline(got).startswith(head + readings.DASH) and mark in headline(got), got
        assert details(got) == details(v) and len(clauses(got)) == len(clauses(v))
        assert readings.status_text("explained", rs) == (
            "explained" if kind == "law_untested" else f"explained ({readings.NOT_ONLY})"
        )
    for by_rival in (False, True):  # a revisit's set: named in the term's place, or kept as its rival
        for outcome, want in (("named", "or " + T.Play.place_label()), ("alternative (x)", " together")):
            r = revisit.Revisit(T.Play.kind, (), (T.Viscous.kind, T.Play.kind), outcome, 1.0, 2.0, "wider")
            clause = revisit.text([SimpleNamespace(pairs=(replace(r, by_rival=by_rival),))])
            rs = readings.of_verdict(head + clause, [T.Play.kind], [])
            assert [x.kind for x in rs] == ["revisit"] and want in rs[0].words, (clause, rs)
    alt = Alternative(T.Viscous.kind, T.ViscousX.kind, math.nan, "wider band")
    rs = readings.of_verdict(head + caveats.alternatives_text([alt], [visc]), [T.Viscous.kind], [alt])
    assert [r.words for r in rs] == [f"or {T.ViscousX.place_label()}"]
    both = [T.Viscous.kind, T.ViscousX.kind]  # the rival named too: no other reading of the headline
    assert readings.of_verdict(head + caveats.alternatives_text([alt], [visc]), both, [alt]) == ()
    quiet = head + caveats.unphysical_places_text([], [visc]) + "; not named: viscous (p = 0.004)"
    assert readings.of_verdict(quiet, [T.Viscous.kind], []) == ()
    assert readings.of_verdict(head + caveats.family_text([dahl]), [], []) == ()  # nothing named
    assert law_chance.text([]) == ""  # its clause needs a step that named nothing: no headline to qualify


class _D:
    def __init__(self, verdict: str) -> None:
        self.verdict = verdict
        self.headline = headline(verdict)


def test_the_bench_scores_a_rate_caveated_name_honest_only_when_the_headline_carries_it() -> None:
    """benches/diagnosis.py: on a rate-independent outside row (pi_u, iwan, dahl_n2) a viscous damping with
    the rate caveat IN ITS HEADLINE is the family's honest reading ("fam"); the same caveat only in the
    details (main's verdict) reads as a confident name and scores wrong, as a bare name does; on other
    outside rows the caveat excuses nothing."""
    said = "explained by: viscous damping c = 0.0049 ± 0.0006"
    said += rate_rival.clause(T.ViscousX.kind, 0.3, [9.4, 38.0])
    carried = _D(readings.headlined(said, readings.of_verdict(said, [T.ViscousX.kind], [])))
    assert bench._family(carried, ["viscous"], "pi_u") and bench._family(carried, ["viscous"], "iwan")
    assert not bench._family(_D(said), ["viscous"], "pi_u")  # in the details only
    assert not bench._family(_D("explained by: viscous damping c = 0.0049"), ["viscous"], "pi_u")
    assert not bench._family(carried, ["viscous"], "rate_width")  # a rate-DEPENDENT loop: not its family
    assert not bench._family(carried, ["viscous", "stiffness"], "pi_u")  # another name beside it


def test_a_rival_the_details_refuse_by_its_law_is_no_reading() -> None:
    """Review of the merge (slack_10): "— or inertia on the measured input u" in the headline while the
    details listed it as "not named: ... its law fails ... stands in for physics outside the library"."""
    from bouc_wen_id import terms as T
    from bouc_wen_id.diagnosis import readings
    from bouc_wen_id.diagnosis.select import Alternative

    label = T.TERMS[T.Inertia.kind].place_label()
    alt = [Alternative(T.StiffnessX.kind, T.Inertia.kind, 0.99, "a second frequency")]
    verdict = "explained in part by: stiffness on x k = 0.05 (63 % of the excess)"
    kept = readings.of_verdict(verdict, [T.StiffnessX.kind], alt)
    assert any(label in r.words for r in kept)  # a plain rival is a reading
    refused = verdict + f"; not named: {label} (p = 0.001): each fits part of the misfit"
    assert not any(label in r.words for r in readings.of_verdict(refused, [T.StiffnessX.kind], alt))


def test_with_two_named_terms_the_headline_says_which_each_rival_replaces() -> None:
    """docs/real-data-diagnosis.md, MR damper 0.5 A: "explained in part by: viscous damping ..., asymmetry
    ... — or Dahl friction on the measured input u, or output offset, or a rate-independent loop outside the
    library" did not say that Dahl and the loop stand for the damping and the offset for the asymmetry. Now
    each rival says the named term it replaces, in the headline and in ``readings`` (JSON ``instead_of``);
    with one named term the words stay as they were (nothing to tell apart)."""
    visc = NamedTerm(T.Viscous.kind, "c", 3.3, 0.01, "N s/mm")
    asym = NamedTerm(T.Asymmetry.kind, "delta", -1e-4, 3e-6, "")
    alts = [
        Alternative(T.Viscous.kind, T.Dahl.kind, math.nan, "wider band"),
        Alternative(T.Asymmetry.kind, T.Offset.kind, math.nan, "an offset-free reference"),
    ]
    verdict = "explained in part by: X (85 % of the excess)" + caveats.alternatives_text(alts, [visc, asym])
    verdict += rate_rival.clause(T.Viscous.kind, 0.21, [1.6, 32.1])
    named = [T.Viscous.kind, T.Asymmetry.kind]
    rs = readings.of_verdict(verdict, named, alts)
    by_kind = {r.words.split(" instead of ")[0]: r for r in rs}
    dahl, offset = f"or {T.Dahl.place_label()}", f"or {T.Offset.place_label()}"
    rate = f"or {rate_rival.RATE_MARK} outside the library"
    assert set(by_kind) == {dahl, offset, rate}, rs
    assert by_kind[dahl].instead_of == (T.Viscous.kind,) and by_kind[rate].instead_of == (T.Viscous.kind,)
    assert by_kind[offset].instead_of == (T.Asymmetry.kind,)
    head = headline(readings.headlined(verdict, rs))
    assert f"{dahl} instead of {T.Viscous.label}" in head, head
    assert f"{offset} instead of {T.Asymmetry.label}" in head, head
    assert f"{rate} instead of {T.Viscous.label}" in head, head
    assert all(r.words in head for r in rs)  # the readings are the headline's own words
    js = [r.to_dict() for r in rs]
    assert {tuple(j["instead_of"]) for j in js} == {(T.Viscous.kind,), (T.Asymmetry.kind,)}
    one = readings.of_verdict(verdict, [T.Viscous.kind], alts[:1])  # one named term: no "instead of"
    assert one and all(" instead of " not in r.words for r in one) and one[0].instead_of == (T.Viscous.kind,)


def test_a_rival_said_for_two_named_terms_is_said_once_for_both() -> None:
    """The same rival found for each of two named terms on its own (output offset for asymmetry, and for
    sensor lag) is said once, "instead of A or of B": one term for either, not one replacing both (review
    rv35m F13: "A and B" read as a one-term reading of the two-term verdict that no test made); a term named
    twice in the family (viscous damping on u and on x) is told by its place, not by the family's label both
    share."""
    alts = [
        Alternative(T.Asymmetry.kind, T.Offset.kind, math.nan, "x"),
        Alternative(T.SensorLag.kind, T.Offset.kind, math.nan, "y"),
    ]
    named = [T.Asymmetry.kind, T.SensorLag.kind]
    rs = readings.of_verdict("explained by: X", named, alts)
    assert len(rs) == 1 and rs[0].instead_of == tuple(named), rs
    assert rs[0].words.endswith(f"instead of {T.Asymmetry.label} or of {T.SensorLag.label}"), rs
    both = [T.Viscous.kind, T.ViscousX.kind]
    v = "explained by: X" + rate_rival.clause(T.ViscousX.kind, 0.3, [1.0, 1.2])
    (r,) = readings.of_verdict(v, both, [])
    assert r.instead_of == (T.ViscousX.kind,) and r.words.endswith(f"instead of {T.ViscousX.place_label()}")

"""``diagnose_across`` applies three more of ``diagnose``'s rules (issue 18, honest verdicts): the Masing
caveat measured on a design with an experiment below saturation (diagnosis/masing.py), "law untested"
(diagnosis/law_untested.py) and loops that have not settled (diagnosis/across_settling.py).

The records are other tests' own (tests/test_diagnosis_masing.py: a Prandtl-Ishlinskii loop written in NumPy
through a first-order or a resonant G with a delay; tests/test_distortion.py: the library's simulator with a
distorted input) and the main bench's generator (benches/generator.py: its null cases' low-amplitude
experiment whose loop centre still settles), each given as two conditions.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id.diagnosis import across_settling, law_untested
from bouc_wen_id.diagnosis.masing import MASING_MARK
from bouc_wen_id.diagnosis.settling import LEFT_OUT
from bouc_wen_id.terms import Distortion, Offset, StiffnessX

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "benches"))
sys.path.insert(0, str(HERE))
gen: Any = importlib.import_module("generator")
masing_records: Any = importlib.import_module("test_diagnosis_masing")._records
distorted_records: Any = importlib.import_module("test_distortion")._recordings


def _across(groups: list[Any], cands: list[str], own: Any = None) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=cands, per_condition=own)


@pytest.mark.parametrize("shape", ["first", "resonant"])
def test_a_pi_loop_named_a_spring_on_x_across_keeps_the_caveat_on_a_weak_design(shape: str) -> None:
    """The PI loop of test_diagnosis_masing (stops reaching 1.4 of saturation) at 20x, one experiment at 0.5
    of saturation beside two saturating ones, two conditions (seeds 3 and 4): named a spring on x across,
    and, as diagnose says of one condition, the design is too weak to separate it from the loop, with the
    separating experiment. Main dropped the caveat across whenever an experiment was below saturation."""
    groups = [masing_records(s, (0.5, 1.4, 3.0), "pi", 20.0, reach=1.4, shape=shape) for s in (3, 4)]
    a = _across(groups, [StiffnessX.kind, "stiffness", "viscous"])
    assert StiffnessX.kind in a.named, a.verdict
    assert MASING_MARK in a.verdict and "too weak to separate" in a.verdict, a.verdict
    assert "the separating experiment" in a.verdict, a.verdict


def test_a_spring_on_x_on_designs_that_separate_it_gets_no_caveat_across() -> None:
    """The library's own spring on x on a design with the power to tell it from a PI loop (0.3 and 0.6 of
    saturation, 1.4 and 3.0 past it, 100 periods, 50x; test_diagnosis_masing's), at two conditions: no
    Masing clause (the measure is the one diagnose reads, not "some experiment is below saturation"). At 30x
    that design is too weak for a reference loop of mostly narrow stops (masing.DENSITIES)."""
    groups = [masing_records(s, (0.3, 0.6, 1.4, 3.0), "spring", 50.0, periods=100) for s in (8, 9)]
    a = _across(groups, [StiffnessX.kind, "stiffness"])
    assert StiffnessX.kind in a.named, a.verdict
    assert MASING_MARK not in a.verdict, a.verdict


def test_a_waveform_carried_by_one_experiment_per_condition_says_its_law_untested_across() -> None:
    """The input distorted in one experiment of six at each of two conditions: the law test has nothing to
    compare at either (NaN, counted as passed), and main named the term across as if its law had passed.
    Now the verdict says the law is untested at every condition where it is present, as diagnose says it
    for one; distorted in every experiment, it does not."""
    cands = [Offset.kind, Distortion.kind]
    one = _across([distorted_records(0.2, s, only=5) for s in (1, 2)], cands)
    every = _across([distorted_records(0.2, s) for s in (1, 2)], cands)
    assert one.named == (Distortion.kind,), one.verdict
    assert "law untested at every condition where it is present" in one.verdict, one.verdict
    assert "0 (1 of 6)" in one.verdict and "1 (1 of 6)" in one.verdict, one.verdict
    assert every.named == (Distortion.kind,) and "law untested" not in every.verdict, every.verdict


def test_the_law_untested_clause_names_the_conditions_where_it_holds() -> None:
    """across_text on known carriers: a term present at three conditions, one of them holding a single
    experiment (nothing to compare there), says so at that condition only; absent there, nothing."""
    exps = [SimpleNamespace(distorted=False)] * 3
    groups = [("a", exps), ("b", exps[:1]), ("c", exps)]
    t = SimpleNamespace(term=Offset.kind, label="output offset", present=(True, True, True))
    text = law_untested.across_text([t], groups)
    assert "law untested at some conditions" in text and "b (1 of 1)" in text and "a (" not in text
    assert (
        law_untested.across_text([SimpleNamespace(**{**vars(t), "present": (True, False, True)})], groups)
        == ""
    )


@pytest.mark.parametrize("seeds", [(60000, 60002), (60001, 60003)], ids=["first", "resonant"])
def test_a_still_settling_experiment_is_left_out_across_and_the_null_is_adequate(
    seeds: tuple[int, int],
) -> None:
    """Null plants of the main bench (first-order G, resonant G with a delay) whose low-amplitude
    experiment's loop centre still settles at each condition: diagnose leaves it out (not settled) and the
    plain model passes. Main fitted it across: "nothing named", status "unexplained". Now it is left out
    per condition, said, and the verdict is adequate; given the per-condition diagnoses the same ones stay
    out (their settings record them)."""
    groups = [gen.make_case("null", None, "", 0.0, s).recordings for s in seeds]
    cands = [Offset.kind, "asymmetry", "viscous"]
    a = _across(groups, cands)
    assert a.status == "adequate" and not a.named, a.verdict
    assert "left out as not settled" in a.verdict and "unexplained" not in a.verdict, a.verdict
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=cands) for g in groups]
    assert all(d.settings.get(LEFT_OUT) for d in own), [d.verdict for d in own]
    b = _across(groups, cands, own)
    assert b.status == a.status and "left out as not settled" in b.verdict, b.verdict
    assert [n for n in b.notes if "left out" in n] == [n for n in a.notes if "left out" in n]


def test_a_condition_with_no_settled_experiment_is_left_out_and_two_are_needed() -> None:
    """from_own on a diagnosis that left out every experiment raises NotSettled; too_few with one condition
    left gives the verdict that names nothing and says why."""
    exps = [SimpleNamespace(source="e1"), SimpleNamespace(source="e2")]
    own = SimpleNamespace(settings={LEFT_OUT: ["e1", "e2"]}, experiments=exps)
    with pytest.raises(across_settling.NotSettled) as err:
        across_settling.from_own(own, "2 A")
    assert err.value.names == ("e1", "e2")
    some = SimpleNamespace(settings={LEFT_OUT: ["e1"]}, experiments=exps[1:])
    assert across_settling.from_own(some, "1 A") == ("e1",)
    g = SimpleNamespace(label="1 A", left_out=("e1",))
    verdict = across_settling.too_few([g], [err.value])
    assert verdict is not None and "not settled" in verdict, verdict
    assert "condition 2 A left out" in verdict and "e1 at 1 A" in verdict, verdict
    assert across_settling.too_few([g, g], []) is None

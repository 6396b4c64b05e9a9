"""``diagnose_across`` says what ``diagnose`` says at the condition that carries the evidence (session 31
review): the Masing caveat of a spring on x present only where every experiment saturates, and a
degrading specimen's drift, which is not a loop "not settled".

The records are other tests' own: tests/test_diagnosis_masing.py (a Prandtl-Ishlinskii loop written in
NumPy, and a Bouc-Wen loop below saturation) and tests/test_degradation.py (the library's simulator with a
degrading element, and the same plant without it), and a resonant G with stiffness degradation here.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.drift import DRIFT_TERMS
from bouc_wen_id.diagnosis.masing import MASING_MARK
from bouc_wen_id.diagnosis.run import ALL_CANDIDATES
from bouc_wen_id.terms import Degradation, Stiffness, StiffnessDegradation, StiffnessX, Viscous

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
masing_records: Any = importlib.import_module("test_diagnosis_masing")._records


@pytest.mark.parametrize(
    "case",
    [(5, 3, (0.3, 0.6), (1.4, 3.0), 20.0, "first"), (7, 8, (0.25, 0.5), (1.5, 2.5), 30.0, "resonant")],
    ids=["first", "resonant"],
)
def test_the_masing_caveat_is_judged_where_the_spring_on_x_is_present(case: tuple[Any, ...]) -> None:
    """A spring on x needed only at a condition whose experiments all saturate (a PI loop past saturation,
    through a first-order G or a resonant one with a delay) keeps the caveat diagnose gives there, though the
    other condition (no spring) lies below saturation: its levels say nothing of the spring (they made the
    joint design read as unsaturated)."""
    seed_a, seed_b, low, high, size, shape = case
    below = masing_records(seed_a, low, "spring", 0.0001, shape=shape)
    pi = masing_records(seed_b, high, "pi", size, reach=high[0], shape=shape)
    cands = [StiffnessX.kind, Stiffness.kind, Viscous.kind]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alone = bw.diagnose(pi, candidates=cands)
        a = bw.diagnose_across([below, pi], [0.0, 1.0], candidates=cands)
    assert StiffnessX.kind in alone.named_terms and MASING_MARK in alone.verdict
    spring = next(t for t in a.terms if t.term == StiffnessX.kind)
    assert spring.present == (False, True)
    assert MASING_MARK in a.verdict
    assert "starts from saturation, as at 1;" in a.verdict  # the condition whose loops all saturate


degradation_records: Any = importlib.import_module("test_degradation")._recs


def _degrading(**kw: Any) -> tuple[Any, Any]:
    """A degrading specimen (rate 1e-3) at condition 1, the same plant without it at 0; diagnose of the
    degrading condition alone, and diagnose_across."""
    plain, degr = degradation_records(0.0, 0.01, seed=5), degradation_records(1e-3, 0.01, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alone = bw.diagnose(degr)
        if kw.pop("own", False):
            kw["per_condition"] = [bw.diagnose(plain), alone]
        return alone, bw.diagnose_across([plain, degr], [0.0, 1.0], **kw)


def test_a_degrading_condition_is_said_across_not_called_unsettled() -> None:
    """diagnose names degradation at the degrading condition; across, which does not model it, leaves its
    drifting experiments out *because the loop degrades* (its own judgement, run as diagnose runs it),
    never "not settled, and no degradation explains it" (said before without any test)."""
    alone, a = _degrading()
    assert Degradation.kind in alone.named_terms
    text = " ".join((a.verdict, *a.notes))
    assert "no degradation explains it" not in text
    assert "left out at 1:" in a.verdict and "diagnose of that condition alone names degradation" in a.verdict
    assert any(n.startswith("1: left out") and "the loop degrades" in n for n in a.notes)


def test_a_degrading_condition_given_its_own_diagnosis_names_no_steady_term_from_the_drift() -> None:
    """Given the conditions' own diagnoses, the degrading one's experiments were reused whole and the joint
    selection read its drift as Dahl friction on x; now its drifting experiments are left out as without
    them, and both paths say the same."""
    _, a = _degrading(own=True)
    _, b = _degrading()
    assert a.named == b.named
    assert not any(k.startswith("dahl") for k in a.named)
    assert "diagnose of that condition alone names degradation" in a.verdict


def test_a_drift_not_tested_for_degradation_is_said_untested() -> None:
    """Without a drift term among the candidates the drift is not judged: the note says degradation was not
    tested instead of claiming none explains it."""
    steady = [c for c in ALL_CANDIDATES if c not in DRIFT_TERMS]
    _, a = _degrading(candidates=steady)
    text = " ".join((a.verdict, *a.notes))
    assert "no degradation explains it" not in text
    assert "degradation not tested" in a.verdict and "degradation was not tested" in " ".join(a.notes)


def _resonant(rate: float, seed: int) -> list[bw.Recording]:
    """Another plant and design than test_degradation's: a resonant G, stiffness degradation, three
    frequencies at 0.6 and 1.8 of |G|'s scale, noise 0.02."""
    lin = bw.TransferFunction([1.0], [1.0 / 400.0, 0.3 / 20.0, 1.0])
    om = np.repeat(2 * np.pi * np.array([0.7, 1.5, 3.0]), 2)
    amps = np.tile([0.6, 1.8], 3) / lin.gain_phase(om)[0]
    terms = (StiffnessDegradation(rate),) if rate > 0 else ()
    plant = bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5), terms=terms)
    plan = bw.SinePlan(
        om, amps, settle_periods=6, periods=16, samples_per_period=64, substeps=8, noise_sd=0.02, seed=seed
    )
    return bw.simulate(plant, plan)


def test_stiffness_degradation_through_a_resonant_g_is_said_alike_on_both_paths() -> None:
    """Stiffness degradation through a resonant G at one condition: diagnose names it there; across says
    the loop degrades, with and without the conditions' own diagnoses (main: "no degradation explains it"
    without them, "nothing named", unexplained, with them)."""
    plain, degr = _resonant(0.0, 21), _resonant(1e-3, 22)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alone = bw.diagnose(degr)
        a = bw.diagnose_across([plain, degr], [0.0, 1.0])
        b = bw.diagnose_across([plain, degr], [0.0, 1.0], per_condition=[bw.diagnose(plain), alone])
    assert StiffnessDegradation.kind in alone.named_terms
    for d in (a, b):
        assert "no degradation explains it" not in " ".join((d.verdict, *d.notes))
        assert "diagnose of that condition alone names degradation" in d.verdict, d.verdict
    assert (a.status, a.named) == (b.status, b.named)

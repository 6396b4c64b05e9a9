"""``diagnose_across`` says what ``diagnose`` says at the condition that carries the evidence (session 31
review): the Masing caveat of a spring on x present only where every experiment saturates, and a
degrading specimen's drift, which is not a loop "not settled".

The records are other tests' own: tests/test_diagnosis_masing.py (a Prandtl-Ishlinskii loop written in
NumPy, and a Bouc-Wen loop below saturation) and tests/test_degradation.py (the library's simulator with a
degrading element, and the same plant without it).
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
from bouc_wen_id.diagnosis.masing import MASING_MARK
from bouc_wen_id.terms import Stiffness, StiffnessX, Viscous

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
masing_records: Any = importlib.import_module("test_diagnosis_masing")._records


def test_the_masing_caveat_is_judged_where_the_spring_on_x_is_present() -> None:
    """A spring on x needed only at a condition whose experiments all saturate (a PI loop at 1.4 and 3 times
    saturation) keeps the caveat diagnose gives there, though the other condition (no spring) lies below
    saturation: its levels say nothing of the spring (they made the joint design read as unsaturated)."""
    below = masing_records(5, (0.3, 0.6), "spring", 0.0001)
    pi = masing_records(3, (1.4, 3.0), "pi", 20.0, reach=1.4)
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

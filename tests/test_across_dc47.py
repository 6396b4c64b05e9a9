"""diagnose_across judges the DC as diagnose does (session 47, across47; diagnosis/across_dc.py): an
"adequate" headline whose DC was taken out says an output offset could not be tested (dc_untested.py).

Data: test_dc_untested.py's records (tests/wiener_sim.py's RK4, not the library's simulator) with an output
offset of 3 noise sd and a straight line of 3 noise sd over each recording, two seeds as two conditions.
Main's headline read "adequate: the plain Wiener-Bouc-Wen model fits at the noise floor at every condition"
and said the drift only in a detail; diagnose of each condition says the caveat in its headline.
"""

from __future__ import annotations

import warnings
from typing import Any

import bouc_wen_id as bw
from bouc_wen_id.diagnosis.verdict_text import headline
from test_dc_untested import CAVEAT, _drifting
from wiener_sim import recordings


def _across(groups: list[list[Any]]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=["offset", "viscous", "asymmetry"])


def test_an_offset_under_a_drifting_zero_at_two_conditions_is_said_untested_and_a_white_null_is_not() -> None:
    a = _across([_drifting(3, 3.0, 3.0), _drifting(4, 3.0, 3.0)])
    assert a.status == "adequate", a.verdict
    head = headline(a.verdict)
    assert CAVEAT + " at 0, 1:" in head and "zero drifts" in head, head  # main: no caveat in the headline
    assert "offset" not in a.named
    white = _across([recordings(3, [0.0] * 4), recordings(4, [0.0] * 4)])
    assert white.status == "adequate" and CAVEAT not in white.verdict, white.verdict

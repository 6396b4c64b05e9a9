"""diagnose_across judges the DC as diagnose does (session 47, across47; diagnosis/across_dc.py): under a
noise coloured at the DC the centre terms' DC is judged between experiments (dc_between.py), and an
"adequate" headline whose DC was taken out says an output offset could not be tested (dc_untested.py).

Pink data: test_dc_only_words.py's plain plant (the library's simulator, noise-free) under
tests/pink_noise.py's sum of AR(1)s at 1 % of the peak, two seeds as two conditions. Main read the pink null
(seeds [45, 3], [45, 4]) "unexplained structure remains" (the offset and asymmetry refused for their laws) and
a real output offset of 10 noise sd / sqrt(periods) at both conditions (seeds [46, 201], [46, 209]) as
asymmetry with Dahl friction and its pre-sliding stiffness, no offset.

Data: test_dc_untested.py's records (tests/wiener_sim.py's RK4, not the library's simulator) with an output
offset of 3 noise sd and a straight line of 3 noise sd over each recording, two seeds as two conditions.
Main's headline read "adequate: the plain Wiener-Bouc-Wen model fits at the noise floor at every condition"
and said the drift only in a detail; diagnose of each condition says the caveat in its headline.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis.verdict_text import headline
from pink_noise import sum_of_ar1
from test_dc_only_words import PERIODS, plain_plant
from test_dc_untested import CAVEAT, _drifting
from wiener_sim import recordings


def _across(groups: list[list[Any]], candidates: Any = ("offset", "viscous", "asymmetry")) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=candidates)


def _pink(key: list[int], offset_sds: float) -> list[Any]:
    """The plain plant under pink noise of 1 % of the peak from ``default_rng(key)``, plus an output offset of
    ``offset_sds`` noise sd / sqrt(periods)."""
    clean = plain_plant()
    sd = 0.01 * float(np.max(np.abs(clean[0].y)))
    rng = np.random.default_rng(key)
    off = offset_sds * sd / math.sqrt(PERIODS)
    return [replace(r, y=r.y + sd * sum_of_ar1(r.y.size, rng) + off) for r in clean]


def test_a_pink_null_across_two_conditions_is_adequate() -> None:
    a = _across([_pink([45, 3], 0.0), _pink([45, 4], 0.0)], None)
    assert a.status == "adequate" and not a.named, a.verdict  # main: unexplained, offset refused for its law


def test_a_pink_offset_at_two_conditions_is_named_an_offset_not_an_asymmetry() -> None:
    a = _across([_pink([46, 201], 10.0), _pink([46, 209], 10.0)], None)
    assert "offset" in a.named and "asymmetry" not in a.named, a.verdict  # main: asymmetry, Dahl, no offset


def test_an_offset_under_a_drifting_zero_at_two_conditions_is_said_untested_and_a_white_null_is_not() -> None:
    a = _across([_drifting(3, 3.0, 3.0), _drifting(4, 3.0, 3.0)])
    assert a.status == "adequate", a.verdict
    head = headline(a.verdict)
    assert CAVEAT + " at 0, 1:" in head and "zero drifts" in head, head  # main: no caveat in the headline
    assert "offset" not in a.named
    white = _across([recordings(3, [0.0] * 4), recordings(4, [0.0] * 4)])
    assert white.status == "adequate" and CAVEAT not in white.verdict, white.verdict

"""Review 43's three false sentences, each held to what its numbers allow: a smoothness degree never tested
(3 conditions, degree 2 passes through any 3 values), a gain ratio of 1.0046 printed "1x apart", and a
share of "100 % of the excess" said where the step's cost showed no excess over its dof."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from bouc_wen_id.diagnosis.across import _how
from bouc_wen_id.diagnosis.across_smooth import MAX_DEGREE, smoothness
from bouc_wen_id.diagnosis.across_types import TermAcross
from bouc_wen_id.diagnosis.bounds_clear import removes
from bouc_wen_id.diagnosis.structure import ratio_apart


def _term(conditions: list[float], values: list[float], ses: list[float]) -> TermAcross:
    p = smoothness(conditions, values, ses)
    degree = next((d for d, pd in enumerate(p) if pd > 0.01), None)
    k = len(values)
    return TermAcross(
        "viscous", "viscous damping", "c", "s", tuple(values), tuple(ses), (True,) * k, (0.0,) * k, p, degree
    )


def test_three_conditions_do_not_claim_degree_two() -> None:
    # review 43 d3: cu 0.001514 / 0.002194 / 0.002981 +- 1.5-1.8e-5, a smooth quadratic not on a line
    t = _term([0.0, 0.5, 1.0], [0.001514, 0.002194, 0.002981], [1.5e-5, 1.6e-5, 1.8e-5])
    assert len(t.smooth_p) == 2 and t.smooth_degree is None  # degrees 0 and 1 tested, both refused
    how = _how(t)
    assert f"degree {MAX_DEGREE} fits" not in how
    assert "up to degree 1" in how and "degree-2 curve passes through any 3 values" in how


def test_five_conditions_keep_the_degree_two_sentence() -> None:
    rng = np.random.default_rng(43)
    values = list(rng.choice([1.0, 3.0], 5) + rng.normal(0, 0.01, 5))  # jumps: no polynomial of degree 2
    t = _term([0.0, 0.25, 0.5, 0.75, 1.0], values, [0.01] * 5)
    assert len(t.smooth_p) == MAX_DEGREE + 1 and t.smooth_degree is None
    assert f"no polynomial up to degree {MAX_DEGREE} fits them" in _how(t)


def test_gain_ratio_said_in_percent_when_close() -> None:
    assert ratio_apart(1.0046) == "0.46 %"
    assert ratio_apart(1.55) == "1.55x"
    assert "1x" not in ratio_apart(1.009)


def test_no_share_said_without_an_excess() -> None:
    tr = SimpleNamespace(share=1.0, improvement=812.5, p_adjusted=1.4e-82)
    said = removes(tr, no_excess=True)
    assert "100 %" not in said and "812" in said and "p adj = 1.4e-82" in said
    assert removes(SimpleNamespace(share=0.85, improvement=3.0, p_adjusted=0.01), False).startswith(
        "would remove 85 % of the excess alone (p adj = 0.01"
    )

"""A term is named beside Dahl's element only with an effect of its own (diagnosis/beside.py, issue 18).

The bench's Dahl loop of exponent 2 (outside the library; benches/generator.py, its own closed-form G and
exact per-step Dahl branch, not the library's simulator) was named Dahl friction and then pinching at 30x
in 3 of 20 cases: pinching explained nothing of the plain model's misfit (share 0.000) and was needed only
to bend the element's branch. The rule's inputs are checked on synthetic fits; the case end to end.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugParams
from bouc_wen_id.diagnosis import beside as B

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

DAHL_X = T.Dahl.at(T.Place.X)


def _fit(terms: tuple[str, ...]) -> Any:
    par = AugParams(1.0, 0.0, 1.5, terms, np.full(len(terms), 0.1), np.array([1.0]), np.array([0.0]))
    return type("F", (), {"params": par})()


def test_the_rule_fires_only_beside_a_dahl_element_and_only_without_an_own_effect() -> None:
    with_dahl = _fit((DAHL_X.kind, DAHL_X.companion))
    plain = _fit(())
    pinch = T.Pinching.kind
    assert B.elements_beside(with_dahl, pinch) == [DAHL_X.kind]
    assert B.only_beside(with_dahl, pinch, 0.6, 0.05)  # nothing on the plain model: refused
    assert B.only_beside(with_dahl, pinch, math.nan, 0.05)  # its plain fit failed: no effect shown
    assert not B.only_beside(with_dahl, pinch, 0.01, 0.05)  # an effect of its own: kept
    assert not B.only_beside(plain, pinch, 0.6, 0.05)  # no Dahl element: the rule does not apply
    # The element itself (or its companion) is never "beside" itself.
    assert B.elements_beside(with_dahl, DAHL_X.kind) == []
    assert B.elements_beside(with_dahl, DAHL_X.companion) == []


def test_pinching_that_only_bends_a_dahl_branch_is_not_named() -> None:
    """Dahl's exponent 2 at 30x (the bench's seed 61010, a resonant G): Dahl friction is named first, then
    pinching passes its F test, its law and its band beside it (the verdict before this rule: "explained
    by Dahl friction, pinching"), though it fitted nothing on the plain model. Now only the element is
    named, with its family caveat; the rest stays unexplained structure."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import caveats

    case = gen.make_case("outside", "dahl_n2", "", 30.0, 61010)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
    pinch = T.Pinching.kind
    assert pinch not in d.named_terms, d.verdict
    assert set(d.named_terms) == {DAHL_X.kind, DAHL_X.companion}, d.verdict
    assert caveats.FAMILY_MARK in d.verdict
    first = {tr.term: tr for tr in d.steps[0].trials}
    assert d.steps[0].chosen == DAHL_X.kind
    assert not first[pinch].passed and not first[pinch].p_value < 0.05  # no effect of its own
    later = {tr.term: tr for tr in d.steps[1].trials}
    assert later[pinch].passed  # beside the element it passed its F test: the rule refused it
    assert d.steps[1].chosen is None
    # Refused, not dropped silently: the step records it and the verdict names it with its plain-model p.
    assert d.steps[1].beside == (pinch,)
    assert f"not named: {T.Pinching.place_label()} beside {DAHL_X.place_label()}" in d.verdict
    assert f"(on the plain model p = {first[pinch].p_value:.2g})" in d.verdict

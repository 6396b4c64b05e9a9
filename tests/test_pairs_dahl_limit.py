"""A Dahl element driven to its spring limit beside another member is not named (review 33, ku_fu_res).

Parallel stiffness and dry friction on u through a resonant G with a delay, 16 experiments (4 frequencies x
4 amplitudes). No single term fits with one value for every experiment, so the pair step runs; Dahl friction
beside dry friction came out with fc = 1.6 +- 0.55 and its sigma the true spring (shape sigma A / fc below
0.05 at every experiment: the spring limit), and the pair "Dahl + Coulomb" was named for "stiffness +
Coulomb". A single Dahl fit at that limit is refused (fitting.at_a_limit); a pair member is too now.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import pairs
from bouc_wen_id.diagnosis.fitting import LIMIT_SHAPES


def test_a_pair_member_at_its_spring_limit_is_refused_and_the_spring_named() -> None:
    lin = bw.TransferFunction([36.0], [1.0, 1.2, 36.0], delay=0.03)
    om = np.array([1.5, 3.0, 5.0, 7.0] * 4)
    amps = np.repeat([0.3, 0.6, 1.0, 1.5], 4)
    plan = bw.SinePlan(
        om, amps, settle_periods=15, periods=15, samples_per_period=128, substeps=3, noise_sd=0.01, seed=9483
    )
    k, f = 0.038, 0.026
    plant = bw.WienerPlant(lin, bw.BoucWen(1.0, 0.3, 1.5), terms=(T.Stiffness(k), T.Coulomb(f)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(bw.simulate(plant, plan))
    assert set(d.named_terms) == {T.Stiffness.kind, T.Coulomb.kind}, d.verdict
    got = {t.term: t for t in d.named}
    assert abs(got[T.Stiffness.kind].value - k) < 5 * got[T.Stiffness.kind].standard_error + 0.02 * k
    assert abs(got[T.Coulomb.kind].value - f) < 5 * got[T.Coulomb.kind].standard_error + 0.02 * f
    # Every set with Dahl friction the pair step fitted here is refused, or holds a shape inside its range.
    for st in d.steps:
        for p in getattr(st, "pairs", ()):
            if T.Dahl.kind in p.terms and p.fit is not None and not p.refused:
                par = p.fit.params
                fc = par.values[par.terms.index(T.Dahl.kind)]
                sigma = par.values[par.terms.index(T.TERMS[T.Dahl.kind].companion)]
                assert max(sigma * a / fc for a in amps) >= LIMIT_SHAPES[0], p


class _Rules(pairs.Rules):
    """Every member physical, significant and away from its null; Dahl friction at its limit."""

    def __init__(self) -> None:
        super().__init__([])

    def dof(self, fit: Any) -> int:
        return 1000

    def physical(self, fit: Any, term: str) -> bool:
        return True

    def at_limit(self, fit: Any, term: str) -> bool:
        return term == T.Dahl.kind

    def away(self, fit: Any, term: str, level: float, s2: float) -> bool:
        return True


def test_the_member_tests_refuse_a_member_at_its_limit_and_say_so() -> None:
    fit = SimpleNamespace(cost=1000.0, params=SimpleNamespace(terms=("dahl_pair_stub",) * 3))
    other = SimpleNamespace(cost=0.0, params=SimpleNamespace(terms=("x",) * 2))
    without = {T.Coulomb.kind: (3000.0, other), T.Dahl.kind: (3000.0, other)}
    ps, why = pairs._member_tests(_Rules(), fit, without, 0.05, 10)  # type: ignore[arg-type]
    assert all(p < 0.05 for p in ps)
    assert "spring or dry-friction limit" in why and T.TERMS[T.Dahl.kind].place_label() in why, why


def test_the_rules_ask_fittings_limit_test(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[str] = []

    def limit(exps: Any, fit: Any, term: str) -> bool:
        seen.append(term)
        return True

    monkeypatch.setattr(pairs, "at_a_limit", limit)
    assert pairs.Rules([]).at_limit(None, T.Dahl.kind) and seen == [T.Dahl.kind]

"""One shared value across conditions (bouc_wen_id.diagnosis.shared, issue 18): the nested fit with one value
of a named term at every condition, refitted jointly, and its F test against one value per condition.

The conditions are made by the bench's independent generator (benches/generator.py: G integrated exactly,
the hysteresis by its own RK4, not the library's simulator), one plant, a noise stream per condition.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import across, shared
from bouc_wen_id.diagnosis.fitting import fit_with, physical
from bouc_wen_id.diagnosis.select import dof_of

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
G: Any = importlib.import_module("generator")

CANDS = ("offset", "stiffness", "viscous", "viscous@x", "asymmetry")


def _conditions(seed: int, sizes: tuple[float, ...], unit: float = 1.0) -> tuple[list[list[Any]], np.ndarray]:
    """Recordings of one plant with viscous damping on u sized ``sizes`` averaged-noise sd per condition; the
    output (and its noise) in ``unit`` times the generator's units."""
    p = G.make_plant(seed)
    b = G.base(p)
    plain = G.run(p, G.Effect(), shared=b)
    one = float(G.contribution(p, G.Effect("viscous", "u", np.ones(1)), plain, b)[0])
    values = np.asarray(sizes) / one
    y = unit * G.run(p, G.Effect("viscous", "u", values), shared=b)
    noise = unit * G.NOISE_SD
    return [G.recordings(p, y[k], 100 * seed + 50 + k, noise_sd=noise) for k in range(values.size)], values


def _across(groups: list[list[Any]]) -> bw.AcrossDiagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [float(k) for k in range(len(groups))], candidates=CANDS)


def test_a_constant_term_is_shared_and_its_value_is_the_truth() -> None:
    groups, truth = _conditions(5, (0.4, 0.4, 0.4, 0.4))
    a = _across(groups)
    assert a.named == ("viscous",), a.verdict
    (t,) = a.terms
    sf = t.shared_fit
    assert sf is not None and sf.shared and t.shared, sf
    assert abs(sf.value - truth[0]) < 3.0 * sf.standard_error, (sf, truth)
    # One value is tighter than any condition's own.
    assert sf.standard_error < min(t.standard_errors)
    assert "shared: c = " in a.verdict
    assert "one shared value refitted: " in a.summary() and "(shared)" in a.summary()
    assert a.to_dict()["terms"][0]["shared_fit"]["shared"] is True


def test_a_term_that_moves_with_the_condition_is_not_shared() -> None:
    groups, _ = _conditions(6, (0.1, 0.3, 0.5, 0.7))
    a = _across(groups)
    assert a.named == ("viscous",), a.verdict
    (t,) = a.terms
    sf = t.shared_fit
    assert sf is not None and not sf.shared and not t.shared, sf
    assert sf.p_value < 0.05 and sf.cost_shared > sf.cost_free
    assert "varies with the condition (one shared value refused, p = " in a.verdict


def _groups_and_fits(seed: int, term: str, unit: float = 1.0) -> tuple[list[Any], list[Any]]:
    groups, _ = _conditions(seed, (0.5, 0.5), unit)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gs = [across._group(g, str(k), float(k), CANDS, None) for k, g in enumerate(groups)]
    fits = [fit_with(g.sx, g.plain, term, g.substeps) for g in gs]
    return gs, fits


def test_the_same_data_twice_share_their_value_exactly() -> None:
    # Two conditions holding the same recordings: the joint fit must reach the free fits' cost (no
    # spurious difference) with the condition's own value.
    gs, fits = _groups_and_fits(7, "viscous")
    g, f = gs[0], fits[0]
    assert f is not None
    sf = shared.shared_test(
        "viscous", [g.sx, g.sx], [g.scale] * 2, [g.substeps] * 2, [f, f], [dof_of(g.sx, f)] * 2, 0.05
    )
    assert sf is not None
    own, se = physical(f, g.scale, "viscous")
    assert abs(sf.value - own) < 1e-3 * se
    assert abs(sf.cost_shared - sf.cost_free) < 1e-6 * sf.cost_free and sf.p_value > 0.99


def test_the_joint_gradient_is_the_costs_derivative() -> None:
    # J^T W r of the joint vector against central differences of the joint cost, including mu's column for
    # the asymmetry (its scaled value moves with mu at a fixed physical value); away from the optimum, so
    # that the gradient is not dominated by the differences' curvature error. The output in units 50 times
    # the generator's: the data scale is far from 1, so that the asymmetry's mu chain matters.
    for term in ("viscous", "asymmetry"):
        gs, fits = _groups_and_fits(8, term, 50.0)
        assert abs(np.log(gs[0].scale.y)) > 2.0
        assert all(f is not None for f in fits)
        conds = [shared._Cond(g.sx, g.scale, g.substeps, f, dof_of(g.sx, f)) for g, f in zip(gs, fits)]
        v = 1.5 * shared._start(term, conds)
        if term == "asymmetry":  # a scaled value far from 0, so that the chain's q~ d ln f / d mu matters
            v = 0.05 * gs[0].scale.factor(term, fits[0].params.mu)
        x = shared._pack(term, conds, v)
        x[1:4] *= 1.01
        ev = shared._evaluate(term, conds, x, True)
        assert ev is not None
        _, grad, _ = ev
        for i in (0, 1, 2, 3, 4, x.size - 2):
            h = 1e-6 * abs(x[i]) if x[i] != 0 else 1e-9
            up, dn = x.copy(), x.copy()
            up[i] += h
            dn[i] -= h
            cu, cd = shared._evaluate(term, conds, up, False), shared._evaluate(term, conds, dn, False)
            assert cu is not None and cd is not None
            fd = (cu[0] - cd[0]) / (2 * h)
            assert abs(fd + 2 * grad[i]) <= 1e-3 * abs(fd) + 1e-5 * np.abs(grad).max(), (term, i, fd, grad[i])


def test_a_joint_fit_cut_at_its_iteration_limit_is_not_converged(monkeypatch: Any) -> None:
    # From a shared value far from the conditions' own, one LM iteration cannot reach a stationary point: the
    # fit says so (its cost only bounds the best shared fit's from above), where the full fit does not.
    gs, fits = _groups_and_fits(8, "viscous")
    assert all(f is not None for f in fits)
    conds = [shared._Cond(g.sx, g.scale, g.substeps, f, dof_of(g.sx, f)) for g, f in zip(gs, fits)]
    v0 = 3.0 * shared._start("viscous", conds)
    full = shared._joint_fit("viscous", conds, v0, 1e-6)
    monkeypatch.setattr(shared, "MAX_ITER", 1)
    cut = shared._joint_fit("viscous", conds, v0, 1e-6)
    assert full is not None and cut is not None
    assert full[4] and not cut[4] and cut[3] == 1 and cut[1] > full[1]


def test_the_text_never_calls_an_undetermined_or_linearised_value_a_refusal_or_a_degree_0_trend() -> None:
    def term(sf: shared.SharedTest, degree: Any) -> across.TermAcross:
        return across.TermAcross(
            "viscous", "viscous damping", "c", "s", (1.0, 1.1), (0.1, 0.1), (True, True), (0.0, 0.0),
            (0.5,), degree, sf,
        )  # fmt: skip

    refused = shared.SharedTest("viscous", 1.05, 0.01, 10.0, 30.0, 8, 9.0, 1e-3, False, 5, True)
    text = across._how(term(refused, 0))
    assert "one shared value refused" in text and "degree-0" not in text and "linearised" in text
    cut = shared.SharedTest("viscous", 1.05, 0.01, 10.0, 30.0, 8, 9.0, 1e-3, False, 60, False)
    text = across._how(term(cut, 1))
    assert "not determined" in text and "refused" not in text

"""Dahl friction in the diagnosis (docs/diagnosis.md, "Dahl friction"): one candidate per place whose two
terms are added together from paired starts, its limits (a spring, dry friction) named as those simpler terms,
and, on data of the independent bench generator (``benches/generator.py``: the library's exponent-1 Dahl loop
on x integrated exactly along each sample step, not the library's closed form), the element named at its
place."""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output, fit_augmented
from bouc_wen_id.diagnosis import fitting as F
from bouc_wen_id.diagnosis import select as S

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

DAHL_X, SIGMA_X = T.DahlX.kind, T.DahlSigmaX.kind


def _data(
    terms: tuple[str, ...], values: tuple[float, ...], seed: int
) -> tuple[list[AugExperiment], AugParams]:
    rng = np.random.default_rng(seed)
    gains, phases, exps = [], [], []
    for k, (u, om) in enumerate([(1.2, 2.0), (3.0, 2.0), (1.2, 5.0), (3.0, 5.0)]):
        g, ph = 1.0, 0.3 + 0.2 * k
        truth = AugParams(0.8, 0.2, 1.6, terms, np.array(values), np.array([g]), np.array([ph]))
        e0 = AugExperiment(np.zeros(64), u, om, 0.1 * k, 1.0)
        y = augmented_output(e0, truth, 0, substeps=4)
        sd = 1e-3
        exps.append(AugExperiment(y + sd * rng.standard_normal(64), u, om, 0.1 * k, 1.0 / sd**2))
        gains.append(g)
        phases.append(ph)
    return exps, AugParams(0.8, 0.2, 1.6, terms, np.array(values), np.array(gains), np.array(phases))


def test_candidate_starts_add_both_terms_from_paired_shapes() -> None:
    exps, truth = _data((), (), seed=1)
    plain = fit_augmented(exps, truth, substeps=4)
    starts = F.candidate_starts(exps, plain, DAHL_X, 4)
    assert len(starts) == len(T.Dahl.START_SHAPES)
    amps = sorted(abs(e.amplitude * g) for e, g in zip(exps, plain.params.gains))
    for st, r in zip(starts, T.Dahl.START_SHAPES):
        assert st.terms == (DAHL_X, SIGMA_X)
        fc, sigma = st.values
        assert fc > 0 and math.isclose(sigma * amps[len(amps) // 2] / fc, r, rel_tol=1e-12)


def test_a_fit_at_a_limit_is_the_simpler_term() -> None:
    """A Dahl fit whose shape sigma A / Fc is tiny everywhere is a spring, huge everywhere dry friction: not
    the element (:func:`fitting.at_a_limit`); in between it is the element."""
    exps, truth = _data((DAHL_X, SIGMA_X), (0.05, 0.2), seed=2)
    fit = fit_augmented(exps, truth, substeps=4)
    assert not F.at_a_limit(exps, fit, DAHL_X)
    amps = [abs(e.amplitude * g) for e, g in zip(exps, fit.params.gains)]
    for sigma, fc in ((1e-3, 1e3), (1e3, 1e-3)):
        at = replace(fit, params=replace(fit.params, values=np.array([fc, sigma])))
        shapes = [sigma * a / fc for a in amps]
        assert max(shapes) < F.LIMIT_SHAPES[0] or min(shapes) > F.LIMIT_SHAPES[1]
        assert F.at_a_limit(exps, at, DAHL_X)
    assert not F.at_a_limit(exps, fit, "stiffness@x")  # a one-term term has no limit here


def test_simpler_first_puts_a_limit_ahead_unless_the_element_beats_it() -> None:
    exps, truth = _data((DAHL_X, SIGMA_X), (0.05, 0.2), seed=3)
    fit = fit_augmented(exps, truth, substeps=4)
    dof = S.dof_of(exps, fit)

    def trial(term: str, cost: float) -> S.Trial:
        return S.Trial(term, cost, 100.0 - cost, 1.0, 0.0, 0.0, 1.0, True, fit=fit)

    spring = T.StiffnessX.kind
    # A tie (the element's one extra parameter removes less than the F test's 5 % point): the spring first.
    tie = [trial(DAHL_X, 50.0), trial(spring, 50.0 * (1 + 1.0 / dof))]
    assert [t.term for t in S.simpler_first(exps, tie, 0.05)] == [spring, DAHL_X]
    # A clear gain: the element stays first; a best term without limits is left alone.
    gain = [trial(DAHL_X, 50.0), trial(spring, 80.0)]
    assert [t.term for t in S.simpler_first(exps, gain, 0.05)] == [DAHL_X, spring]
    # A limit at the other place counts too (where G is flat a spring on u is one on x).
    on_u = [trial(DAHL_X, 50.0), trial(T.Stiffness.kind, 50.0 * (1 + 1.0 / dof))]
    assert [t.term for t in S.simpler_first(exps, on_u, 0.05)] == [T.Stiffness.kind, DAHL_X]
    other = [trial("play", 40.0), trial(DAHL_X, 50.0)]
    assert S.simpler_first(exps, other, 0.05) == other


def _diagnose(name: str, place: str, size: float, seed: int) -> Any:
    case = gen.make_case("library", name, place, size, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(case.recordings)


@pytest.mark.parametrize("seed", [48001, 48002])
def test_the_generators_dahl_loop_on_x_is_named_dahl_friction_on_x(seed: int) -> None:
    # The generator's loop is the library's law (exponent 1) integrated its own way. Where G is nearly flat
    # over the band (seed 48001) x is u up to a constant gain and phase: the element may be named at either
    # place (48001: on u; on x it fits better but fails its law narrowly, p = 0.0031: a false alarm of the
    # law test, so x is listed as the place alternative with that p, select.preferred_by_fit; docs/
    # diagnosis.md "Misses at 10x"); elsewhere (48002, first order) at x. Named with the family caveat
    # (diagnosis/caveats.py): other loops would fit too.
    from bouc_wen_id.diagnosis.caveats import FAMILY_MARK

    d = _diagnose("dahl", "x", 10.0, seed)
    assert d.status == "explained", d.verdict
    flat = gen.make_plant(seed).shape == "flat"
    on_u = {T.Dahl.kind, T.DahlSigma.kind}
    assert set(d.named_terms) == {DAHL_X, SIGMA_X} or (flat and set(d.named_terms) == on_u), d.verdict
    assert FAMILY_MARK in d.verdict
    if set(d.named_terms) == on_u:  # named at the other place: the truth's place is never dropped silently
        assert any(a.rival == DAHL_X for a in d.alternatives), d.verdict


@pytest.mark.parametrize(("name", "place"), [("stiffness", "x"), ("coulomb", "x")])
def test_nested_limits_keep_their_own_names(name: str, place: str) -> None:
    """A spring on x and dry friction on x (the generator's, 30x the noise) are named as themselves: the
    element that nests them does not take their rows."""
    d = _diagnose(name, place, 30.0, 47001)
    named = set(d.named_terms)
    assert f"{name}@{place}" in named and DAHL_X not in named, d.verdict


def _varied(sigmas: tuple[float, ...], seed: int) -> list[AugExperiment]:
    """Records of a Dahl element on x whose level is shared but whose pre-sliding stiffness differs by
    experiment (no one element draws them all)."""
    rng = np.random.default_rng(seed)
    exps = []
    for k, ((u, om), sg) in enumerate(zip([(1.2, 2.0), (3.0, 2.0), (1.2, 5.0), (3.0, 5.0)], sigmas)):
        truth = AugParams(
            0.8, 0.2, 1.6, (DAHL_X, SIGMA_X), np.array([0.05, sg]), np.array([1.0]), np.array([0.3 + 0.2 * k])
        )
        e0 = AugExperiment(np.zeros(64), u, om, 0.1 * k, 1.0)
        y = augmented_output(e0, truth, 0, substeps=4)
        exps.append(AugExperiment(y + 1e-3 * rng.standard_normal(64), u, om, 0.1 * k, 1.0 / 1e-6))
    return exps


def test_the_law_frees_both_parameters_of_the_element() -> None:
    """The element claims one level AND one pre-sliding stiffness for all experiments: its law test frees
    both per experiment, so a stiffness that moves between experiments fails it while one shared passes."""
    _, start = _data((DAHL_X, SIGMA_X), (0.05, 0.2), seed=6)
    same = _varied((0.2, 0.2, 0.2, 0.2), seed=6)
    moved = _varied((0.2, 0.3, 0.2, 0.3), seed=6)  # the level's column alone: p ~ 1e-3, both: ~ 1e-34
    p_same = S.law_test(same, fit_augmented(same, start, substeps=4), DAHL_X, 4)
    p_moved = S.law_test(moved, fit_augmented(moved, start, substeps=4), DAHL_X, 4)
    assert p_same > 0.01
    assert p_moved < 1e-8

"""Pinching's band test (diagnosis/pinch_shape.py): the NumPy pinched loop is the core's, its band columns are
derivatives of the law, and the test refuses pinching on a kinked (stop-distribution) loop while it keeps
pinching on pinched loops; the loops made by ``benches/generator.py`` (its own RK4 and stops, not the
library's solvers)."""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output
from bouc_wen_id.diagnosis import pinch_shape as PS
from bouc_wen_id.diagnosis import select as S

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def _random_loop(rng: np.random.Generator) -> tuple[float, float, float, float, float, float]:
    beta = float(rng.uniform(0.3, 1.5))
    gamma = float(rng.uniform(-0.8, 0.8)) * beta
    return (
        beta,
        gamma,
        float(rng.uniform(1.1, 2.5)),
        float(rng.uniform(0.1, 0.9)),
        float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 4.0)),
        float(rng.uniform(-math.pi, math.pi)),
    )


@pytest.mark.parametrize("seed", range(4))
def test_the_numpy_pinched_loop_is_the_cores(seed: int) -> None:
    rng = np.random.default_rng(seed)
    beta, gamma, mu, zeta1, a, phi = _random_loop(rng)
    p = 96
    e = AugExperiment(ybar=np.zeros(p), amplitude=1.0, frequency=1.0, grid_phase=0.0, weight=1.0)
    par = AugParams(beta, gamma, mu, (T.Pinching.kind,), np.array([zeta1]), np.array([a]), np.array([phi]))
    y = augmented_output(e, par, 0, substeps=8)
    w = PS.band_columns([a], [-phi], [p], beta, gamma, mu, zeta1)[0][:, 0]
    assert np.max(np.abs(w - y)) <= 1e-6 * np.max(np.abs(y))


def _euler_loop(
    a: float, beta: float, gamma: float, mu: float, zeta1: float, q: float, z2: float, p: int
) -> Any:
    """The pinched law stepped in time (explicit Euler, 20000 steps a cycle, three cycles from rest): an
    independent integration, sampled at ``x_j = a cos(2 pi j / p)`` on the last cycle."""
    wu = (1.0 / (beta + gamma)) ** (1.0 / mu)
    per = 20000 // p
    steps = per * p
    x = a * np.cos(np.linspace(0.0, 2 * math.pi, steps + 1))
    w = 0.0
    out = np.empty(p)
    for _cycle in range(3):
        for k in range(steps):
            if k % per == 0:
                out[k // per] = w
            dx = float(x[k + 1] - x[k])
            s = math.copysign(1.0, dx)
            hb = 1.0 - abs(w) ** mu * (beta * s * math.copysign(1.0, w) + gamma)
            z = (w * s - q * wu) / (z2 * wu)
            w += dx * hb * (1.0 - zeta1 * math.exp(-z * z))
    return out


def test_the_band_columns_are_the_laws_derivatives() -> None:
    beta, gamma, mu, zeta1, a, p = 0.8, 0.2, 1.6, 0.6, 2.5, 32
    cols = PS.band_columns([a], [0.0], [p], beta, gamma, mu, zeta1)[0]
    dq, dz = 0.02, 0.04
    fd_q = (
        _euler_loop(a, beta, gamma, mu, zeta1, T.PINCHING_CENTRE + dq, T.PINCHING_WIDTH, p)
        - _euler_loop(a, beta, gamma, mu, zeta1, T.PINCHING_CENTRE - dq, T.PINCHING_WIDTH, p)
    ) / (2 * dq)
    fd_z = (
        _euler_loop(a, beta, gamma, mu, zeta1, T.PINCHING_CENTRE, T.PINCHING_WIDTH + dz, p)
        - _euler_loop(a, beta, gamma, mu, zeta1, T.PINCHING_CENTRE, T.PINCHING_WIDTH - dz, p)
    ) / (2 * dz)
    for col, fd in ((cols[:, 1], fd_q), (cols[:, 2], fd_z)):
        assert np.max(np.abs(col)) > 0.05  # the band moves the loop
        assert np.max(np.abs(col - fd)) <= 0.03 * np.max(np.abs(fd))


def _pinching_trial(recordings: list[Any]) -> tuple[Any, Any]:
    """The diagnosis with pinching its only candidate: the diagnosis and pinching's first trial."""
    import bouc_wen_id as bw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recordings, candidates=(T.Pinching.kind,))
    trials = [tr for st in d.steps for tr in st.trials if tr.term == T.Pinching.kind]
    return d, (trials[0] if trials else None)


def test_the_band_test_refuses_a_kinked_loop_and_keeps_a_pinched_one() -> None:
    """A parallel sum of five stops on x (the bench's Iwan loop at 30x noise sd) is fitted by pinching with
    its law holding (one zeta1 for all experiments): the law test alone named it; the band test refuses it.
    Pinched loops (Foliente's factor in the generator's own RK4) keep their name."""
    from bouc_wen_id.diagnosis import pinch_shape

    fitted = 0
    for seed in range(301, 306):
        case = gen.make_case("outside", "iwan", "", 30.0, seed)
        d, tr = _pinching_trial(case.recordings)
        assert T.Pinching.kind not in d.named_terms
        if tr is None or not tr.passed:  # pinching does not fit this loop at all
            continue
        fitted += 1
        assert tr.law_p_value < S.LAW_ALPHA  # refused by its claims ...
        exps, fit = _experiments_and_fit(d, tr)
        substeps = d.settings["substeps"]
        # ... by its band: its law alone (one zeta1 for all experiments, the check before this one) holds.
        assert S.law_test(exps, fit, T.Pinching.kind, substeps) >= S.LAW_ALPHA
        assert pinch_shape.band_test(exps, fit, T.Pinching.kind, substeps) < S.LAW_ALPHA / 2
    assert fitted >= 3  # pinching fits part of most kinked loops: the test is exercised
    named = 0
    for seed in range(311, 316):
        case = gen.make_case("library", "pinching", "", 30.0, seed)
        d, tr = _pinching_trial(case.recordings)
        named += T.Pinching.kind in d.named_terms
    # The band test is a 2-dof Wald test at LAW_ALPHA / 2 (Bonferroni with the law): on 31 pinched loops at
    # 30x (seeds 311-341) its p was below 0.005 once (seed 313, a flat G; docs/diagnosis.md).
    assert named >= 4


def _experiments_and_fit(d: Any, tr: Any) -> tuple[Any, Any]:
    from bouc_wen_id.diagnosis.fitting import Scale, carry_through_g, scaled

    s = d.settings["scale"]
    sx = carry_through_g(
        scaled(list(d.experiments), Scale(s["y"], s["u"])), d.plain_fit, d.settings["substeps"]
    )
    return sx, tr.fit


def test_the_band_is_not_tested_where_the_loop_is_not_solved() -> None:
    p = 32
    e = AugExperiment(ybar=np.zeros(p), amplitude=1.0, frequency=1.0, grid_phase=0.0, weight=1.0)
    names = (T.Pinching.kind, T.Asymmetry.kind)
    par = AugParams(1.0, 0.0, 1.5, names, np.array([0.3, 0.1]), np.array([1.0]), np.array([0.0]))
    from bouc_wen_id.augmented import AugFit  # noqa: F401 - the type the test builds below

    fit: Any = type("F", (), {"params": par})()
    assert math.isnan(PS.band_test([e], fit, T.Pinching.kind, 4))
    assert math.isnan(PS.band_test([e], fit, T.Asymmetry.kind, 4))
    assert PS.is_pinching(T.Pinching.kind) and not PS.is_pinching(T.Asymmetry.kind)

"""One RK4 substep count per experiment in the augmented fit (issue 18 item 4: the diagnosis's speed).

The core (``augmented_refine``'s ``experiment_substeps``), the NumPy oracle and the typed API
(``AugExperiment.substeps``) evaluate each experiment at its own count; the diagnosis gives a coarse grid
more steps per sample than the fine grids fitted with it. Every random number comes from
``np.random.default_rng(seed)`` with a fixed seed.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Literal

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output, fit_augmented
from bouc_wen_id.diagnosis.data import DiagExperiment
from bouc_wen_id.diagnosis.fitting import experiment_substeps, scale_of, scaled, substeps_for
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.reference import augmented as ra

HYST = (0.8, 0.2, 1.6)
#: The MR damper's six grids (samples per period of /work/shared/data/real's files at one current).
MR_SIZES = (401, 391, 401, 325, 243, 37)


def _experiments(
    seed: int, sizes: tuple[int, ...], terms: tuple[str, ...], values: tuple[float, ...], sigma: float = 2e-3
) -> tuple[list[AugExperiment], AugParams]:
    """Periods of the augmented model, made at 64 substeps per sample (far finer than any fitted count),
    plus seeded white noise; random frequencies, amplitudes and grid phases."""
    rng = np.random.default_rng(seed)
    exps, gains, phases = [], [], []
    for p in sizes:
        om, u = float(rng.uniform(1.0, 8.0)), float(rng.uniform(0.7, 1.6))
        psi = float(rng.uniform(0, 2 * np.pi))
        g, ph = 1.0 / math.sqrt(1.0 + (om / 4.0) ** 2), math.atan(om / 4.0)
        y, _, _ = _core.augmented_output(p, u, om, psi, list(terms), np.array([*HYST, *values]), g, ph, 64)
        exps.append(AugExperiment(y + sigma * rng.standard_normal(p), u, om, psi, 1.0 / sigma**2))
        gains.append(g)
        phases.append(ph)
    truth = AugParams(*HYST, terms, np.array(values), np.array(gains), np.array(phases))
    return exps, truth


def _start(truth: AugParams) -> AugParams:
    return AugParams(0.7, 0.25, 1.8, truth.terms, 0.7 * truth.values, truth.gains * 1.05, truth.phases + 0.02)


@pytest.mark.parametrize("seed", [1, 2])
def test_fit_parity_rust_numpy_with_own_counts(seed: int) -> None:
    """Rust and the oracle agree when each experiment has its own count (random grids and counts)."""
    rng = np.random.default_rng(100 + seed)
    sizes = tuple(int(v) for v in rng.integers(12, 48, size=3))
    exps, truth = _experiments(seed, sizes, ("offset", "viscous"), (0.2, 0.03))
    counts = [int(v) for v in rng.integers(1, 6, size=3)]
    own = [replace(e, substeps=k) for e, k in zip(exps, counts)]
    r = fit_augmented(own, _start(truth), substeps=3, backend="rust")
    n = fit_augmented(own, _start(truth), substeps=3, backend="numpy")
    assert r.converged and n.converged and abs(r.iterations - n.iterations) <= 3
    np.testing.assert_allclose(r.params.shared, n.params.shared, rtol=1e-8)
    np.testing.assert_allclose(r.params.gains, n.params.gains, rtol=1e-8)
    np.testing.assert_allclose(r.cost, n.cost, rtol=1e-9)
    for a, b in zip(r.outputs, n.outputs):
        np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_each_experiment_is_evaluated_at_its_own_count(backend: Literal["rust", "numpy"]) -> None:
    exps, truth = _experiments(3, (13, 40), ("offset",), (0.3,))
    own = [replace(exps[0], substeps=7), replace(exps[1], substeps=1)]
    fit = fit_augmented(own, _start(truth), max_iter=4, substeps=3, backend=backend)
    for i, (e, k) in enumerate(zip(exps, (7, 1))):
        at_k = augmented_output(e, fit.params, i, substeps=k, backend=backend)
        np.testing.assert_array_equal(fit.outputs[i], at_k)
        # The experiment's own count wins over the call's, in the output wrapper too.
        mine = augmented_output(own[i], fit.params, i, substeps=3, backend=backend)
        np.testing.assert_array_equal(mine, at_k)
        # ... and it is not the call's count (1 and 7 steps per sample give visibly different loops).
        assert np.max(np.abs(augmented_output(e, fit.params, i, substeps=3, backend=backend) - at_k)) > 1e-9
    # Counts equal to the call's reproduce the one-count fit bit for bit.
    same = fit_augmented([replace(e, substeps=3) for e in exps], _start(truth), substeps=3, backend=backend)
    plain = fit_augmented(exps, _start(truth), substeps=3, backend=backend)
    np.testing.assert_array_equal(same.params.shared, plain.params.shared)
    assert same.cost == plain.cost


def test_own_counts_move_the_estimates_by_less_than_their_error() -> None:
    """The MR damper's grids (one coarse, five fine): the diagnosis's counts against one count for all
    move the shared parameters by a small fraction of their standard errors."""
    sizes = MR_SIZES
    exps, truth = _experiments(7, sizes, ("offset", "viscous"), (0.2, 0.03), sigma=1e-3)
    counts = [experiment_substeps(p, sizes) for p in sizes]
    one = substeps_for(sizes)
    assert counts == [2, 2, 2, 2, 2, 4] and one == 4
    f_one = fit_augmented(exps, _start(truth), substeps=one)
    f_own = fit_augmented([replace(e, substeps=k) for e, k in zip(exps, counts)], _start(truth), substeps=one)
    se = np.sqrt(np.diag(f_one.covariance))[: f_one.params.shared.size]
    assert np.all(np.isfinite(se))
    assert np.max(np.abs(f_own.params.shared - f_one.params.shared) / se) < 0.05
    assert abs(f_own.cost - f_one.cost) < 0.01 * f_one.cost


@pytest.mark.parametrize("p", [16, 37, 64, 243])
def test_the_rule_keeps_the_loop_error_small(p: int) -> None:
    """At the count the diagnosis gives a grid (>= 128 steps per period), the loop is within 1e-5 of its
    size of a 16384-steps-per-period reference (measured: 1.5e-6 at 128 steps per period, 7e-8 at 148 for
    P = 37, 2e-9 at 486 for P = 243), and twice the count is closer still."""
    terms = ["viscous"]
    shared = np.array([*HYST, 0.03])
    k = experiment_substeps(p, (p, 401))
    assert p * k >= 128
    ref = _core.augmented_output(p, 1.2, 3.0, 0.4, terms, shared, 1.0, 0.3, math.ceil(16384 / p))[0]
    err = [
        float(np.max(np.abs(_core.augmented_output(p, 1.2, 3.0, 0.4, terms, shared, 1.0, 0.3, s)[0] - ref)))
        for s in (k, 2 * k)
    ]
    size = float(np.ptp(ref))
    assert err[0] < 1e-5 * size
    assert err[1] < err[0]


def test_the_rule_per_grid() -> None:
    # The MR damper: 3670 RK4 steps per evaluation instead of 7192 with one count for all.
    assert sum(p * experiment_substeps(p, MR_SIZES) for p in MR_SIZES) == 3670
    assert sum(p * substeps_for(MR_SIZES) for p in MR_SIZES) == 7192
    # Equal grids keep the count one rule gave them all: 2 pi/512 per step, at least 2 per sample.
    for p in (8, 16, 37, 64, 100, 256, 300, 1000):
        assert experiment_substeps(p, (p, p)) == max(2, math.ceil(512 / p)) == substeps_for((p, p))


def _diag(p: int, seed: int) -> DiagExperiment:
    rng = np.random.default_rng(seed)
    y = np.cos(2 * np.pi * np.arange(p) / p) + 0.01 * rng.standard_normal(p)
    return DiagExperiment(
        frequency=2.0,
        amplitude=1.0,
        grid_phase=0.0,
        ybar=y,
        periods=10.0,
        noise_var=1e-4,
        spread_var=1e-4,
        noise_dof=9 * p,
        dc=np.zeros(1),
        h1=np.zeros(1, np.complex128),
        source=f"P={p}",
    )


def test_scaled_sets_each_experiments_count() -> None:
    exps = [_diag(p, i) for i, p in enumerate((401, 37, 243))]
    sx = scaled(exps, scale_of(exps))
    assert [e.substeps for e in sx] == [2, 4, 2]


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_bad_counts_are_named(bad: Any) -> None:
    exps, _ = _experiments(4, (16,), ("offset",), (0.1,))
    with pytest.raises(InvalidParameterError, match="substeps"):
        replace(exps[0], substeps=bad)


@pytest.mark.parametrize("core", [_core, ra], ids=["rust", "numpy"])
@pytest.mark.parametrize("counts", [[2], [2, 2, 2], [2, 0]])
def test_core_rejects_bad_experiment_counts(core: Any, counts: list[int]) -> None:
    exps, truth = _experiments(5, (16, 20), ("offset",), (0.1,))
    with pytest.raises(InvalidParameterError, match="substep"):
        core.augmented_refine(
            [e.ybar for e in exps],
            np.array([e.amplitude for e in exps]),
            np.array([e.frequency for e in exps]),
            np.array([e.grid_phase for e in exps]),
            np.array([e.weight for e in exps]),
            ["offset"],
            np.array([*HYST, 0.1]),
            truth.gains,
            truth.phases,
            experiment_substeps=counts,
        )


@pytest.mark.parametrize(("gap", "restarts"), [(3.5e-6, True), (0.0, True), (5e-3, False)])
def test_plain_fit_near_the_open_face_tries_the_generic_starts(
    monkeypatch: pytest.MonkeyPatch, gap: float, restarts: bool
) -> None:
    """A first plain fit that stalls within PLAIN_FACE_GAP of |gamma| = beta (the MR damper at 0 A stalled
    at a gap of 3.5e-6 towards gamma = -beta) is not taken as the null: the generic starts are tried, and a
    better one wins; a fit clear of the face is kept as it is."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import fitting

    calls: list[int] = []

    def fake_fit_from(exps: Any, start: Any, substeps: int, max_iter: int = 200) -> Any:
        calls.append(max_iter)
        if len(calls) == 1:  # the first start: stalled near the open face, cost 10
            return SimpleNamespace(
                params=SimpleNamespace(beta=1.0, gamma=-(1.0 - gap), mu=1.5), cost=10.0, active=False
            )
        return SimpleNamespace(
            params=SimpleNamespace(beta=1.0, gamma=1.0, mu=1.5), cost=1.0 + len(calls), active=False
        )

    monkeypatch.setattr(fitting, "fit_from", fake_fit_from)
    starts = [object()] * 4
    monkeypatch.setattr(fitting, "plain_start", lambda exps, sx, s: starts)
    best = fitting.fit_plain([], [], fitting.Scale(1.0, 1.0), 2)
    assert (len(calls) > 1) is restarts
    assert best.cost == (3.0 if restarts else 10.0)

"""The augmented model (design.md 9.1, 9.3): output Jacobians, Rust/NumPy parity, recovery, named errors.

Every random number comes from ``np.random.default_rng(seed)`` with a fixed seed.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.augmented import (
    TERM_NAMES,
    TERM_SYMBOLS,
    TERM_UNITS,
    AugExperiment,
    AugParams,
    augmented_output,
    fit_augmented,
    term_unit,
)
from bouc_wen_id.errors import InsufficientDataError, InvalidParameterError, NonFiniteError
from bouc_wen_id.reference import augmented as ra
from bouc_wen_id.terms import TERMS

#: A visible value of each term for the test plant (beta, gamma, mu = 0.8, 0.2, 1.6; U ~ 1, omega ~ 1..10,
#: so w ~ 1 and udot ~ 1..10): each changes y by about 5-30 % of its range.
TERM_VALUES = {
    "offset": 0.3,
    "stiffness": 0.2,
    "viscous": 0.03,
    "inertia": 0.003,
    "coulomb": 0.15,
    "sensor_lag": 0.02,
    "asymmetry": 0.3,
    "play": 0.15,
    "pinching": 0.4,
    # The mechanical terms across the hysteretic element, on x (|A| ~ 1): tests/test_place.py.
    **{f"{k}@x": v for k, v in (("stiffness", 0.2), ("viscous", 0.03), ("inertia", 0.003), ("coulomb", 0.1))},
}
HYST = (0.8, 0.2, 1.6)
#: The terms that act on a pure sine (the distortion term needs the input's harmonics: test_distortion.py;
#: the series dashpot's loop carries the asymmetry only, not play or pinching: test_series_dashpot.py; a
#: two-term element, Dahl friction, is given as its pair: test_dahl.py).
SINE_TERMS = tuple(
    t
    for t in TERM_NAMES
    if t not in ("distortion", "series_dashpot") and not (TERMS[t].companion or TERMS[t].part_of)
)


def _fd_columns(
    terms: Sequence[str], shared: np.ndarray, p: int, gain: float, phase: float, substeps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Analytic and central-difference Jacobians (shared, own) of the Rust augmented_output."""

    def y(sh: np.ndarray, g: float, ph: float) -> np.ndarray:
        return _core.augmented_output(p, 1.3, 2.5, 0.7, list(terms), sh, g, ph, substeps)[0]

    _, js, jo = _core.augmented_output(p, 1.3, 2.5, 0.7, list(terms), shared, gain, phase, substeps)
    h = 1e-6
    fs = np.empty_like(js)
    for k in range(shared.size):
        e = np.zeros_like(shared)
        e[k] = h
        fs[:, k] = (y(shared + e, gain, phase) - y(shared - e, gain, phase)) / (2 * h)
    fo = np.column_stack(
        [
            (y(shared, gain + h, phase) - y(shared, gain - h, phase)) / (2 * h),
            (y(shared, gain, phase + h) - y(shared, gain, phase - h)) / (2 * h),
        ]
    )
    return js, fs, jo, fo


@pytest.mark.parametrize("term", SINE_TERMS)
@pytest.mark.parametrize("with_lag", [False, True])
def test_output_jacobian_matches_central_differences(term: str, with_lag: bool) -> None:
    terms = [term] if (term == "sensor_lag" or not with_lag) else [term, "sensor_lag"]
    shared = np.array([*HYST, *(TERM_VALUES[t] for t in terms)])
    for p in (32, 33):
        js, fs, jo, fo = _fd_columns(terms, shared, p, 0.9, 1.1, substeps=256)
        # Central differences with h = 1e-6 err by ~1e-10 relative (h^2 truncation, eps/h rounding). The
        # plain loop's phase column is its continuous rate, exact for the RK4 map only up to ~1e-7
        # relative at 256 substeps (|w|^mu is not smooth at w = 0; measured): 1e-6 covers both.
        for a, f in ((js, fs), (jo, fo)):
            scale = np.maximum(np.max(np.abs(a), axis=0), 1e-3)
            assert np.all(np.max(np.abs(a - f), axis=0) <= 1e-6 * scale), (term, p, np.abs(a - f).max(0))


def test_term_columns_are_what_design_91_says() -> None:
    """The term columns are the input, its derivatives, the smoothed sign and 1 (no lag)."""
    p, u, om, psi = 40, 1.3, 2.5, 0.7
    terms = ["offset", "stiffness", "viscous", "inertia", "coulomb"]
    _, js, _ = _core.augmented_output(p, u, om, psi, terms, np.array([*HYST, 0, 0, 0, 0, 0.0]), 1, 0, 4)
    th = 2 * np.pi * np.arange(p) / p + psi
    udot = -u * om * np.sin(th)
    expect = [np.ones(p), u * np.cos(th), udot, -u * om**2 * np.cos(th), np.tanh(udot / (0.01 * u * om))]
    for k, col in enumerate(expect):
        np.testing.assert_allclose(js[:, 3 + k], col, rtol=1e-13, atol=1e-13)


def _random_case(rng: np.random.Generator, terms: Sequence[str]) -> tuple[object, ...]:
    p = int(rng.integers(8, 80))
    shared = np.array(
        [rng.uniform(0.4, 1.0), rng.uniform(-0.3, 0.3), rng.uniform(1.2, 3.0)]
        + [TERM_VALUES[t] * rng.uniform(0.5, 1.5) for t in terms]
    )
    if "asymmetry" in terms:  # admissible: |delta| < beta + gamma (gamma may be negative)
        k = 3 + list(terms).index("asymmetry")
        shared[k] = min(shared[k], 0.9 * (shared[0] + shared[1]))
    return (
        p,
        rng.uniform(0.5, 2.0) * rng.choice([-1, 1]),
        rng.uniform(0.5, 10.0),
        rng.uniform(0, 2 * np.pi),
        list(terms),
        shared,
        rng.uniform(0.5, 1.5) * rng.choice([-1, 1]),
        rng.uniform(0, 2 * np.pi),
        int(rng.integers(1, 6)),
    )


@pytest.mark.parametrize("seed", range(10))
def test_output_parity_rust_numpy(seed: int) -> None:
    rng = np.random.default_rng(seed)
    terms = list(rng.permutation(SINE_TERMS)[: rng.integers(0, len(SINE_TERMS) + 1)])
    args = _random_case(rng, terms)
    r = _core.augmented_output(*args)  # type: ignore[arg-type]
    n = ra.augmented_output(*args)  # type: ignore[arg-type]
    # Same RK4 steps in the same order (steady-loop parity is ~1e-15); the sensor lag goes through two
    # different FFTs (rustfft, pocketfft), each exact to ~P eps: 1e-12 relative to the column's size.
    for a, b in zip(r, n):
        assert a.shape == b.shape
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(1.0, float(np.max(np.abs(b)))))


def _make_data(
    terms: Sequence[str],
    values: Sequence[float],
    *,
    seed: int,
    freqs: Sequence[float] = (1.0, 2.5, 5.0, 9.0),
    amps: Sequence[float] = (0.8, 1.6),
    p: int = 64,
    sigma: float = 2e-3,
    n_avg: int = 20,
) -> tuple[list[AugExperiment], AugParams]:
    """Experiments made by the augmented model itself plus seeded white noise of the average's size."""
    rng = np.random.default_rng(seed)
    exps = []
    gains, phases = [], []
    for om in freqs:
        for u in amps:
            g = 1.0 / np.sqrt(1.0 + (om / 4.0) ** 2)
            ph = float(np.arctan(om / 4.0))
            psi = float(rng.uniform(0, 2 * np.pi))
            y, _, _ = _core.augmented_output(
                p, u, om, psi, list(terms), np.array([*HYST, *values]), g, ph, 32
            )
            noisy = y + sigma / np.sqrt(n_avg) * rng.standard_normal(p)
            exps.append(AugExperiment(noisy, u, om, psi, n_avg / sigma**2, source=f"{om} rad/s, U={u}"))
            gains.append(g)
            phases.append(ph)
    truth = AugParams(*HYST, tuple(terms), np.array(values, dtype=float), np.array(gains), np.array(phases))
    return exps, truth


@pytest.mark.parametrize("term", SINE_TERMS)
def test_each_term_alone_is_recovered(term: str) -> None:
    exps, truth = _make_data([term], [TERM_VALUES[term]], seed=TERM_NAMES.index(term))
    start = AugParams(
        0.7, 0.25, 1.8, (term,), np.array([0.5 * TERM_VALUES[term]]), truth.gains * 1.05, truth.phases + 0.03
    )
    fit = fit_augmented(exps, start, substeps=8)
    assert fit.converged
    # The data have noise of known variance and the weights are N/sigma^2: chi2 ~ sum P - n_params.
    dof = sum(e.ybar.size for e in exps) - fit.fisher.shape[0]
    assert 0.6 * dof < fit.cost < 1.5 * dof, (fit.cost, dof)
    for name in ("beta", "gamma", "mu", term):
        se = fit.standard_error(name)
        assert np.isfinite(se) and se > 0
        # Within ~4 standard errors (probability of a false alarm below 1e-4 per parameter).
        assert abs(fit.params.value(name) - truth.value(name)) < 4 * se, (name, fit.params.value(name), se)
    # The term is clearly visible in these data: far more than 4 standard errors from 0.
    assert abs(fit.params.value(term)) > 10 * fit.standard_error(term)


def test_plain_model_through_the_augmented_path_matches_refine() -> None:
    exps, truth = _make_data([], [], seed=11, freqs=(1.0, 3.0), p=48)
    start = (0.7, 0.25, 1.8, truth.gains * 1.05, truth.phases + 0.05)
    ref = _core.refine(
        [e.ybar for e in exps],
        [e.amplitude for e in exps],
        [e.weight for e in exps],
        *start,
        substeps=4,
    )
    out = _core.augmented_refine(
        [e.ybar for e in exps],
        [e.amplitude for e in exps],
        [e.frequency for e in exps],
        [e.grid_phase for e in exps],
        np.array([e.weight for e in exps]),
        [],
        np.array(start[:3]),
        start[3],
        start[4],
        substeps=4,
    )
    # One LM on the same model: the same iterates up to rounding, so the same minimiser to ~1e-12.
    params = np.concatenate([out[0], np.column_stack([out[1], out[2]]).ravel()])
    np.testing.assert_allclose(params, ref[0], rtol=1e-10, atol=1e-12)
    assert out[4] == ref[2] and out[5] == ref[3]
    np.testing.assert_allclose(out[3], ref[1], rtol=1e-10)
    np.testing.assert_allclose(out[6], ref[4], rtol=1e-9, atol=1e-9 * np.abs(ref[4]).max())


@pytest.mark.parametrize(
    ("terms", "values", "start_values"),
    [
        (("offset", "viscous", "sensor_lag"), [0.3, 0.03, 0.02], [0.2, 0.02, 0.01]),
        (("asymmetry", "play"), [0.3, 0.15], [0.1, 0.1]),
        (("pinching", "play"), [0.4, 0.15], [0.2, 0.1]),
    ],
)
def test_full_fit_parity_rust_numpy(
    terms: tuple[str, ...], values: list[float], start_values: list[float]
) -> None:
    exps, truth = _make_data(terms, values, seed=5, freqs=(1.0, 4.0), amps=(1.0,), p=32)
    start = AugParams(0.7, 0.25, 1.8, terms, np.array(start_values), truth.gains * 1.05, truth.phases)
    r = fit_augmented(exps, start, substeps=2, backend="rust")
    n = fit_augmented(exps, start, substeps=2, backend="numpy")
    # The reference solves the full damped system, the core its Schur complement: equal steps up to
    # rounding (~1e-13), which a converged LM carries to its minimiser at the cost's flatness, ~1e-9.
    # Near the minimum the relative cost decrease is at ftol = 1e-12, where the two loop solvers' rounding
    # (~1e-13; the path loops shoot differently) can add or drop a last step or two.
    assert abs(r.iterations - n.iterations) <= 3 and r.converged and n.converged
    np.testing.assert_allclose(r.params.shared, n.params.shared, rtol=1e-8)
    np.testing.assert_allclose(r.params.gains, n.params.gains, rtol=1e-8)
    np.testing.assert_allclose(r.cost, n.cost, rtol=1e-9)
    np.testing.assert_allclose(r.fisher, n.fisher, rtol=1e-6, atol=1e-8 * np.abs(n.fisher).max())
    for a, b in zip(r.outputs, n.outputs):
        np.testing.assert_allclose(a, b, atol=1e-9)


def test_augmented_output_wrapper_reproduces_the_fit_outputs() -> None:
    exps, truth = _make_data(["offset"], [0.3], seed=2, freqs=(2.0,), amps=(1.0,), p=32)
    start = AugParams(*HYST, ("offset",), np.array([0.3]), truth.gains, truth.phases)
    fit = fit_augmented(exps, start, max_iter=3, substeps=4)
    y = augmented_output(exps[0], fit.params, 0, substeps=4)
    np.testing.assert_allclose(y, fit.outputs[0], rtol=0, atol=1e-14)


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_typed_output_carries_the_core_jacobians(backend: Literal["rust", "numpy"]) -> None:
    """``jacobian=True`` hands back the core's own derivatives, keyed on the typed experiment and model."""
    exps, truth = _make_data(["viscous", "play"], [0.05, 0.04], seed=3, freqs=(1.5,), amps=(1.0,), p=32)
    e = exps[0]
    par = AugParams(*HYST, ("viscous", "play"), np.array([0.05, 0.04]), truth.gains, truth.phases)
    got = augmented_output(e, par, 0, substeps=4, jacobian=True, backend=backend)
    core: Any = _core if backend == "rust" else ra
    y, js, jo = core.augmented_output(
        32, e.amplitude, e.frequency, e.grid_phase, list(par.terms), par.shared, *truth_of(par), 4, e.waveform
    )
    np.testing.assert_array_equal(got.y, y)
    np.testing.assert_array_equal(got.jacobian, js)
    np.testing.assert_array_equal(got.own_jacobian, jo)
    assert got.jacobian.shape == (32, 5) and got.own_jacobian.shape == (32, 2)
    np.testing.assert_array_equal(augmented_output(e, par, 0, substeps=4, backend=backend), y)
    # A sub-model keeps the chosen terms in the model's own order, with their values.
    sub = par.only(["play"])
    assert sub.terms == ("play",) and sub.values.tolist() == [0.04] and par.terms == ("viscous", "play")
    with pytest.raises(InvalidParameterError, match="unknown term"):
        par.only(["spring"])
    with pytest.raises(InvalidParameterError, match="not an AugParams"):
        augmented_output(e, {"beta": 1.0}, 0)  # type: ignore[call-overload]


def truth_of(par: AugParams) -> tuple[float, float]:
    return float(par.gains[0]), float(par.phases[0])


DETERMINISM_SCRIPT = """
import numpy as np
from bouc_wen_id import _core
rng = np.random.default_rng(3)
terms = ["offset", "viscous"]
true = np.array([0.8, 0.2, 1.6, 0.3, 0.03])
ys, amps, freqs, psis = [], [], [], []
for i in range(6):
    a, om, psi = 1.0 + i % 2, 1.0 + i, float(rng.uniform(0, 6))
    y = _core.augmented_output(64, a, om, psi, terms, true, 0.9, 0.5, 4)[0]
    ys.append(y + 1e-3 * rng.standard_normal(64)); amps.append(a); freqs.append(om); psis.append(psi)
out = _core.augmented_refine(ys, amps, freqs, psis, np.full(6, 1e6), terms, true * 1.1, np.full(6, 1.0),
                             np.full(6, 0.55))
print(out[0].tobytes().hex(), out[1].tobytes().hex(), float(out[3]).hex(), out[6].tobytes().hex())
"""


def test_fit_is_bitwise_identical_for_any_thread_count() -> None:
    outs = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        run = subprocess.run(
            [sys.executable, "-c", DETERMINISM_SCRIPT], env=env, capture_output=True, text=True, check=True
        )
        outs.append(run.stdout)
    assert outs[0] == outs[1] and len(outs[0]) > 100


def test_names_symbols_and_units() -> None:
    assert TERM_NAMES == (
        "offset",
        "stiffness",
        "viscous",
        "inertia",
        "coulomb",
        "sensor_lag",
        "asymmetry",
        "play",
        "pinching",
        "distortion",
        "stiffness@x",
        "viscous@x",
        "inertia@x",
        "coulomb@x",
        "series_dashpot",
        "dahl",
        "dahl_sigma",
        "dahl@x",
        "dahl_sigma@x",
    )
    assert set(TERM_SYMBOLS) == set(TERM_UNITS) == set(TERM_NAMES)
    assert TERM_SYMBOLS["viscous"] == "c" and TERM_UNITS["viscous"] == "{y} s/{u}"
    assert term_unit("viscous", y="N", u="mm") == "N s/mm"
    with pytest.raises(InvalidParameterError, match="unknown term"):
        term_unit("damping")


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_named_errors(backend: str) -> None:
    exps, truth = _make_data(["offset"], [0.3], seed=1, freqs=(2.0,), p=16)
    good = AugParams(*HYST, ("offset",), np.array([0.3]), truth.gains, truth.phases)
    core = _core if backend == "rust" else ra
    args = (16, 1.0, 2.0, 0.0)
    with pytest.raises(InvalidParameterError, match="unknown term 'bogus'|unknown term \"bogus\""):
        core.augmented_output(*args, ["bogus"], np.array([*HYST, 0.0]), 1.0, 0.0, 4)
    with pytest.raises(InvalidParameterError, match="given twice"):
        core.augmented_output(*args, ["offset", "offset"], np.array([*HYST, 0.0, 0.0]), 1.0, 0.0, 4)
    with pytest.raises(InvalidParameterError, match="need 4"):
        core.augmented_output(*args, ["offset"], np.array(HYST), 1.0, 0.0, 4)
    with pytest.raises(InvalidParameterError, match="sensor_lag"):
        core.augmented_output(*args, ["sensor_lag"], np.array([*HYST, -0.1]), 1.0, 0.0, 4)
    with pytest.raises(InvalidParameterError, match="mu bracket"):
        fit_augmented(exps, good, mu_lo=2.0, mu_hi=1.5, backend=backend)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="mu bracket"):
        fit_augmented(exps, good, mu_lo=float("nan"), backend=backend)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="gains"):
        fit_augmented(exps[:1], good, backend=backend)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="starting point"):
        fit_augmented(
            exps,
            AugParams(0.1, 0.5, 1.6, ("offset",), np.array([0.3]), truth.gains, truth.phases),
            backend=backend,  # type: ignore[arg-type]
        )
    with pytest.raises(InvalidParameterError, match="experiments but"):
        core.augmented_refine(
            [e.ybar for e in exps],
            [1.0],
            [2.0, 2.0],
            [0.0, 0.0],
            np.ones(2),
            [],
            np.array(HYST),
            [1, 1],
            [0, 0],
        )


def test_typed_api_errors_and_immutability() -> None:
    y = np.sin(np.linspace(0, 6, 16))
    e = AugExperiment(y, 1.0, 2.0, 0.0, 10.0)
    y[0] = 99.0
    assert e.ybar[0] != 99.0 and not e.ybar.flags.writeable
    with pytest.raises(NonFiniteError):
        AugExperiment(np.array([1.0, np.nan, 0, 0]), 1.0, 2.0, 0.0, 1.0)
    with pytest.raises(InsufficientDataError):
        AugExperiment(np.zeros(3), 1.0, 2.0, 0.0, 1.0)
    with pytest.raises(InvalidParameterError, match="weight"):
        AugExperiment(y, 1.0, 2.0, 0.0, 0.0)
    p = AugParams(*HYST, (), np.array([]), np.array([1.0]), np.array([0.0]))
    q = p.with_term("viscous", 0.1).with_term("offset", 0.2)
    assert q.terms == ("viscous", "offset") and q.value("offset") == 0.2 and p.terms == ()
    assert q.names == ("beta", "gamma", "mu", "viscous", "offset")
    with pytest.raises(InvalidParameterError, match="given twice"):
        q.with_term("viscous", 0.0)
    with pytest.raises(InvalidParameterError, match="unknown term"):
        q.with_term("damper", 0.0)
    with pytest.raises(InvalidParameterError, match="not active"):
        q.value("coulomb")
    with pytest.raises(InvalidParameterError, match="2 values|values"):
        AugParams(*HYST, ("offset",), np.array([1.0, 2.0]), np.array([1.0]), np.array([0.0]))
    with pytest.raises(InvalidParameterError, match="backend"):
        fit_augmented([e], p, backend="julia")  # type: ignore[arg-type]
    with pytest.raises(InsufficientDataError):
        fit_augmented([], p)
    with pytest.raises(InvalidParameterError, match="index"):
        augmented_output(e, p, 1)


def test_singular_fisher_gives_a_nan_covariance() -> None:
    """Two terms that the data cannot tell apart: at a single frequency the inertia column uddot is
    -omega^2 times the stiffness column u, so the Fisher matrix is singular and no standard error exists."""
    exps, truth = _make_data(["stiffness"], [0.2], seed=4, freqs=(2.0,), amps=(1.0,), p=32)
    start = AugParams(*HYST, ("stiffness", "inertia"), np.array([0.2, 0.0]), truth.gains, truth.phases)
    fit = fit_augmented(exps, start, max_iter=5, substeps=4)
    assert np.all(np.isnan(fit.covariance))
    assert np.isnan(fit.standard_error("inertia"))
    # The estimate itself stays finite: the LM's damping handles the flat direction.
    assert np.all(np.isfinite(fit.params.shared))


def test_converged_is_false_when_the_iteration_cap_ends_the_search() -> None:
    exps, truth = _make_data(["viscous"], [0.03], seed=6, freqs=(1.0, 4.0), amps=(1.0,), p=32)
    start = AugParams(0.6, 0.3, 2.0, ("viscous",), np.array([0.0]), truth.gains * 1.2, truth.phases + 0.1)
    capped = fit_augmented(exps, start, max_iter=2, substeps=4)
    assert capped.iterations == 2 and not capped.converged
    full = fit_augmented(exps, start, substeps=4)
    assert full.converged and full.iterations > 2 and full.cost < capped.cost

"""The steady loop along the input path (``docs/design.md`` 9.2): Rust core vs NumPy reference, Jacobian vs
finite differences, an independent time-domain cross-check, and the named errors.

The core and the reference solve the same discrete problem (the same nodes, the same RK4 segment maps) to
the same periodicity tolerance ``|W(w_0) - w_0| <= 1e-13 w_b``, by different routes (the core: multiple
shooting, each RK4 step's sensitivities summed in reverse; the reference: single shooting, a forward
7-component RK4 state), so they differ by the shooting tolerance amplified by ``1/(1 - dW/dw_0)`` plus
rounding of about P * substeps steps.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.errors import (
    BoucWenIdError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    NotConvergedError,
    ZeroAmplitudeError,
)
from bouc_wen_id.reference.path_loop import PD_AMPLITUDE, PD_DELTA, PD_PHI, PD_PLAY
from bouc_wen_id.reference.path_loop import path_loop as ref_path_loop

TWO_PI = 2.0 * math.pi
PARAMS = ("amplitude", "beta", "gamma", "mu", "delta", "play", "phi")
# Jacobian column of each entry of PARAMS.
COLUMN = {
    "beta": 0,
    "gamma": 1,
    "mu": 2,
    "amplitude": PD_AMPLITUDE,
    "phi": PD_PHI,
    "delta": PD_DELTA,
    "play": PD_PLAY,
}


def _random_case(seed: int) -> dict[str, Any]:
    """Admissible parameters: beta > |gamma|, |delta| < beta + gamma, 0 <= b < |A|, either sign of A."""
    rng = np.random.default_rng([909, seed])
    beta = float(rng.uniform(0.3, 1.5))
    gamma = float(rng.uniform(-0.8, 1.0)) * beta
    delta = float(rng.uniform(-0.8, 0.8)) * (beta + gamma)
    mu = float(rng.uniform(1.2, 4.0))
    amplitude = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 4.0))
    play = 0.0 if seed % 4 == 0 else float(rng.uniform(0.0, 0.6)) * abs(amplitude)
    delta = 0.0 if seed % 5 == 1 else delta
    p = int(rng.integers(4, 33))
    # RK4 steps in x short enough for the loop's stiffness |dh/dw| <= mu w_b^(mu-1) (|beta| + |gamma| +
    # |delta|): beyond 2.8 / stiffness RK4 itself is unstable (the core then says so, see BAD below).
    stiffness = mu * _bound_of(beta, gamma, mu, delta) ** (mu - 1.0) * (abs(beta) + abs(gamma) + abs(delta))
    longest = abs(amplitude) * TWO_PI / p
    substeps = max(int(rng.integers(1, 5)), math.ceil(longest * stiffness / 1.5))
    return {
        "amplitude": amplitude,
        "beta": beta,
        "gamma": gamma,
        "mu": mu,
        "delta": delta,
        "play": play,
        "phi": float(rng.uniform(-2 * TWO_PI, 2 * TWO_PI)),
        "samples_per_period": p,
        "substeps": substeps,
    }


def _bound_of(beta: float, gamma: float, mu: float, delta: float) -> float:
    return float((beta + gamma - abs(delta)) ** (-1.0 / mu))


def _bound(c: dict[str, Any]) -> float:
    return _bound_of(c["beta"], c["gamma"], c["mu"], c["delta"])


@pytest.mark.parametrize("seed", range(16))
def test_rust_matches_the_numpy_reference(seed: int) -> None:
    c = _random_case(seed)
    w, jac, _ = _core.path_loop(**c)
    w_ref, jac_ref, _ = ref_path_loop(**c)
    assert w.shape == (c["samples_per_period"],) and jac.shape == (c["samples_per_period"], 7)
    # Each solve leaves |W - w_0| <= 1e-13 w_b, i.e. w_0 within 1e-13 w_b / (1 - dW/dw_0); over these
    # cases dW/dw_0 <= 0.99, so w agrees to 2e-11 w_b (measured over these seeds: <= 2e-13 w_b).
    np.testing.assert_allclose(w, w_ref, rtol=0.0, atol=2e-11 * _bound(c))
    # The Jacobian inherits the same relative offset through dJ/dw_0 = O(J / w_b), plus the different
    # summation order of the sensitivities (measured: <= 2e-12 relative).
    scale = 1.0 + np.abs(jac_ref)
    assert np.max(np.abs(jac - jac_ref) / scale) < 2e-9


@pytest.mark.parametrize("seed", [2, 3, 7])
def test_jacobian_matches_central_differences(seed: int) -> None:
    c = _random_case(seed)
    c["samples_per_period"], c["substeps"] = 24, 3
    _, jac, _ = _core.path_loop(**c)
    for name in PARAMS:
        h = 1e-5 * max(1.0, abs(c[name]))
        up, dn = dict(c), dict(c)
        up[name] += h
        dn[name] -= h
        fd = (_core.path_loop(**up)[0] - _core.path_loop(**dn)[0]) / (2.0 * h)
        # Central differences of the same discrete map: truncation h^2 w''' ~ 1e-10 and the shooting
        # tolerance 1e-13 w_b / (1 - dW/dw_0) / (2h) ~ 1e-7 at worst (measured: 5e-8); a wrong chain-rule
        # term is O(1).
        np.testing.assert_allclose(jac[:, COLUMN[name]], fd, rtol=0.0, atol=1e-6 * (1.0 + np.max(np.abs(fd))))


def _time_domain(
    c: dict[str, float], p: int, steps_per_sample: int, periods: int, averaged: int
) -> np.ndarray:
    """Generalised Bouc-Wen behind a play, integrated in time from rest, sample-wise mean of the last periods.

    x(t) = A cos(omega t - phi) on a fine grid; the play is the discrete play operator
    ``xp_k = clip(xp_{k-1}, x_k - b, x_k + b)`` (exact for an input monotone between grid points, apart from
    the step in which a dwell starts or ends); w by RK4 in time with ``xpdot`` constant over each step
    and the rate ``xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))]`` written out directly.
    Nothing of the path loop's nodes, play formula, top/bottom bookkeeping or shooting is used.
    """
    n = p * steps_per_sample
    a, beta, gamma, mu, delta, b, phi = (float(c[k]) for k in PARAMS)
    k = np.arange(n * periods + 1)
    x = a * np.cos(TWO_PI * k / n - phi)
    xp = np.empty_like(x)
    xp[0] = float(np.clip(0.0, x[0] - b, x[0] + b))
    for i in range(1, len(x)):
        xp[i] = min(max(xp[i - 1], x[i] - b), x[i] + b)

    def rate(w: float, v: float) -> float:
        # v = xpdot * dt.
        return float(v * (1.0 - abs(w) ** mu * (beta * np.sign(v * w) + gamma + delta * np.sign(w))))

    w = np.empty(len(x))
    w[0] = 0.0
    dxp = np.diff(xp)
    for i, v in enumerate(dxp):
        wi = w[i]
        k1 = rate(wi, v)
        k2 = rate(wi + 0.5 * k1, v)
        k3 = rate(wi + 0.5 * k2, v)
        k4 = rate(wi + k3, v)
        w[i + 1] = wi + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
    # The samples t_j = j T / P of the last `averaged` periods.
    last = w[n * (periods - averaged) : n * periods : steps_per_sample].reshape(averaged, p)
    return np.asarray(last.mean(axis=0))


@pytest.mark.parametrize(
    "case",
    [
        # asymmetry and play together, A > 0
        {"amplitude": 2.0, "beta": 0.8, "gamma": 0.2, "mu": 2.0, "delta": 0.35, "play": 0.3, "phi": 0.7},
        # A < 0, negative asymmetry, mu < 2, a wide play
        {"amplitude": -1.6, "beta": 0.6, "gamma": 0.3, "mu": 1.5, "delta": -0.4, "play": 0.5, "phi": -2.2},
    ],
)
def test_matches_a_long_time_domain_integration(case: dict[str, float]) -> None:
    p = 32
    td = _time_domain(case, p, steps_per_sample=48, periods=12, averaged=2)
    w, _, _ = _core.path_loop(**case, samples_per_period=p, substeps=16)
    # The time-domain side is the least accurate: a dwell starts or ends inside one fine step, where the
    # discrete play puts the kink of xp up to one step (2 pi A / 1536 in x) off, an O(step^2) error in w;
    # the transient from rest has decayed below 1e-11 after 10 periods (12 vs 10 periods: 9e-12).
    # Measured: 4e-7 w_b; tolerance 2e-6 w_b, while dropping the asymmetry or the play moves w by > 0.1 w_b.
    tol = 2e-6 * _bound(case)
    np.testing.assert_allclose(w, td, rtol=0.0, atol=tol)
    # The check discriminates: without the asymmetry, or without the play, the loop is far off.
    for change in ({"delta": 0.0}, {"play": 0.0}):
        other, _, _ = _core.path_loop(**{**case, **change}, samples_per_period=p, substeps=16)
        assert np.max(np.abs(other - td)) > 100 * tol


GOOD: dict[str, Any] = {
    "amplitude": 1.0,
    "beta": 0.5,
    "gamma": 0.2,
    "mu": 1.5,
    "delta": 0.1,
    "play": 0.1,
    "phi": 0.0,
    "samples_per_period": 16,
    "substeps": 2,
}

BAD: list[tuple[str, dict[str, Any], type[Exception]]] = [
    *[(f"{name}_nan", {name: math.nan}, NonFiniteError) for name in PARAMS],
    *[(f"{name}_inf", {name: -math.inf}, NonFiniteError) for name in PARAMS],
    ("mu_one", {"mu": 1.0}, InvalidParameterError),
    ("unbounded_side", {"delta": 0.7}, InvalidParameterError),
    ("unbounded_negative_side", {"delta": -0.75}, InvalidParameterError),
    ("negative_play", {"play": -0.01}, InvalidParameterError),
    ("zero_substeps", {"substeps": 0}, InvalidParameterError),
    ("bound_overflows", {"beta": 5e-324, "gamma": 0.0, "delta": 0.0, "mu": 3.0}, InvalidParameterError),
    ("zero_amplitude", {"amplitude": 0.0}, ZeroAmplitudeError),
    ("play_equals_amplitude", {"play": 1.0}, ZeroAmplitudeError),
    ("play_beyond_negative_amplitude", {"amplitude": -0.5, "play": 0.6}, ZeroAmplitudeError),
    ("three_samples", {"samples_per_period": 3}, InsufficientDataError),
    # beta < 0 (with beta + gamma > 0): the unloading branch runs away at a large amplitude.
    (
        "runaway",
        {"amplitude": 20.0, "beta": -0.4, "gamma": 1.0, "delta": 0.0, "play": 0.0},
        NotConvergedError,
    ),
    # A stiff loop on RK4 steps far beyond its stability limit.
    (
        "rk4_unstable",
        {
            "amplitude": 30.0,
            "beta": 1.26,
            "gamma": 0.78,
            "mu": 2.14,
            "delta": 1.54,
            "play": 0.8,
            "substeps": 1,
        },
        NotConvergedError,
    ),
]


@pytest.mark.parametrize("label, change, error", BAD, ids=[b[0] for b in BAD])
def test_both_backends_raise_the_same_named_error(
    label: str, change: dict[str, Any], error: type[Exception]
) -> None:
    args = {**GOOD, **change}
    with pytest.raises(error):
        _core.path_loop(**args)
    with pytest.raises(error):
        ref_path_loop(**args)


def test_oversized_grid_is_refused_before_any_work() -> None:
    # The binding's work budget refuses it first (BudgetExceededError); the loop's own limits stand behind.
    with pytest.raises(InvalidParameterError, match="budget exceeded|exceeds the limits"):
        _core.path_loop(**{**GOOD, "samples_per_period": 1 << 20, "substeps": 1 << 20})
    with pytest.raises(InvalidParameterError):
        _core.path_loop(**{**GOOD, "samples_per_period": -5})


def test_extreme_inputs_give_a_finite_loop_or_a_named_error() -> None:
    """Admissible cases with one or two parameters set across the float range: finite, or a named error."""
    rng = np.random.default_rng(4242)
    values = [0.0, 5e-324, 1e-300, 1e-12, 0.5, 1.0, 1.0000001, 3.0, 50.0, 1e6, 1e300, 1.7e308, -1e-300, -0.5]
    outcomes = {"ok": 0, "error": 0}
    for i in range(400):
        c = _random_case(i)
        c["samples_per_period"] = min(c["samples_per_period"], 12)
        for name in rng.choice(PARAMS, size=int(rng.integers(1, 3)), replace=False):
            c[str(name)] = float(rng.choice(values)) * float(rng.choice([1.0, -1.0, 1.37]))
        try:
            w, jac, _ = _core.path_loop(**c)
        except BoucWenIdError:
            outcomes["error"] += 1
            continue
        outcomes["ok"] += 1
        assert np.all(np.isfinite(w)) and np.all(np.isfinite(jac)), c
    assert outcomes["ok"] > 40 and outcomes["error"] > 40, outcomes

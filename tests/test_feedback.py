"""Bouc-Wen in feedback (issue #20): the Rust simulator against its NumPy oracle and an independent
integrator, its Jacobian against finite differences, the band-limited input, the fit, and the named errors."""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id._backend import feedback_part
from bouc_wen_id.errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    TimeAxisError,
)
from bouc_wen_id.timedomain import FeedbackModel, TimeRecord, fit_feedback, upsample_input

BENCH = np.array([2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0])
FS = 750.0


def _random_case(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    theta = BENCH * rng.uniform(0.7, 1.3, size=7)
    theta[6] = rng.uniform(1.0, 2.0)
    theta[4:6] /= 60.0 ** (theta[6] - 1.0)  # keep |z|^nu terms of the benchmark's size for nu > 1
    x0 = rng.normal(size=3) * np.array([1e-4, 1e-2, 5.0])
    u = rng.normal(scale=40.0, size=n)
    return theta, x0, u


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("upsample", [1, 3])
def test_rust_matches_the_numpy_oracle_on_random_inputs(seed: int, upsample: int) -> None:
    rng = np.random.default_rng(seed)
    theta, x0, u = _random_case(rng, 3 * 12 + 1)
    dt = 1.0 / FS
    out = {
        name: feedback_part(name).feedback_simulate(theta, x0, u, dt, upsample, 3, True)
        for name in ("rust", "numpy")
    }
    (y_r, j_r, s_r), (y_n, j_n, s_n) = out["rust"], out["numpy"]
    assert y_r.shape == ((u.size - 1) // upsample + 1,) and j_r.shape == (y_r.size, 10)
    np.testing.assert_allclose(y_r, y_n, rtol=1e-10, atol=1e-12 * np.max(np.abs(y_n)))
    for j in range(10):
        scale = np.max(np.abs(j_n[:, j])) + 1e-300
        np.testing.assert_allclose(j_r[:, j], j_n[:, j], rtol=0, atol=1e-9 * scale, err_msg=f"column {j}")
    np.testing.assert_allclose(s_r, s_n, rtol=1e-10, atol=1e-12)


def test_jacobian_matches_finite_differences() -> None:
    rng = np.random.default_rng(7)
    theta, x0, u = _random_case(rng, 120)
    part = feedback_part("rust")
    y, jac, _ = part.feedback_simulate(theta, x0, u, 1 / FS, 1, 8, True)
    p = np.concatenate([theta, x0])
    for j in range(10):
        step = 1e-6 * max(abs(p[j]), 1e-3)
        hi, lo = p.copy(), p.copy()
        hi[j] += step
        lo[j] -= step
        fd = (
            part.feedback_simulate(hi[:7], hi[7:], u, 1 / FS, 1, 8, False)[0]
            - part.feedback_simulate(lo[:7], lo[7:], u, 1 / FS, 1, 8, False)[0]
        ) / (2 * step)
        scale = np.max(np.abs(jac[:, j]))
        assert scale > 0
        assert np.max(np.abs(fd - jac[:, j])) < 1e-5 * scale, f"column {j}"
    # Without sensitivities the same output and an empty Jacobian.
    y2, j2, _ = part.feedback_simulate(theta, x0, u, 1 / FS, 1, 8, False)
    np.testing.assert_array_equal(y, y2)
    assert j2.shape == (y.size, 0)


def test_simulation_matches_an_independent_adaptive_integrator() -> None:
    """scipy's DOP853 on the analytic input against the RK4 on samples (band-limited reconstruction)."""
    from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

    m, c, k, alpha, bg, bd, nu = BENCH

    def force(t: float) -> float:
        return 45.0 * math.sin(2 * math.pi * 31.0 * t) + 20.0 * math.sin(2 * math.pi * 74.0 * t + 1.0)

    def rhs(t: float, x: np.ndarray) -> list[float]:
        y, v, z = x
        az = abs(z) ** nu
        return [
            v,
            (force(t) - c * v - k * y - z) / m,
            alpha * v - bg * abs(v) * math.copysign(az, z) - bd * v * az,
        ]

    n = 400
    t = np.arange(n) / FS
    ref = solve_ivp(
        rhs, (0, t[-1]), [0.0, 0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-11, atol=1e-14, max_step=2e-4
    )
    u_fine = np.array([force(tt) for tt in np.arange((n - 1) * 8 + 1) / (8 * FS)])
    scale = np.max(np.abs(ref.y[0]))
    assert scale > 1e-4
    errors = []
    for substeps in (20, 40):
        y, _, _ = feedback_part("rust").feedback_simulate(
            BENCH, [0, 0, 0], u_fine, 1 / FS, 8, substeps, False
        )
        errors.append(np.max(np.abs(y - ref.y[0])) / scale)
    # RK4 at 15 kHz is within 5e-5 of the adaptive solution, and converges to it (the |yd| kink makes the
    # order about 2 instead of 4: measured 2.0e-5 -> 3.9e-6 when the step halves).
    assert errors[0] < 5e-5
    assert errors[1] < errors[0] / 3.0


def test_periodic_upsampling_is_exact_for_a_multisine() -> None:
    n, factor = 256, 5
    t_fine = np.arange((n - 1) * factor + 1) / (FS * factor)
    freqs = np.array([3, 17, 60, 101]) * FS / n

    def signal(tt: np.ndarray) -> np.ndarray:
        out: np.ndarray = np.sum(
            np.sin(2 * np.pi * freqs[:, None] * tt[None, :] + np.arange(4)[:, None]), axis=0
        )
        return out

    fine = upsample_input(signal(np.arange(n) / FS), factor, periodic=True)
    np.testing.assert_allclose(fine, signal(t_fine), atol=1e-10)
    # A non-periodic record: the polyphase filter, exact away from the end for content well below Nyquist.
    slow = np.sin(2 * np.pi * 20.0 * np.arange(n) / FS)
    fine = upsample_input(slow, factor)
    ok = slice(20 * factor, (n - 20) * factor)
    np.testing.assert_allclose(fine[ok], np.sin(2 * np.pi * 20.0 * t_fine[ok]), atol=2e-4)


def _independent_rk4(
    theta: np.ndarray, u_half: np.ndarray, h: float, keep: int, x0: np.ndarray
) -> np.ndarray:
    """A plain-Python RK4 (different code from the library's) on the input at every half step."""
    m, c, k, alpha, bg, bd, nu = theta

    def f(x: np.ndarray, u: float) -> np.ndarray:
        az = abs(x[2]) ** nu
        return np.array(
            [
                x[1],
                (u - c * x[1] - k * x[0] - x[2]) / m,
                alpha * x[1] - bg * abs(x[1]) * math.copysign(az, x[2]) - bd * x[1] * az,
            ]
        )

    x = np.array(x0, dtype=float)
    out = [x[0]]
    for i in range((u_half.size - 1) // 2):
        k1 = f(x, u_half[2 * i])
        k2 = f(x + 0.5 * h * k1, u_half[2 * i + 1])
        k3 = f(x + 0.5 * h * k2, u_half[2 * i + 1])
        k4 = f(x + h * k3, u_half[2 * i + 2])
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (i + 1) % keep == 0:
            out.append(x[0])
    return np.array(out)


def _multisine_data(seed: int, n: int, sub: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    spec = np.zeros(n // 2 + 1, dtype=complex)
    band = (np.arange(n // 2 + 1) * FS / n >= 5) & (np.arange(n // 2 + 1) * FS / n <= 150)
    spec[band] = np.exp(2j * np.pi * rng.uniform(size=int(band.sum())))
    one = np.fft.irfft(spec, n * 2 * sub) * 2 * sub
    one *= 50.0 / np.sqrt(np.mean(one**2))
    u_half = np.concatenate([one, one[:1]])
    y = _independent_rk4(BENCH, u_half, 1 / (FS * sub), sub, np.zeros(3))[:n]
    return u_half[: n * 2 * sub : 2 * sub], y


def test_fit_recovers_the_benchmark_parameters_within_their_intervals() -> None:
    n, noise = 1024, 8e-6
    u, y = _multisine_data(11, n, 8)
    rng = np.random.default_rng(12)
    rec = TimeRecord(np.arange(n) / FS, u, y + noise * rng.standard_normal(n))
    fit = fit_feedback(rec, beta=1e3, starts=4, seed=3, upsample=4, periodic=True, substeps=8)
    assert fit.names == ("m", "c", "k", "alpha", "beta_gamma", "beta_delta", "nu")
    assert fit.rmse[0] < 1.3 * noise
    for name, truth in zip(fit.names, BENCH):
        i = fit.names.index(name)
        assert abs(fit.estimates[i] - truth) < 4.0 * fit.standard_errors[i], name
        assert fit.standard_errors[i] < 0.2 * abs(truth), name
    form = fit.benchmark_form()
    assert abs(form["gamma"][0] - 0.8) < 4 * form["gamma"][1]
    assert abs(form["delta"][0] + 1.1) < 4 * form["delta"][1]
    assert np.all(np.abs(fit.correlation[np.triu_indices(7, 1)]) < 0.9999)
    lo, hi = fit.interval("m")
    assert lo < fit.model.m < hi
    with pytest.raises(InvalidParameterError):
        fit.interval("beta")


def test_fit_estimates_the_initial_state_of_a_record_cut_mid_motion() -> None:
    n, sub = 2048, 8
    u, y = _multisine_data(21, n, sub)
    cut = 300
    rec = TimeRecord(np.arange(n - cut) / FS, u[cut:], y[cut:])
    # A start a few per cent off in every direction (from BENCH * 1.02 this record has a local minimum with
    # beta*gamma, beta*delta 8 % low and c 3.5 % high, rmse 1.3e-6: the multi-start's business).
    start = BENCH * np.array([0.97, 1.1, 1.03, 0.98, 1.05, 0.95, 1.0])
    fit = fit_feedback(
        rec, theta0=start, fixed=("nu",), initial_state="estimate", starts=1, upsample=4, substeps=8
    )
    assert fit.names[-3:] == ("y0[0]", "yd0[0]", "z0[0]")
    assert abs(fit.x0[0][0] - y[cut]) < 1e-3 * np.max(np.abs(y))
    assert fit.rmse[0] < 1e-4 * np.max(np.abs(y))
    # From rest the same record cannot be matched: the estimated state matters.
    rest = fit_feedback(rec, theta0=start, fixed=("nu",), starts=1, upsample=4, substeps=8, max_iter=5)
    assert rest.rmse[0] > 10 * fit.rmse[0]


def test_rust_and_numpy_backends_give_the_same_fit() -> None:
    n = 160
    u, y = _multisine_data(5, n, 4)
    rec = TimeRecord(np.arange(n) / FS, u, y)
    fits = [
        fit_feedback(rec, theta0=BENCH * 1.05, fixed=("nu",), starts=1, substeps=2, max_iter=8, backend=b)
        for b in ("rust", "numpy")
    ]
    np.testing.assert_allclose(fits[0].estimates, fits[1].estimates, rtol=1e-7)


def test_beta_is_a_normalisation_not_a_parameter() -> None:
    a = FeedbackModel.from_benchmark(2, 10, 5e4, 5e4, 1e3, 0.8, -1.1, 1.0)
    b = FeedbackModel.from_benchmark(2, 10, 5e4, 5e4, 2.5e3, 0.8 / 2.5, -1.1 / 2.5, 1.0)
    u = np.random.default_rng(0).normal(scale=30, size=200)
    np.testing.assert_allclose(a.simulate(u, 1 / FS), b.simulate(u, 1 / FS), rtol=1e-12, atol=1e-18)
    assert a.gamma == pytest.approx(0.8) and b.gamma == pytest.approx(0.32)


def test_bad_input_is_named() -> None:
    part = feedback_part("rust")
    u = np.ones(20)
    with pytest.raises(NonFiniteError):
        part.feedback_simulate(BENCH, [0, 0, 0], np.array([1.0, np.nan, 2.0]), 1 / FS, 1, 4, True)
    with pytest.raises(InvalidParameterError, match="m = "):
        part.feedback_simulate([0, 10, 1, 1, 1, 1, 1], [0, 0, 0], u, 1 / FS, 1, 4, True)
    with pytest.raises(InvalidParameterError):
        part.feedback_simulate(BENCH[:6], [0, 0, 0], u, 1 / FS, 1, 4, True)
    with pytest.raises(InvalidParameterError):
        part.feedback_simulate(BENCH, [0, 0], u, 1 / FS, 1, 4, True)
    with pytest.raises(InsufficientDataError):
        part.feedback_simulate(BENCH, [0, 0, 0], np.ones(1), 1 / FS, 1, 4, True)
    with pytest.raises(InvalidParameterError):
        part.feedback_simulate(BENCH, [0, 0, 0], u, -1.0, 1, 4, True)
    t = np.arange(40) / FS
    with pytest.raises(TimeAxisError):
        fit_feedback((t[::-1], np.ones(40), np.ones(40)), theta0=BENCH)
    with pytest.raises(InsufficientDataError):
        fit_feedback((t, np.ones(40), np.ones(40)), theta0=BENCH, lead_in=0.045)
    with pytest.raises(InvalidParameterError, match="fixed"):
        fit_feedback((t, np.ones(40), np.ones(40)), theta0=BENCH, fixed=("beta",))
    with pytest.raises(InvalidParameterError, match="initial_state"):
        fit_feedback((t, np.ones(40), np.ones(40)), theta0=BENCH, initial_state="guess")  # type: ignore[arg-type]
    # Public entry points.
    assert bw.fit_feedback is fit_feedback


def test_validate_takes_the_feedback_structure() -> None:
    # bw.validate simulates "either structure" (issue 20 item 3): the model and the fit, on a fresh record.
    n = 1024
    u, y = _multisine_data(21, n, 8)
    t = np.arange(n) / FS
    truth = FeedbackModel.from_theta(BENCH, beta=1e3)
    rep = bw.validate(truth, t, u, y)
    assert rep.model == "FeedbackModel" and rep.nrmse < 0.02
    wrong = FeedbackModel.from_theta(BENCH * np.array([1, 1, 1.3, 1, 1, 1, 1]), beta=1e3)  # k 30 % off
    assert bw.validate(wrong, t, u, y).nrmse > 5 * rep.nrmse
    with pytest.raises(InvalidParameterError):
        truth.simulate_record(t[:1], u[:1])

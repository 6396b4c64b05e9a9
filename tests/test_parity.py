"""Parity of the Rust core (``bouc_wen_id._core``) with the NumPy reference (``bouc_wen_id.reference``).

Both follow docs/design.md operation by operation, so on the same seeded random inputs they may differ
only by rounding: the order of a few summations (dot products of length <= 5, sums over one period, the
direct DFT of the Rust derivative against NumPy's FFT) and the last bit of libm's sin/cos/pow.  The
tolerances below are stated per routine with the measured discrepancy they cover.

Also here: both backends raise the *same named error* for the same bad input, neither modifies its input
arrays, and the Rust core refuses non-contiguous arrays with a ValueError instead of crashing.
"""

from __future__ import annotations

import math
import typing
from typing import Any, Callable

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id._backend import current_lab, get_backend, selected
from bouc_wen_id.demo import design_amplitudes
from bouc_wen_id.errors import (
    ImproperTransferFunctionError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    SearchAtBoundError,
    SingularNormalMatrixError,
    UnstableSystemError,
    ZeroAmplitudeError,
)
from bouc_wen_id.identification import Method
from numpy.testing import assert_allclose

SEEDS = (0, 1, 2)


def _scale(a: np.ndarray) -> float:
    return float(np.max(np.abs(a)))


# --------------------------------------------------------------------------------------------------
# 1. Simulation
# --------------------------------------------------------------------------------------------------


def _random_simulation_case(helpers: Any, order: int, seed: int) -> dict[str, Any]:
    rng = np.random.default_rng([101, order, seed])
    num, den, tau = helpers.random_tf(rng, order)
    if seed == 0:
        tau = 0.0  # always cover the undelayed case
    alpha, beta, gamma, mu, w0 = helpers.random_bouc_wen(rng)
    omega = float(rng.uniform(0.5, 8.0))
    dt = 2.0 * math.pi / omega / int(rng.integers(16, 64))
    if seed == 1:
        tau = 7 * dt  # a delay on the step grid: the "t - tau < 0" test sits exactly on stage times
    return {
        "num": num,
        "den": den,
        "delay": tau,
        "alpha": alpha,
        "beta": beta,
        "gamma": gamma,
        "mu": mu,
        "w0": w0,
        "omega": omega,
        "dt": dt,
        "amplitude": float(rng.uniform(0.2, 3.0) * rng.choice([-1.0, 1.0])),
        "n_samples": int(rng.integers(200, 400)),
        "substeps": int(rng.integers(1, 4)),
    }


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("order", range(5))
def test_simulate_sine_parity(helpers: Any, order: int, seed: int) -> None:
    c = _random_simulation_case(helpers, order, seed)
    args = (c["num"], c["den"], c["delay"], c["alpha"], c["beta"], c["gamma"], c["mu"], c["w0"])
    tail = (c["amplitude"], c["omega"], c["dt"], c["n_samples"], c["substeps"])
    xr, wr = _core.simulate_sine(*args, *tail)
    xn, wn = reference.simulate_sine(*args, *tail)
    assert xr.shape == xn.shape == (c["n_samples"],)
    assert wr.shape == wn.shape == (c["n_samples"],)
    # Same RK4 stages in the same order; only the 1-5 term dot products and libm's cos/sin/pow may round
    # differently.  Measured: <= 3e-15 of the signal's peak over <= 1200 steps (the stable linear part
    # and the dissipative Bouc-Wen element do not amplify rounding).  1e-11 of the peak leaves a
    # 3000x margin and still catches any difference of method (a wrong stage time, delay or sign).
    assert_allclose(xr, xn, rtol=1e-11, atol=1e-11 * _scale(xn))
    assert_allclose(wr, wn, rtol=1e-11, atol=1e-11 * _scale(wn))
    # The simulation actually did something (a stub returning zeros would not pass the line above
    # against the reference, but make the intent explicit).
    assert _scale(wn) > 0.0 and _scale(xn) > 0.0


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("order", range(5))
def test_simulate_sampled_parity(helpers: Any, order: int, seed: int) -> None:
    c = _random_simulation_case(helpers, order, seed)
    rng = np.random.default_rng([102, order, seed])
    n = c["n_samples"]
    t = np.arange(n) * c["dt"]
    # A smooth input plus sample noise: the Catmull-Rom slopes and the hold after the end all matter.
    u = c["amplitude"] * np.cos(c["omega"] * t) + 0.1 * rng.standard_normal(n)
    # A constant stretch at the end: zero Catmull-Rom slopes inside, one-sided slope at the very end.
    u[-20:] = u[-21]
    args = (c["num"], c["den"], c["delay"], c["alpha"], c["beta"], c["gamma"], c["mu"], c["w0"])
    xr, wr = _core.simulate_sampled(*args, u, c["dt"], c["substeps"])
    xn, wn = reference.simulate_sampled(*args, u, c["dt"], c["substeps"])
    assert xr.shape == xn.shape == (n,)
    # As for the sine input; the Hermite interpolant adds a few more roundings per stage, same size.
    assert_allclose(xr, xn, rtol=1e-11, atol=1e-11 * _scale(xn))
    assert_allclose(wr, wn, rtol=1e-11, atol=1e-11 * _scale(wn))


def test_simulate_sampled_of_a_cosine_tracks_simulate_sine() -> None:
    """The sampled input interpolates a cosine to O(dt^3): its response follows the sine response."""
    omega, p = 2.0, 200
    dt = 2 * math.pi / omega / p
    t = np.arange(3 * p) * dt
    args = ([2.0, 1.0], [1.0, 3.0, 4.0], 0.1, 1.0, 0.7, 0.1, 1.8, 0.0)
    xs, ws = _core.simulate_sine(*args, 1.3, omega, dt, t.size, 2)
    xh, wh = _core.simulate_sampled(*args, 1.3 * np.cos(omega * t), dt, 2)
    # Catmull-Rom interpolation error of cos on a 200-per-period grid: ~ (omega dt)^3/... ~ 1e-6 of U;
    # 1e-4 of the peak allows for the end effects (one-sided slopes) without hiding a wrong interpolant.
    assert_allclose(xh[: -p // 2], xs[: -p // 2], atol=1e-4 * _scale(xs))
    assert_allclose(wh[: -p // 2], ws[: -p // 2], atol=1e-4 * _scale(ws))


# --------------------------------------------------------------------------------------------------
# 2-4. Averaging, phase, derivative
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize(
    ("p", "settle", "periods", "extra"), [(4, 0, 1, 0), (7, 2, 3, 5), (64, 3, 10, 63), (1000, 1, 7, 1)]
)
def test_periodic_average_parity(p: int, settle: int, periods: int, extra: int, seed: int) -> None:
    rng = np.random.default_rng([103, p, seed])
    y = rng.normal(0.3, 2.0, (settle + periods) * p + extra)
    yr = _core.periodic_average(y, p, settle, periods)
    yn = reference.periodic_average(y, p, settle, periods)
    # A sum of `periods` numbers then one division: the only freedom is the summation order.  Measured
    # difference <= 1 ulp; 1e-13 relative to the data scale covers any order.
    assert yr.shape == (p,)
    assert_allclose(yr, yn, rtol=1e-13, atol=1e-13 * _scale(y))
    # And it is the average the design states (independent of both implementations).
    expected = y[settle * p : (settle + periods) * p].reshape(periods, p).sum(axis=0) / periods
    assert_allclose(yr, expected, rtol=1e-13, atol=1e-13 * _scale(y))


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("p", [4, 5, 64, 1023])
def test_phase_from_max_parity(p: int, seed: int) -> None:
    rng = np.random.default_rng([104, p, seed])
    ybar = rng.standard_normal(p)
    j = int(np.argmax(ybar))
    # An index, so the two must agree exactly.
    assert _core.phase_from_max(ybar) == reference.phase_from_max(ybar) == 2 * math.pi * j / p
    # Ties: the first maximum wins in both.
    ybar[(j + p // 2) % p] = ybar[j]
    first = min(j, (j + p // 2) % p)
    assert _core.phase_from_max(ybar) == reference.phase_from_max(ybar) == 2 * math.pi * first / p


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("p", [8, 9, 64, 255, 1024])
def test_spectral_derivative_parity(p: int, seed: int) -> None:
    rng = np.random.default_rng([105, p, seed])
    ybar = rng.standard_normal(p) * rng.uniform(0.1, 10.0)
    omega = float(rng.uniform(0.1, 50.0))
    for k in (1, int(rng.integers(1, (p - 1) // 2 + 1)), (p - 1) // 2):
        dr = _core.spectral_derivative(ybar, omega, k)
        dn = reference.spectral_derivative(ybar, omega, k)
        # Rust: direct DFT of K harmonics; NumPy: FFT.  Each harmonic's coefficient carries ~P eps |y|
        # of rounding and is multiplied by k omega <= K omega.  Measured <= 1.5e-15 * K omega max|y|;
        # allow 1e-12 of that scale.
        assert_allclose(dr, dn, rtol=0, atol=1e-12 * k * omega * _scale(ybar))


def test_spectral_derivative_is_exact_on_trigonometric_polynomials(core: Any) -> None:
    p, omega = 32, 3.0
    t = np.arange(p) * (2 * math.pi / omega / p)
    y = 0.5 + np.cos(omega * t - 0.3) + 0.25 * np.sin(5 * omega * t)
    dy = -omega * np.sin(omega * t - 0.3) + 1.25 * omega * np.cos(5 * omega * t)
    # Harmonics 1..5 reproduce the derivative exactly (up to rounding of an FFT/DFT of 32 points).
    assert_allclose(core.spectral_derivative(y, omega, 5), dy, atol=1e-12)
    # Truncating to K = 4 drops the 5th harmonic entirely: what remains is the first one's derivative.
    assert_allclose(core.spectral_derivative(y, omega, 4), -omega * np.sin(omega * t - 0.3), atol=1e-12)


# --------------------------------------------------------------------------------------------------
# 5. Separable least squares
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("p", [4, 33, 256])
def test_sls_regressor_parity(p: int, seed: int) -> None:
    rng = np.random.default_rng([106, p, seed])
    ybar, ydot = rng.standard_normal(p), rng.standard_normal(p)
    amp = float(rng.uniform(0.2, 3.0) * rng.choice([-1.0, 1.0]))
    omega, phi, nu = float(rng.uniform(0.5, 10)), float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(1, 5))
    pr = _core.sls_regressor(ybar, ydot, amp, omega, phi, nu)
    pn = reference.sls_regressor(ybar, ydot, amp, omega, phi, nu)
    assert pr.shape == pn.shape == (p, 3)
    # Elementwise products of sin and pow: a few ulps each.
    assert_allclose(pr, pn, rtol=1e-13, atol=1e-14 * _scale(pn))


def _random_spd(rng: np.random.Generator, log_cond: float) -> np.ndarray:
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    lam = np.array([1.0, 10 ** (-log_cond * rng.uniform(0.2, 0.8)), 10.0**-log_cond])
    s = q @ np.diag(lam) @ q.T
    d = 10.0 ** rng.uniform(-3, 3, 3)  # badly scaled columns: what the Jacobi scaling is for
    m = d[:, None] * s * d[None, :]
    out: np.ndarray = 0.5 * (m + m.T)
    return out


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("log_cond", [0.0, 3.0, 6.0, 9.0])
def test_solve_normal_parity(log_cond: float, seed: int) -> None:
    rng = np.random.default_rng([107, int(log_cond), seed])
    m = _random_spd(rng, log_cond)
    theta_true = rng.standard_normal(3)
    r = m @ theta_true
    tr, rc_r = _core.solve_normal(m, r)
    tn, rc_n = reference.solve_normal(m, r)
    # rcond from two symmetric eigen-solvers (nalgebra, LAPACK): each eigenvalue carries ~eps ||S||
    # of absolute error, so rcond agrees to ~1e-15 absolutely; allow 1e-13 absolute and 1e-6 relative.
    assert_allclose(rc_r, rc_n, rtol=1e-6, atol=1e-13)
    # Cholesky solves of the same Jacobi-scaled matrix S: the forward error of z = D theta is bounded by
    # ~cond(S) eps ||z|| (cond(S) = 1/rcond), so measure errors in the scaled norm ||D v||.  Measured
    # over 1200 random draws: <= 0.5 cond(S) eps between the backends, <= 2.1 cond(S) eps against the
    # true solution; allow 20 cond(S) eps.  (Componentwise in theta the error can be 1e6 times larger
    # for a weakly scaled column: that is the conditioning of M, not a fault of either solver.)
    d = np.sqrt(np.diag(m))
    tol = 20 * np.finfo(float).eps / rc_n
    assert np.linalg.norm(d * (tr - tn)) <= tol * np.linalg.norm(d * tn)
    # Both solve the system (the same bound against the known solution).
    assert np.linalg.norm(d * (tr - theta_true)) <= tol * np.linalg.norm(d * theta_true)
    assert np.linalg.norm(d * (tn - theta_true)) <= tol * np.linalg.norm(d * theta_true)


def test_solve_normal_accepts_any_memory_layout(core: Any) -> None:
    m = np.asfortranarray([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    r = np.array([1.0, 2.0, 3.0, 4.0])[::-1][:3]  # a reversed (negative-stride) view
    theta, rcond = core.solve_normal(m, r)
    assert_allclose(m @ theta, r, rtol=1e-14)
    assert 0 < rcond <= 1


@pytest.mark.parametrize("p", [64, 256, 1024])
def test_sls_theta_parity(helpers: Any, p: int) -> None:
    pr = helpers.loop_problem(samples_per_period=p)
    dt = 2 * math.pi / pr["omega"] / p
    energy = dt * float(np.sum(pr["ydot"] ** 2))
    for nu in (1.0, 1.2, 1.6, 2.5, 5.0):
        args = (pr["ybar"], pr["ydot"], pr["amplitude"], pr["omega"], pr["phi"], nu)
        th_r, cost_r = _core.sls_theta(*args)
        th_n, cost_n = reference.sls_theta(*args)
        # The normal matrix's sums differ by rounding (~1e-16 relative) and the 3x3 solve amplifies that
        # by cond(M) (~1e3 on these loops).  Measured <= 3e-13 relative; 1e-10 leaves room.
        assert_allclose(th_r, th_n, rtol=1e-10)
        # The cost is a residual: near the true mu it is ~1e-8 of the data energy, so its absolute
        # error is what to bound: measured <= 5e-18 of dt sum(ydot^2); 1e-13 allowed.
        assert cost_r >= 0.0
        assert_allclose(cost_r, cost_n, rtol=1e-10, atol=1e-13 * energy)


def _recording_objective(fn: Callable[[float], float]) -> tuple[Callable[[float], float], list[float]]:
    calls: list[float] = []

    def f(x: float) -> float:
        calls.append(x)
        return fn(x)

    return f, calls


GOLDEN_FUNCTIONS: list[tuple[str, Callable[[float], float], float, float, float]] = [
    ("parabola", lambda x: (x - 2.3) ** 2 + 1.0, 1.0, 10.0, 1e-8),
    ("cosh", lambda x: math.cosh(x - 1.7), -5.0, 5.0, 1e-10),
    ("abs_power", lambda x: abs(x - 3.0) ** 1.5, 0.0, 7.0, 1e-6),
    ("flat_at_min", lambda x: (x - 0.4) ** 4, 0.0, 1.0, 1e-9),
    ("piecewise", lambda x: max(x - 5.5, 2 * (5.5 - x)), 1.0, 9.0, 1e-7),
]


@pytest.mark.parametrize(
    ("name", "fn", "lo", "hi", "tol"), GOLDEN_FUNCTIONS, ids=[g[0] for g in GOLDEN_FUNCTIONS]
)
def test_golden_section_parity(
    name: str, fn: Callable[[float], float], lo: float, hi: float, tol: float
) -> None:
    fr, calls_r = _recording_objective(fn)
    fn_, calls_n = _recording_objective(fn)
    xr, fxr, itr = _core.golden_section(fr, lo, hi, tol)
    xn, fxn, itn = reference.golden_section(fn_, lo, hi, tol)
    # The same update rule on the same callable: the same evaluation points, bit for bit.
    assert calls_r == calls_n
    assert (xr, fxr, itr) == (xn, fxn, itn)
    # Each iteration shrinks the bracket by rho, from hi - lo down to <= tol (+-1 for rounding).
    rho = (math.sqrt(5) - 1) / 2
    assert abs(itr - math.ceil(math.log(tol / (hi - lo)) / math.log(rho))) <= 1
    assert fxr == fn(xr)


def test_golden_section_max_iter_parity() -> None:
    f = lambda x: (x - 2.0) ** 2  # noqa: E731
    r = _core.golden_section(f, 0.0, 5.0, 1e-12, 10)
    n = reference.golden_section(f, 0.0, 5.0, 1e-12, 10)
    assert r == n and r[2] == 10


def test_golden_section_propagates_the_objectives_exception(core: Any) -> None:
    class Boom(RuntimeError):
        pass

    def f(x: float) -> float:
        raise Boom(str(x))

    with pytest.raises(Boom):
        core.golden_section(f, 0.0, 1.0, 1e-3)


@pytest.mark.parametrize(("p", "mu", "gamma"), [(64, 1.6, 0.2), (256, 2.5, -0.3), (512, 1.3, 0.5)])
def test_sls_search_parity(helpers: Any, p: int, mu: float, gamma: float) -> None:
    pr = helpers.loop_problem(samples_per_period=p, mu=mu, gamma=gamma)
    args = (pr["ybar"], pr["ydot"], pr["amplitude"], pr["omega"], pr["phi"], 1.0, 10.0, 1e-8)
    mu_r, th_r, cost_r, it_r = _core.sls_search(*args)
    mu_n, th_n, cost_n, it_n = reference.sls_search(*args)
    # The golden search compares I(c) < I(d); once the bracket is so narrow that the two costs differ by
    # rounding only, the implementations could branch differently.  Measured: identical mu on these
    # loops; 1e-6 would still flag a different search (the bracket is 9 wide).
    assert abs(mu_r - mu_n) < 1e-6
    assert abs(it_r - it_n) <= 1
    assert_allclose(th_r, th_n, rtol=1e-8)
    dt = 2 * math.pi / pr["omega"] / p
    assert_allclose(cost_r, cost_n, rtol=1e-6, atol=1e-13 * dt * float(np.sum(pr["ydot"] ** 2)))
    # And the search found the loop's exponent (true phase, noise-free; see test_identification for
    # the accuracy analysis): a stub would not.
    assert abs(mu_r - mu) < 5e-3


def test_gain_estimate_parity(helpers: Any) -> None:
    for seed in SEEDS:
        rng = np.random.default_rng([108, seed])
        gain, phi = float(rng.uniform(0.5, 2.0)), float(rng.uniform(0, 2 * math.pi))
        beta, gamma, mu = 0.8, float(rng.uniform(-0.7, 0.7)), float(rng.uniform(1.2, 3.0))
        amp = float(rng.uniform(0.5, 1.5) / gain)
        pr = helpers.loop_problem(gain, phi, beta, gamma, mu, amp, 2.5, 256)
        args = (pr["ybar"], pr["ydot"], amp, 2.5, phi, beta, gamma, mu)
        gr, gn = _core.gain_estimate(*args), reference.gain_estimate(*args)
        # Two sums over one period and a division: ~1e-15 relative.
        assert gr == pytest.approx(gn, rel=1e-12)
        # With the true (beta, gamma, mu, phi) the estimator returns the true gain (to the loop's
        # discretisation error, well below 1e-4 at P = 256).
        assert gr == pytest.approx(gain, rel=1e-4)


# --------------------------------------------------------------------------------------------------
# 5. Steady loop, joint refinement, and the whole identification on both backends
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_steady_loop_parity_with_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.3, 3.0) * rng.choice([-1, 1])
    beta = rng.uniform(0.2, 1.5)
    gamma = rng.uniform(-0.5, 0.9) * beta
    mu = rng.uniform(1.1, 3.0)
    phi = rng.uniform(0, 2 * np.pi)
    p = int(rng.integers(16, 80))
    got = _core.steady_loop(amp, beta, gamma, mu, phi, p, 3)
    want = reference.steady_loop(amp, beta, gamma, mu, phi, p, 3)
    assert_allclose(got[0], want[0], rtol=1e-11, atol=1e-12)
    assert_allclose(got[1], want[1], rtol=1e-9, atol=1e-10)
    assert got[3] == want[3]


@pytest.mark.parametrize(
    "args, error",
    [
        ((1.0, 0.5, 0.2, 1.0, 0.0, 64, 4), bw.InvalidParameterError),  # mu <= 1
        ((1.0, -0.5, 0.2, 1.5, 0.0, 64, 4), bw.InvalidParameterError),  # beta + gamma <= 0
        ((0.0, 0.5, 0.2, 1.5, 0.0, 64, 4), bw.ZeroAmplitudeError),
        ((math.nan, 0.5, 0.2, 1.5, 0.0, 64, 4), bw.NonFiniteError),
        ((1.0, 0.5, 0.2, 1.5, 0.0, 3, 4), bw.InsufficientDataError),
        # Valid parameters whose shooting does not converge in 60 Newton steps on a coarse lattice: its
        # own error, not an InvalidParameterError.
        ((100.0, 0.5, 0.0, 1.01, 0.3, 8, 2), bw.NotConvergedError),
        ((1.0, 1000.0, -999.0, 1.01, 0.3, 8, 2), bw.NotConvergedError),
    ],
)
def test_steady_loop_errors_match_reference(args: tuple[Any, ...], error: type[Exception]) -> None:
    with pytest.raises(error):
        _core.steady_loop(*args)
    with pytest.raises(error):
        reference.steady_loop(*args)


def test_refine_parity_with_reference() -> None:
    ys = [_core.steady_loop(a, 0.8, 0.2, 1.6, ph, 48, 4)[0] for a, ph in ((1.8, 1.1), (1.2, 2.5))]
    rng = np.random.default_rng(5)
    ys = [y + 0.01 * rng.standard_normal(y.size) for y in ys]
    args = (ys, [2.0, 1.0], [1e4, 2e4], 0.7, 0.3, 1.7, [0.85, 1.25], [1.05, 2.45])
    got = _core.refine(*args, max_iter=50, substeps=3)
    want = reference.refine(*args, max_iter=50, substeps=3)
    # Same damping schedule and acceptance rule; the dense and Schur solves differ by rounding only.
    assert_allclose(got[0], want[0], rtol=1e-7, atol=1e-9)
    assert got[1] == pytest.approx(want[1], rel=1e-8)
    assert_allclose(got[4], want[4], rtol=1e-6)
    assert got[3] and want[3]


def _demo_plan(p: int, **kw: Any) -> bw.SinePlan:
    """The demo plant's design at 2 and 5 rad/s with P samples per period."""
    freqs = (2.0, 5.0)
    return bw.SinePlan(
        freqs, design_amplitudes(bw.demo_plant(), freqs), samples_per_period=p, substeps=2, **kw
    )


BACKEND_RTOL = {"paper": 1e-8, "profile": 1e-7, "refined": 1e-8}


@pytest.mark.parametrize("method", typing.get_args(Method))
def test_identify_numpy_backend_agrees_with_rust(method: Method) -> None:
    recs = bw.simulate(bw.demo_plant(), _demo_plan(64, settle_periods=10, periods=3))
    r_rust = bw.identify(recs, method=method, backend="rust")
    r_np = bw.identify(recs, method=method, backend="numpy")
    assert r_rust.backend == "rust" and r_np.backend == "numpy"
    rtol = BACKEND_RTOL.get(method, 1e-8)
    assert abs(r_rust.mu - r_np.mu) < rtol * 10
    assert r_rust.beta == pytest.approx(r_np.beta, rel=rtol)
    assert r_rust.gamma == pytest.approx(r_np.gamma, rel=rtol)
    assert r_rust.iterations == r_np.iterations
    assert_allclose(r_rust.gains, r_np.gains, rtol=rtol)
    assert_allclose(r_rust.phases, r_np.phases, rtol=0, atol=rtol)
    if method == "paper":
        assert np.array_equal(r_rust.phases, r_np.phases)  # argmax of the same averaged loop
    assert r_rust.cost == pytest.approx(r_np.cost, rel=1e-6)
    # Both are accurate (noise-free, P = 64), so agreement is not agreement on nonsense.
    assert abs(r_rust.mu - 1.6) < 0.02


def test_simulate_numpy_backend_agrees_with_rust() -> None:
    plant = bw.demo_plant()
    plan = _demo_plan(32, settle_periods=2, periods=2, noise_sd=0.01, seed=3)
    a = bw.simulate(plant, plan, backend="rust")
    b = bw.simulate(plant, plan, backend="numpy")
    for ra, rb in zip(a, b):
        assert ra.x is not None and rb.x is not None and ra.w is not None and rb.w is not None
        # See test_parity: RK4 rounding only (measured <= 3e-15 of the peak).
        assert_allclose(ra.x, rb.x, rtol=1e-11, atol=1e-11 * np.max(np.abs(rb.x)))
        assert_allclose(ra.w, rb.w, rtol=1e-11, atol=1e-11 * np.max(np.abs(rb.w)))
        assert_allclose(ra.y - ra.w, rb.y - rb.w, atol=1e-12)  # the same noise stream
        assert np.array_equal(ra.t, rb.t) and np.array_equal(ra.u, rb.u)


#: The Rust lab kernels signal/ asks for (the Lab part of bouc_wen_id._backend).
LAB_KERNELS = (
    "moment_fit",
    "harmonic_lsq",
    "nls",
    "unscaled_variances",
    "harmonic_rss",
    "window_fits",
    "spectral_peak",
)


def test_backend_means_the_same_for_a_measurements_lab_preprocessing(monkeypatch: pytest.MonkeyPatch) -> None:
    # backend="numpy" runs every step on NumPy, the steady segments and synchronous averages of a
    # Measurement too; backend="rust" runs them on the Rust kernels.
    recs = bw.simulate(bw.demo_plant(), _demo_plan(64, settle_periods=2, periods=8, noise_sd=0.002, seed=5))
    meas = [bw.Measurement(r.t, r.u, r.y, nominal_frequency=r.frequency) for r in recs]
    lab = type(get_backend("rust").lab)
    calls: list[str] = []

    def counting(name: str, real: Callable[..., Any]) -> Callable[..., Any]:
        def method(self: Any, *args: Any, **kwargs: Any) -> Any:
            calls.append(name)
            return real(self, *args, **kwargs)

        return method

    for name in LAB_KERNELS:
        monkeypatch.setattr(lab, name, counting(name, getattr(lab, name)))
    r_np = bw.identify(meas, method="paper", backend="numpy")
    assert calls == [], f"backend='numpy' ran the Rust lab kernels {sorted(set(calls))}"
    r_rust = bw.identify(meas, method="paper", backend="rust")
    assert {"moment_fit", "window_fits", "spectral_peak"} <= set(calls)
    # Two implementations of the same least squares: the same segments, estimates equal to rounding.
    assert len(r_np.experiments) == len(r_rust.experiments) == len(meas)
    assert r_np.mu == pytest.approx(r_rust.mu, rel=1e-6)
    assert_allclose(r_np.gains, r_rust.gains, rtol=1e-6)


def test_the_backend_in_force_is_scoped_and_named() -> None:
    rust_lab = get_backend("rust").lab
    assert current_lab() is rust_lab
    with pytest.raises(InvalidParameterError, match="backend must be 'rust' or 'numpy'"):
        get_backend("fortran")
    with pytest.raises(RuntimeError, match="inside"):
        with selected("numpy") as parts:
            assert current_lab() is parts.lab is get_backend("numpy").lab
            assert parts.multistart is None and parts.paper is reference
            raise RuntimeError("inside")
    assert current_lab() is rust_lab  # restored after an error too


# --------------------------------------------------------------------------------------------------
# Same named errors from both backends
# --------------------------------------------------------------------------------------------------

_Y = np.cos(np.linspace(0, 2 * math.pi, 64, endpoint=False))
_YD = -np.sin(np.linspace(0, 2 * math.pi, 64, endpoint=False))
_BW = (1.0, 0.8, 0.2, 1.6, 0.0)  # alpha, beta, gamma, mu, w0
_SINE = (1.0, 2.0, 0.01, 50, 2)  # amplitude, omega, dt, n_samples, substeps


def _with_nan(a: np.ndarray, i: int = 5) -> np.ndarray:
    b: np.ndarray = a.copy()
    b[i] = np.nan
    return b


def _sim(
    num: Any = (1.0,), den: Any = (1.0, 1.0), delay: float = 0.0, bw: Any = _BW, sine: Any = _SINE
) -> tuple[Any, ...]:
    return ("simulate_sine", (np.asarray(num, float), np.asarray(den, float), delay, *bw, *sine))


def _bw(**kw: float) -> tuple[float, ...]:
    d = dict(zip(("alpha", "beta", "gamma", "mu", "w0"), _BW))
    d.update(kw)
    return tuple(d.values())


def _sine(**kw: Any) -> tuple[Any, ...]:
    d = dict(zip(("amplitude", "omega", "dt", "n_samples", "substeps"), _SINE))
    d.update(kw)
    return tuple(d.values())


def _search_at(mu_lo: float, mu_hi: float) -> tuple[Any, ...]:
    return ("sls_search", "LOOP", mu_lo, mu_hi)


def _parabola(x: float) -> float:
    return (x - 2.0) ** 2


BAD_INPUTS: list[tuple[str, tuple[Any, ...], type[Exception]]] = [
    # periodic averaging
    ("nan_in_y", ("periodic_average", (_with_nan(np.tile(_Y, 4)), 64, 1, 2)), NonFiniteError),
    ("inf_in_y", ("periodic_average", (np.r_[np.tile(_Y, 4)[:-1], np.inf], 64, 1, 2)), NonFiniteError),
    ("too_few_samples_for_periods", ("periodic_average", (np.tile(_Y, 4), 64, 2, 3)), InsufficientDataError),
    ("samples_per_period_below_4", ("periodic_average", (np.ones(30), 3, 0, 2)), InsufficientDataError),
    ("zero_periods", ("periodic_average", (np.tile(_Y, 4), 64, 0, 0)), InsufficientDataError),
    ("negative_periods", ("periodic_average", (np.tile(_Y, 4), 64, 0, -1)), InsufficientDataError),
    ("negative_settle", ("periodic_average", (np.tile(_Y, 4), 64, -1, 2)), InvalidParameterError),
    # phase
    ("constant_ybar", ("phase_from_max", (np.full(64, 0.3),)), ZeroAmplitudeError),
    ("nan_in_ybar_phase", ("phase_from_max", (_with_nan(_Y),)), NonFiniteError),
    ("ybar_too_short_phase", ("phase_from_max", (np.array([1.0, 2.0, 0.0]),)), InsufficientDataError),
    # spectral derivative
    ("harmonics_zero", ("spectral_derivative", (_Y, 2.0, 0)), InvalidParameterError),
    ("harmonics_negative", ("spectral_derivative", (_Y, 2.0, -3)), InvalidParameterError),
    ("harmonics_nyquist", ("spectral_derivative", (_Y, 2.0, 32)), InvalidParameterError),
    ("harmonics_nyquist_odd", ("spectral_derivative", (_Y[:9], 2.0, 5)), InvalidParameterError),
    ("derivative_omega_zero", ("spectral_derivative", (_Y, 0.0, 3)), InvalidParameterError),
    ("derivative_nan", ("spectral_derivative", (_with_nan(_Y), 2.0, 3)), NonFiniteError),
    # SLS inputs
    ("mismatched_lengths", ("sls_regressor", (_Y, _YD[:-1], 1.0, 2.0, 0.3, 1.5)), InvalidParameterError),
    (
        "mismatched_lengths_gain",
        ("gain_estimate", (_Y[:-2], _YD, 1.0, 2.0, 0.3, 0.8, 0.2, 1.6)),
        InvalidParameterError,
    ),
    ("zero_amplitude_regressor", ("sls_regressor", (_Y, _YD, 0.0, 2.0, 0.3, 1.5)), ZeroAmplitudeError),
    ("zero_amplitude_theta", ("sls_theta", (_Y, _YD, 0.0, 2.0, 0.3, 1.5)), ZeroAmplitudeError),
    ("zero_amplitude_gain", ("gain_estimate", (_Y, _YD, 0.0, 2.0, 0.3, 0.8, 0.2, 1.6)), ZeroAmplitudeError),
    ("nan_ydot", ("sls_theta", (_Y, _with_nan(_YD), 1.0, 2.0, 0.3, 1.5)), NonFiniteError),
    ("inf_phi", ("sls_regressor", (_Y, _YD, 1.0, 2.0, math.inf, 1.5)), NonFiniteError),
    ("sls_omega_negative", ("sls_theta", (_Y, _YD, 1.0, -2.0, 0.3, 1.5)), InvalidParameterError),
    ("sls_too_short", ("sls_theta", (_Y[:3], _YD[:3], 1.0, 2.0, 0.3, 1.5)), InsufficientDataError),
    ("singular_ybar_zero", ("sls_theta", (np.zeros(64), _YD, 1.0, 2.0, 0.3, 1.5)), SingularNormalMatrixError),
    (
        "singular_search_ybar_zero",
        ("sls_search", (np.zeros(64), _YD, 1.0, 2.0, 0.3, 1.0, 10.0, 1e-6)),
        SingularNormalMatrixError,
    ),
    ("gain_nan_beta", ("gain_estimate", (_Y, _YD, 1.0, 2.0, 0.3, math.nan, 0.2, 1.6)), NonFiniteError),
    # normal equations
    (
        "normal_zero_column",
        ("solve_normal", (np.diag([1.0, 0.0, 2.0]), np.ones(3))),
        SingularNormalMatrixError,
    ),
    (
        "normal_negative_diagonal",
        ("solve_normal", (np.diag([1.0, -1.0, 2.0]), np.ones(3))),
        SingularNormalMatrixError,
    ),
    (
        "normal_collinear",
        ("solve_normal", (np.outer([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]), np.ones(3))),
        SingularNormalMatrixError,
    ),
    (
        "normal_nan",
        ("solve_normal", (_with_nan(np.eye(3).ravel(), 4).reshape(3, 3), np.ones(3))),
        NonFiniteError,
    ),
    ("normal_bad_shape", ("solve_normal", (np.eye(2), np.ones(2))), InvalidParameterError),
    # golden section
    ("golden_lo_eq_hi", ("golden_section", (_parabola, 3.0, 3.0, 1e-6)), InvalidParameterError),
    ("golden_lo_gt_hi", ("golden_section", (_parabola, 5.0, 1.0, 1e-6)), InvalidParameterError),
    ("golden_tol_zero", ("golden_section", (_parabola, 0.0, 5.0, 0.0)), InvalidParameterError),
    ("golden_tol_negative", ("golden_section", (_parabola, 0.0, 5.0, -1e-3)), InvalidParameterError),
    ("golden_tol_wider_than_bracket", ("golden_section", (_parabola, 0.0, 5.0, 6.0)), InvalidParameterError),
    ("golden_nan_bound", ("golden_section", (_parabola, math.nan, 5.0, 1e-3)), NonFiniteError),
    ("golden_min_at_lower_bound", ("golden_section", (_parabola, 2.5, 9.0, 1e-6)), SearchAtBoundError),
    ("golden_min_at_upper_bound", ("golden_section", (_parabola, -4.0, 1.5, 1e-6)), SearchAtBoundError),
    ("golden_min_on_lower_bound", ("golden_section", (_parabola, 2.0, 9.0, 1e-6)), SearchAtBoundError),
    ("golden_nan_objective", ("golden_section", (lambda x: math.nan, 0.0, 5.0, 1e-3)), NonFiniteError),
    ("golden_max_iter_zero", ("golden_section", (_parabola, 0.0, 5.0, 1e-3, 0)), InvalidParameterError),
    # mu search on a real loop (true mu = 1.6)
    ("search_bracket_above_mu", _search_at(3.0, 10.0), SearchAtBoundError),
    ("search_bracket_below_mu", _search_at(1.0, 1.3), SearchAtBoundError),
    ("search_bracket_below_one", _search_at(0.5, 10.0), InvalidParameterError),
    # simulation: the linear part
    ("unstable_den", _sim(den=(1.0, -1.0)), UnstableSystemError),
    ("unstable_den_order3", _sim(den=(1.0, 1.0, 1.0, 5.0)), UnstableSystemError),
    ("marginal_den", _sim(den=(1.0, 0.0, 4.0)), UnstableSystemError),
    ("integrator", _sim(den=(1.0, 0.0)), UnstableSystemError),
    ("improper_num", _sim(num=(1.0, 0.0, 1.0), den=(1.0, 1.0)), ImproperTransferFunctionError),
    ("den_leading_zero", _sim(den=(0.0, 1.0, 1.0)), ImproperTransferFunctionError),
    ("nan_in_num", _sim(num=(math.nan,)), NonFiniteError),
    ("negative_delay", _sim(delay=-0.1), InvalidParameterError),
    # simulation: the hysteresis
    ("mu_below_one", _sim(bw=_bw(mu=0.9)), InvalidParameterError),
    ("alpha_zero", _sim(bw=_bw(alpha=0.0)), InvalidParameterError),
    ("alpha_negative", _sim(bw=_bw(alpha=-1.0)), InvalidParameterError),
    ("beta_plus_gamma_zero", _sim(bw=_bw(beta=0.5, gamma=-0.5)), InvalidParameterError),
    ("gamma_above_beta", _sim(bw=_bw(beta=0.2, gamma=0.5)), InvalidParameterError),
    ("nan_beta", _sim(bw=_bw(beta=math.nan)), NonFiniteError),
    # simulation: grid and input
    ("dt_zero", _sim(sine=_sine(dt=0.0)), InvalidParameterError),
    ("substeps_zero", _sim(sine=_sine(substeps=0)), InvalidParameterError),
    ("n_samples_zero", _sim(sine=_sine(n_samples=0)), InvalidParameterError),
    ("omega_zero", _sim(sine=_sine(omega=0.0)), InvalidParameterError),
    ("nan_amplitude", _sim(sine=_sine(amplitude=math.nan)), NonFiniteError),
    (
        "sampled_one_sample",
        ("simulate_sampled", (np.ones(1), np.ones(2), 0.0, *_BW, np.ones(1), 0.01, 1)),
        InsufficientDataError,
    ),
    (
        "sampled_nan_u",
        ("simulate_sampled", (np.ones(1), np.ones(2), 0.0, *_BW, _with_nan(_Y), 0.01, 1)),
        NonFiniteError,
    ),
    (
        "sampled_dt_negative",
        ("simulate_sampled", (np.ones(1), np.ones(2), 0.0, *_BW, _Y, -0.01, 1)),
        InvalidParameterError,
    ),
]


@pytest.mark.parametrize(
    ("call", "error"), [(c, e) for _, c, e in BAD_INPUTS], ids=[n for n, _, _ in BAD_INPUTS]
)
def test_same_named_error_from_both_backends(
    helpers: Any, call: tuple[Any, ...], error: type[Exception]
) -> None:
    name, args = call[0], call[1]
    if args == "LOOP":
        pr = helpers.loop_problem(samples_per_period=128)
        args = (pr["ybar"], pr["ydot"], pr["amplitude"], pr["omega"], pr["phi"], call[2], call[3], 1e-6)
    raised = {}
    for backend, mod in helpers.BACKENDS.items():
        with pytest.raises(error) as info:
            getattr(mod, name)(*args)
        raised[backend] = type(info.value)
    # Not merely a subclass of the expected one: exactly the same class from both.
    assert raised["rust"] is raised["numpy"] is error, raised


# --------------------------------------------------------------------------------------------------
# Inputs are not modified; non-contiguous arrays are refused cleanly by the Rust core
# --------------------------------------------------------------------------------------------------


def _all_calls(helpers: Any) -> list[tuple[str, tuple[Any, ...]]]:
    pr = helpers.loop_problem(samples_per_period=64)
    yb, yd = pr["ybar"], pr["ydot"]
    a, om, ph = pr["amplitude"], pr["omega"], pr["phi"]
    y = np.tile(yb, 3) + 0.01 * np.random.default_rng(5).standard_normal(192)
    num, den = np.array([1.0, 2.0]), np.array([1.0, 3.0, 2.0])
    u = np.cos(np.linspace(0, 6, 40))
    m = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    return [
        ("simulate_sine", (num, den, 0.1, *_BW, 1.0, 2.0, 0.05, 40, 1)),
        ("simulate_sampled", (num, den, 0.1, *_BW, u, 0.05, 1)),
        ("periodic_average", (y, 64, 1, 2)),
        ("phase_from_max", (yb,)),
        ("spectral_derivative", (yb, om, 10)),
        ("sls_regressor", (yb, yd, a, om, ph, 1.5)),
        ("solve_normal", (m, np.array([1.0, 2.0, 3.0]))),
        ("sls_theta", (yb, yd, a, om, ph, 1.5)),
        ("sls_search", (yb, yd, a, om, ph, 1.0, 10.0, 1e-6)),
        ("gain_estimate", (yb, yd, a, om, ph, 0.8, 0.2, 1.6)),
    ]


def test_inputs_are_never_modified(helpers: Any) -> None:
    for backend, mod in helpers.BACKENDS.items():
        for name, args in _all_calls(helpers):
            copies = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
            out = getattr(mod, name)(*args)
            for before, after in zip(copies, args):
                if isinstance(after, np.ndarray):
                    assert np.array_equal(before, after), (backend, name)
            # Outputs are fresh arrays, never views of an input.
            outs = out if isinstance(out, tuple) else (out,)
            for o in outs:
                for a in args:
                    if isinstance(o, np.ndarray) and isinstance(a, np.ndarray):
                        assert not np.shares_memory(o, a), (backend, name)


def test_rust_core_refuses_non_contiguous_arrays(helpers: Any) -> None:
    checked = 0
    for name, args in _all_calls(helpers):
        for i, a in enumerate(args):
            if not (isinstance(a, np.ndarray) and a.ndim == 1 and a.size >= 4) or name.startswith(
                "simulate_sine"
            ):
                continue
            # A strided view with the same values as a contiguous array of half the length.
            doubled = np.repeat(a, 2)
            view = doubled[::2]
            assert not view.flags.c_contiguous and np.array_equal(view, a)
            bad = list(args)
            bad[i] = view
            with pytest.raises(ValueError, match="contiguous"):
                getattr(_core, name)(*bad)
            # The reference accepts the same view, and both agree once the array is made contiguous.
            ok = list(args)
            ok[i] = np.ascontiguousarray(view)
            getattr(_core, name)(*ok)
            getattr(reference, name)(*bad)
            checked += 1
    assert checked >= 10


def test_rust_core_refuses_a_strided_recording(helpers: Any) -> None:
    y = np.tile(np.cos(np.linspace(0, 2 * math.pi, 64, endpoint=False)), 8)
    with pytest.raises(ValueError, match="contiguous"):
        _core.periodic_average(y[::2], 32, 0, 4)
    # The reference averages the view like any array.
    assert_allclose(reference.periodic_average(y[::2], 32, 0, 4), y[:64:2])


@pytest.mark.parametrize(
    "bad",
    [
        np.arange(192),  # int64
        np.arange(192, dtype=np.float32),
        list(np.arange(192.0)),
        np.arange(192.0).reshape(3, 64),
    ],
    ids=["int64", "float32", "list", "2d"],
)
def test_rust_core_refuses_other_array_types_without_crashing(bad: Any) -> None:
    """The core takes 1-D float64 ndarrays only (the public API converts before calling it); anything
    else is a Python exception, not a crash.  (The reference converts with np.asarray instead.)"""
    with pytest.raises((TypeError, ValueError)):
        _core.periodic_average(bad, 64, 1, 2)

"""Spencer's series dashpot (docs/diagnosis.md, "Series dashpot"): the registry term, the steady loop and
its Jacobian (Rust against the NumPy oracle and central differences), the time-domain simulation (Rust
against the oracle, and against scipy's solve_ivp of Spencer's own equations)."""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id import terms as T
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.reference import augmented as ra
from numpy.testing import assert_allclose

SD = T.SeriesDashpot.kind
TWO_PI = 2.0 * math.pi


# ------------------------------------------------------------------ the registry term


def test_registry_term_range_normalisation_and_candidacy() -> None:
    assert T.TERMS[SD] is T.SeriesDashpot and T.SeriesDashpot.acts_on == T.Place.HYSTERESIS
    assert SD in T.STEADY_TERM_NAMES and SD in T.DIAGNOSIS_CANDIDATES
    assert T.SeriesDashpot(0.0).value == 0.0 and T.physical_value(SD, 2.0)
    with pytest.raises(InvalidParameterError, match="series_dashpot rho"):
        T.SeriesDashpot(-0.1)
    # rho is qdot / w, in units of x per unit of w: G -> alpha G scales it by alpha.
    assert T.SeriesDashpot(2.0).normalized(3.0) == T.SeriesDashpot(6.0)
    assert T.term_from_dict(T.SeriesDashpot(0.5).to_dict()) == T.SeriesDashpot(0.5)
    ctx = T.StartContext((1.0,), 10.0, 0.5, 0.5, lambda: 0.0)
    assert all(s > 0.0 for s in T.SeriesDashpot.start(ctx))


# ------------------------------------------------------------------ steady loop: Rust vs oracle, Jacobian


def _case(rng: np.random.Generator, others: list[str]) -> tuple[Any, ...]:
    p = int(rng.integers(24, 48))
    beta = float(rng.uniform(0.3, 1.0))
    gamma = float(rng.uniform(-0.2, 0.9)) * beta
    mu = float(rng.uniform(1.2, 2.5))
    names = [SD, *others]
    values = {
        SD: float(rng.uniform(0.0, 3.0)),
        "asymmetry": float(rng.uniform(-0.5, 0.5)) * (beta + gamma),
        "offset": float(rng.normal()),
        "sensor_lag": float(rng.uniform(0.0, 0.1)),
        "viscous": float(rng.normal()) * 0.1,
        "stiffness@x": float(rng.uniform(0.0, 0.5)),
        "viscous@x": float(rng.uniform(0.0, 0.1)),
    }
    shared = np.array([beta, gamma, mu, *(values[n] for n in names)])
    amp, omega, psi = float(rng.uniform(0.5, 2.0)), float(rng.uniform(0.5, 6.0)), float(rng.uniform(-3, 3))
    gain, phase = float(rng.uniform(0.5, 2.0)) * float(rng.choice([-1.0, 1.0])), float(rng.uniform(-3, 3))
    return (p, amp, omega, psi, names, shared, gain, phase, int(rng.integers(1, 4)))


OTHERS = ["asymmetry", "offset", "sensor_lag", "viscous", "stiffness@x", "viscous@x"]


@pytest.mark.parametrize("seed", range(6))
def test_steady_output_rust_matches_the_oracle(seed: int) -> None:
    rng = np.random.default_rng([1823, seed])
    others = list(rng.permutation(OTHERS)[: rng.integers(0, len(OTHERS) + 1)])
    args = _case(rng, others)
    core: Any = _core
    r = core.augmented_output(*args)
    n = ra.augmented_output(*args)
    # The same RK4 steps and Newton passes in the same order; libm's and the FFTs' rounding differ.
    for a, b in zip(r, n):
        assert a.shape == b.shape
        assert_allclose(a, b, rtol=0, atol=1e-10 * max(1.0, float(np.max(np.abs(b)))))


@pytest.mark.parametrize("seed", range(3))
def test_steady_jacobian_matches_central_differences(seed: int) -> None:
    rng = np.random.default_rng([1824, seed])
    p, amp, omega, psi, names, shared, gain, phase, sub = _case(rng, ["asymmetry", "stiffness@x"])
    core: Any = _core

    def y(sh: np.ndarray, g: float, ph: float) -> np.ndarray:
        return np.asarray(core.augmented_output(p, amp, omega, psi, names, sh, g, ph, sub)[0])

    _, js, jo = core.augmented_output(p, amp, omega, psi, names, shared, gain, phase, sub)
    h = 1e-6
    for c in range(shared.size):
        e = np.zeros(shared.size)
        e[c] = h
        fd = (y(shared + e, gain, phase) - y(shared - e, gain, phase)) / (2 * h)
        assert_allclose(js[:, c], fd, rtol=0, atol=2e-5 * max(1.0, float(np.max(np.abs(fd)))))
    for c, (dg, dp) in enumerate(((h, 0.0), (0.0, h))):
        fd = (y(shared, gain + dg, phase + dp) - y(shared, gain - dg, phase - dp)) / (2 * h)
        assert_allclose(jo[:, c], fd, rtol=0, atol=2e-5 * max(1.0, float(np.max(np.abs(fd)))))


def test_zero_dashpot_is_the_plain_loop_and_a_dashpot_changes_it() -> None:
    args = (64, 1.3, 2.0, 0.3, [SD], np.array([0.6, 0.3, 1.7, 0.0]), 1.1, 0.4, 8)
    core: Any = _core
    y0 = core.augmented_output(*args)[0]
    plain = core.augmented_output(64, 1.3, 2.0, 0.3, [], np.array([0.6, 0.3, 1.7]), 1.1, 0.4, 64)[0]
    assert_allclose(y0, plain, rtol=0, atol=1e-5)
    args1 = (*args[:5], np.array([0.6, 0.3, 1.7, 1.0]), *args[6:])
    assert float(np.max(np.abs(core.augmented_output(*args1)[0] - y0))) > 0.05


@pytest.mark.parametrize("core", [_core, ra], ids=["rust", "numpy"])
def test_bad_steady_input_is_named(core: Any) -> None:
    sh = np.array([0.6, 0.3, 1.7, -0.5])
    with pytest.raises(InvalidParameterError, match="series_dashpot"):
        core.augmented_output(32, 1.0, 2.0, 0.0, [SD], sh, 1.0, 0.0, 2)
    sh = np.array([0.6, 0.3, 1.7, 0.5, 0.1])
    with pytest.raises(InvalidParameterError, match="asymmetry only"):
        core.augmented_output(32, 1.0, 2.0, 0.0, [SD, "play"], sh, 1.0, 0.0, 2)


# ------------------------------------------------------------------ time domain: Rust vs oracle


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize(
    "terms",
    [{SD: 1.5}, {SD: 0.8, "asymmetry": 0.3, "sensor_lag": 0.02, "play": 0.05, "degradation": 0.02}],
    ids=["alone", "with-others"],
)
def test_simulation_rust_matches_the_oracle(helpers: Any, terms: dict[str, float], seed: int) -> None:
    rng = np.random.default_rng([1825, seed])
    num, den, delay = helpers.random_tf(rng, int(rng.integers(1, 3)))
    alpha, beta, gamma, mu, w0 = helpers.random_bouc_wen(rng)
    terms = dict(terms)
    if "asymmetry" in terms:
        terms["asymmetry"] *= beta + gamma
    omega = float(rng.uniform(0.5, 6.0))
    dt = TWO_PI / omega / 40
    amp = float(rng.uniform(0.5, 2.5))
    args = (num, den, delay, alpha, beta, gamma, mu, w0)
    core: Any = _core
    ref: Any = reference
    n, sub = 240, 2
    xr, wr, yr = core.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms)
    xn, wn, yn = ref.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms)
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * float(np.max(np.abs(p))))
    u = amp * np.cos(omega * np.arange(n) * dt) + 0.1 * rng.standard_normal(n)
    xr, wr, yr = core.simulate_sampled(*args, u, dt, sub, terms=terms)
    xn, wn, yn = ref.simulate_sampled(*args, u, dt, sub, terms=terms)
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * float(np.max(np.abs(p))))
    without = {k: v for k, v in terms.items() if k != SD}
    _, w_without, _ = core.simulate_sine(*args, amp, omega, dt, n, sub, terms=without)
    assert float(np.max(np.abs(wr - w_without))) > 1e-4 * float(np.max(np.abs(w_without)))


@pytest.mark.parametrize("core", [_core, reference], ids=["rust", "numpy"])
def test_negative_dashpot_is_a_named_error(core: Any) -> None:
    args = (np.array([1.0]), np.array([1.0, 1.0]), 0.0, 1.0, 1.0, 0.2, 1.5, 0.0, 1.0, 2.0, 0.05, 50, 1)
    with pytest.raises(InvalidParameterError, match=SD):
        core.simulate_sine(*args, terms={SD: -1.0})


def test_zero_dashpot_leaves_the_run_bit_identical() -> None:
    args = (np.array([1.0]), np.array([0.3, 1.0]), 0.1, 1.0, 0.8, 0.3, 1.7, 0.0, 1.5, 2.0, 0.05, 300, 2)
    core: Any = _core
    base = core.simulate_sine(*args, terms={"play": 0.1, "degradation": 0.01})
    same = core.simulate_sine(*args, terms={"play": 0.1, "degradation": 0.01, SD: 0.0})
    for a, b in zip(base, same):
        assert np.array_equal(a, b)


# ------------------------------------------------------------------ Spencer's equations, solved by scipy


def _spencer_ivp(kind: str, t: np.ndarray, u_of_t: Any, sp: dict[str, float]) -> np.ndarray:
    """F(t) of Spencer's model (c0 = k0 = 0) driven by x = G u, all states by solve_ivp (LSODA-free: an
    adaptive RK45 at tight tolerance). G: first order ``tc x' = K u - x`` or resonant
    ``x'' + 2 z wn x' + wn^2 x = K wn^2 u``."""
    from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

    names = ("A", "alpha", "beta", "gamma", "n", "c1", "k1", "x0")
    A, alpha, beta, gamma, n, c1, k1, x0 = (sp[k] for k in names)
    K, tc, z, wn = 1.0, 0.05, 0.2, TWO_PI * 3.0

    def f(tt: float, s: np.ndarray) -> list[float]:
        if kind == "first":
            x, zz, q = s
            xdot = (K * u_of_t(tt) - x) / tc
            lin = [xdot]
        else:
            x, v, zz, q = s
            xdot = v
            lin = [v, wn**2 * (K * u_of_t(tt) - x) - 2 * z * wn * v]
        qdot = alpha * zz / c1  # c1 qdot = alpha z + k0 (x - q) + c0 (xdot - qdot), k0 = c0 = 0
        d = xdot - qdot
        zdot = -gamma * abs(d) * zz * abs(zz) ** (n - 1) - beta * d * abs(zz) ** n + A * d
        return [*lin, zdot, qdot]

    n_lin = 1 if kind == "first" else 2
    span, start = (t[0], t[-1]), np.zeros(n_lin + 2)
    sol = solve_ivp(f, span, start, t_eval=t, rtol=1e-10, atol=1e-12, max_step=t[1] - t[0])
    x, zz, q = sol.y[0], sol.y[-2], sol.y[-1]
    return np.asarray(alpha * zz + k1 * (x - x0) + 0.0 * q)


@pytest.mark.parametrize("kind", ["first", "resonant"])
def test_simulate_input_matches_spencers_equations_by_solve_ivp(kind: str) -> None:
    # Spencer's notation: zdot = -gamma |d| z |z|^(n-1) - beta d |z|^n + A d, F = alpha z + k1 (x - x0).
    sp = {"A": 1.2, "alpha": 2.0, "beta": 0.4, "gamma": 0.9, "n": 2.0, "c1": 1.5, "k1": 0.3, "x0": 0.2}
    dt, n_s = 1.0 / 400.0, 1200
    t = np.arange(n_s) * dt
    omega = TWO_PI * 1.5

    def u_of_t(tt: float) -> float:
        # Not a clean sine: a ramped tone plus a second one (the library sees only its samples).
        return 1.5 * math.sin(omega * tt) * (1.0 - math.exp(-tt / 0.1)) + 0.4 * math.sin(2.3 * omega * tt)

    u = np.array([u_of_t(tt) for tt in t])

    ours = _spencer_ivp(kind, t, u_of_t, sp)
    # The library's parameters: w = alpha z, so its alpha is Spencer's alpha A, and its beta (the |xdot|
    # term) and gamma are Spencer's gamma and beta times alpha^(1 - n); rho = 1/c1; k1 on x; -k1 x0.
    a_lib, scale = sp["alpha"] * sp["A"], sp["alpha"] ** (1.0 - sp["n"])
    tf = (
        bw.TransferFunction([1.0], [0.05, 1.0])
        if kind == "first"
        else bw.TransferFunction([(TWO_PI * 3.0) ** 2], [1.0, 2 * 0.2 * TWO_PI * 3.0, (TWO_PI * 3.0) ** 2])
    )
    plant = bw.WienerPlant(
        tf,
        bw.BoucWen(sp["gamma"] * scale, sp["beta"] * scale, sp["n"], alpha=a_lib),
        terms=(
            T.SeriesDashpot(1.0 / sp["c1"]),
            T.StiffnessX(sp["k1"]),
            T.Offset(-sp["k1"] * sp["x0"]),
        ),
    )
    _, _, y = bw.simulate_input(plant, t, u, substeps=8, output=True)
    peak = float(np.max(np.abs(ours)))
    err = float(np.max(np.abs(np.asarray(y) - ours)))
    # Two integrators (RK4 at dt/8 on the samples' Catmull-Rom interpolant, RK45 at 1e-10 on the analytic
    # input): they differ by the interpolation (O(dt^3) between samples) and the kinks' O(h^2).
    assert err < 2e-3 * peak, err / peak
    # ...and the dashpot matters here: without it the library's output is far off.
    plain = bw.WienerPlant(plant.linear, plant.hysteresis, terms=plant.terms[1:])
    _, _, y_plain = bw.simulate_input(plain, t, u, substeps=8, output=True)
    assert float(np.max(np.abs(np.asarray(y_plain) - ours))) > 20 * err


def test_exporters_write_the_term_and_compensation_refuses_it_by_name() -> None:
    # The exporters write it (held to the simulator bit for bit in test_export.py); compensation does not.
    from bouc_wen_id.compensation import compensate
    from bouc_wen_id.export import EXPORTED
    from bouc_wen_id.export._model import flatten

    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.1, 1.0]), bw.BoucWen(0.5, 0.5, 2.0), (T.SeriesDashpot(1.0),)
    )
    assert T.SeriesDashpot in EXPORTED and flatten(plant, "export").rho == 1.0
    t = np.arange(200) * 0.01
    with pytest.raises(InvalidParameterError, match=SD):
        compensate(plant, 0.1 * np.sin(TWO_PI * t), t)


@pytest.mark.parametrize("core", [_core, ra], ids=["rust", "numpy"])
def test_too_stiff_a_loop_is_a_named_error_not_a_hang(core: Any) -> None:
    # rho/omega = 5e4: the explicit RK4 would need more than MAX_STEPS_PER_SAMPLE steps per sample.
    from bouc_wen_id.errors import NotConvergedError

    with pytest.raises(NotConvergedError, match="too stiff"):
        core.augmented_output(32, 1.0, 2.0, 0.0, [SD], np.array([0.6, 0.3, 1.7, 1e5]), 1.0, 0.0, 2)

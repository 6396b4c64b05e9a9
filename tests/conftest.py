"""Shared helpers of the test suite: random stable plants, random Bouc-Wen elements, exact averaged loops.

Everything random is drawn from ``np.random.default_rng(seed)`` with an explicit seed, so a failure
reproduces bit for bit.

The helpers reach the tests through the ``helpers`` fixture (a namespace of the functions below) rather
than ``from conftest import ...``: ``scripts/test.sh`` runs pytest with ``--import-mode=importlib``, under
which a test module cannot import the conftest by name.
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any, Callable

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference

# The tests' shared simulators (wiener_sim, on_x_sim, drift_null_sim, ...) import by name from any test
# module, whatever the collection order: under --import-mode=importlib nothing else puts tests/ on the path
# (before session 45 a test module that happened to sort first did, and a new one sorting before it failed).
if str(Path(__file__).resolve().parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))

#: Both implementations of the core routines, by the names ``identify(backend=...)`` uses.
BACKENDS: dict[str, ModuleType] = {"rust": _core, "numpy": reference}

TWO_PI = 2.0 * math.pi

#: The real recordings: where ``BOUC_WEN_ID_REAL_DATA`` says, else ``../shared/data/real`` next to the
#: repository (read in place, never copied into it).
REAL_DATA = Path(
    os.environ.get("BOUC_WEN_ID_REAL_DATA")
    or Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real"
)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "real_data: reads the real recordings (skipped when they are absent)")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip the ``real_data`` tests, saying why, when the recordings are absent.

    ``BOUC_WEN_ID_REQUIRE_REAL_DATA=1`` (for CI, which has them) makes their absence a failure instead.
    """
    if REAL_DATA.is_dir():
        return
    why = (
        f"the real recordings are not in {REAL_DATA}: put them in ../shared/data/real next to the "
        "repository, or point BOUC_WEN_ID_REAL_DATA at them"
    )
    if os.environ.get("BOUC_WEN_ID_REQUIRE_REAL_DATA") == "1":
        raise pytest.UsageError(why)
    for item in items:
        if "real_data" in item.keywords:
            item.add_marker(pytest.mark.skip(reason=why))


@pytest.fixture(scope="session")
def real_data() -> Path:
    """The folder of the real recordings (the ``real_data`` marker skips a test when it is absent)."""
    return REAL_DATA


@pytest.fixture(params=sorted(BACKENDS))
def core(request: pytest.FixtureRequest) -> ModuleType:
    """Each backend in turn (the Rust extension and the NumPy reference)."""
    return BACKENDS[request.param]


def random_stable_den(rng: np.random.Generator, order: int) -> np.ndarray:
    """A denominator of the given order with every root strictly in the left half-plane.

    Roots: complex pairs with real part in [-3, -0.3] and imaginary part in [0.5, 6], plus a real root
    in [-4, -0.3] when the order is odd; the leading coefficient is a random positive or negative scale
    (a negative ``den[0]`` must be accepted: stability is decided after normalising ``den[0] = 1``).
    """
    roots: list[complex] = []
    for _ in range(order // 2):
        z = complex(-rng.uniform(0.3, 3.0), rng.uniform(0.5, 6.0))
        roots += [z, z.conjugate()]
    if order % 2:
        roots.append(complex(-rng.uniform(0.3, 4.0), 0.0))
    lead = rng.uniform(0.5, 2.0) * rng.choice([-1.0, 1.0])
    den = lead * np.real(np.poly(roots)) if roots else np.array([lead])
    return np.asarray(den, dtype=np.float64)


def random_tf(
    rng: np.random.Generator, order: int, *, delay: bool = True
) -> tuple[np.ndarray, np.ndarray, float]:
    """``(num, den, delay)`` of a random proper, stable G of the given order (delay 0 half the time)."""
    den = random_stable_den(rng, order)
    num_deg = int(rng.integers(0, order + 1))
    num = rng.uniform(-2.0, 2.0, num_deg + 1)
    num[0] = np.copysign(max(abs(num[0]), 0.3), num[0])
    tau = float(rng.uniform(0.0, 0.8)) if (delay and rng.random() < 0.5) else 0.0
    return num, den, tau


def random_bouc_wen(rng: np.random.Generator) -> tuple[float, float, float, float, float]:
    """``(alpha, beta, gamma, mu, w0)`` inside the admissible set: alpha > 0, beta >= |gamma|, mu >= 1."""
    alpha = float(rng.uniform(0.5, 2.5))
    beta = float(rng.uniform(0.2, 1.5))
    gamma = float(rng.uniform(-0.95, 0.95) * beta)
    mu = float(rng.uniform(1.0, 4.0))
    w0 = float(rng.uniform(-0.3, 0.3))
    return alpha, beta, gamma, mu, w0


def averaged_loop(
    gain: float,
    phi: float,
    beta: float,
    gamma: float,
    mu: float,
    amplitude: float,
    omega: float,
    samples_per_period: int,
    *,
    settle_periods: int = 20,
    periods: int = 1,
    substeps: int = 2,
    core: ModuleType = _core,
) -> np.ndarray:
    """Noise-free averaged loop ``ybar`` of the alpha = 1 Bouc-Wen element driven by
    ``x = U |G| cos(omega t - phi)``.

    The linear part is a static gain ``|G|`` behind a pure delay ``tau = phi / omega``, so after
    ``t >= tau`` the simulated ``x`` is the steady sine exactly (no linear transient): the only error of
    ``ybar`` is the RK4 error of ``w`` and whatever transient of ``w`` survives ``settle_periods``.
    """
    p = int(samples_per_period)
    dt = TWO_PI / omega / p
    phi = float(np.mod(phi, TWO_PI))
    _, w = core.simulate_sine(
        np.array([gain]),
        np.array([1.0]),
        phi / omega,
        1.0,
        beta,
        gamma,
        mu,
        0.0,
        amplitude,
        omega,
        dt,
        (settle_periods + periods) * p,
        substeps,
    )
    return np.asarray(core.periodic_average(np.ascontiguousarray(w), p, settle_periods, periods))


def loop_problem(
    gain: float = 1.5,
    phi: float = 1.1,
    beta: float = 0.8,
    gamma: float = 0.2,
    mu: float = 1.6,
    amplitude: float = 0.8,
    omega: float = 2.0,
    samples_per_period: int = 256,
) -> dict[str, Any]:
    """An averaged loop and its spectral derivative, ready for the SLS routines (true phase ``phi``)."""
    ybar = averaged_loop(gain, phi, beta, gamma, mu, amplitude, omega, samples_per_period)
    ydot = np.asarray(_core.spectral_derivative(ybar, omega, (samples_per_period - 1) // 2))
    return {"ybar": ybar, "ydot": ydot, "amplitude": amplitude, "omega": omega, "phi": phi}


def rust_against_oracle(
    rng: np.random.Generator,
    order: int,
    draw_terms: Callable[[np.random.Generator], dict[str, float]],
    extra: dict[str, float],
    *,
    hold_tail: int = 0,
) -> SimpleNamespace:
    """The simulation with terms, Rust against the NumPy oracle, on a random plant and input.

    A random G of ``order`` (delay half the time), a random Bouc-Wen, a random sine (24-64 samples per
    period) and the terms ``draw_terms(rng)`` with ``extra`` (a play's half-width is scaled by the sine's
    amplitude at x, and a biproper G is made strictly proper beside it: its x steps at the delay's end).
    ``simulate_sine`` and ``simulate_sampled`` (the sine plus noise, its last ``hold_tail`` samples held) of
    ``_core`` and ``reference`` agree to ``rtol = atol / peak = 1e-11``: the same stages in the same order,
    only the rounding of short dot products and libm differs (measured <= 2e-15 of the peak), so 1e-11 still
    catches any difference of method. Returns ``args`` (G and the Bouc-Wen as the core takes them), ``u``,
    ``dt``, ``sub``, ``terms`` and ``rust`` (Rust's sampled run) for the caller's own checks.
    """
    num, den, delay = random_tf(rng, order)
    if order and "play" in extra:
        num = num[-order:]
    plant = random_bouc_wen(rng)
    omega = float(rng.uniform(0.5, 6.0))
    dt = TWO_PI / omega / int(rng.integers(24, 64))
    amp = float(rng.uniform(0.5, 2.5) * rng.choice([-1.0, 1.0]))
    terms = draw_terms(rng)
    terms.update(extra)
    if "play" in terms:
        gain = abs(np.polyval(num, 1j * omega) / np.polyval(den, 1j * omega))
        terms["play"] *= abs(amp) * float(gain)
    args = (num, den, delay, *plant)
    n, sub = 150, 2
    core: Any = _core
    ref: Any = reference

    def agree(rust: Any, oracle: Any) -> None:
        for r, p in zip(rust, oracle):
            np.testing.assert_allclose(r, p, rtol=1e-11, atol=1e-11 * float(np.max(np.abs(p))))

    agree(
        core.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms),
        ref.simulate_sine(*args, amp, omega, dt, n, sub, terms=terms),
    )
    u = amp * np.cos(omega * np.arange(n) * dt) + 0.05 * rng.standard_normal(n)
    if hold_tail:
        u[-hold_tail:] = u[-hold_tail - 1]
    rust = core.simulate_sampled(*args, u, dt, sub, terms=terms)
    agree(rust, ref.simulate_sampled(*args, u, dt, sub, terms=terms))
    return SimpleNamespace(args=args, u=u, dt=dt, sub=sub, terms=terms, rust=rust)


def designs_bench() -> ModuleType:
    """``benches/diagnosis_designs.py``, the designs bench's driver (a script beside the package)."""
    import importlib
    import sys

    benches = str(Path(__file__).resolve().parents[1] / "benches")
    if benches not in sys.path:
        sys.path.insert(0, benches)
    return importlib.import_module("diagnosis_designs")


def designs_case(design: str, name: Any, place: str, size: float, seed: int) -> list[Any]:
    """One case of the designs bench: its plant for ``seed`` (exact G, its own RK4), ``design``'s plan and
    noise, the effect ``name`` at ``place`` sized ``size`` (None: nothing hidden)."""
    dd = designs_bench()
    des = dd.DESIGNS[design]
    p = dd.plant_for(des, seed)
    y, _, _ = dd.outputs(p, des, name, place, size)
    recs: list[Any] = dd.recordings(p, des, y, seed)
    return recs


def diagnose_quietly(recs: list[Any]) -> Any:
    """``bw.diagnose`` with its warnings silenced (the tests read the verdict, not the warnings)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


@pytest.fixture(scope="session")
def helpers() -> SimpleNamespace:
    """The helper functions of this module, as one namespace."""
    return SimpleNamespace(
        BACKENDS=BACKENDS,
        random_stable_den=random_stable_den,
        random_tf=random_tf,
        random_bouc_wen=random_bouc_wen,
        averaged_loop=averaged_loop,
        loop_problem=loop_problem,
        rust_against_oracle=rust_against_oracle,
        designs_bench=designs_bench,
        designs_case=designs_case,
        diagnose_quietly=diagnose_quietly,
    )


@pytest.fixture(scope="session")
def recordings() -> list[bw.Recording]:
    """Two short noisy demo recordings (2 and 5 rad/s, one of negative amplitude), for file and CLI tests."""
    plant = bw.demo_plant()
    plan = bw.SinePlan(
        [2.0, 5.0], [0.5, -0.25], settle_periods=3, periods=2, samples_per_period=64, noise_sd=0.01, seed=4
    )
    return bw.simulate(plant, plan)

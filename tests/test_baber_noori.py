"""The Baber-Noori family beyond strength degradation (issue 18 item 2): stiffness degradation (eta) and
pinching (Foliente's h(w)) as library terms, their simulation (Rust against the NumPy oracle), their values
recovered from data of an independent NumPy integrator written here, and stiffness degradation diagnosed in
drift space beside strength degradation (design.md 9.4, 10.6).
"""

from __future__ import annotations

import json
import math
from typing import Any, Callable

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import drift as D
from bouc_wen_id.errors import InvalidParameterError
from numpy.testing import assert_allclose

TWO_PI = 2.0 * math.pi
ETA = T.StiffnessDegradation.kind
NU = T.Degradation.kind
PINCH = T.Pinching.kind


# ------------------------------------------------------------------ the terms


def test_terms_units_validation_and_round_trip() -> None:
    eta, pin = T.StiffnessDegradation(2e-3), T.Pinching(0.5)
    assert T.TERMS[ETA] is T.StiffnessDegradation and T.TERMS[PINCH] is T.Pinching
    assert eta.symbol == "delta_eta" and pin.symbol == "zeta1"
    assert T.StiffnessDegradation.units(y="N") == "1/N^2" and T.Pinching.units(y="N") == ""
    assert eta.acts_on == pin.acts_on == T.Place.HYSTERESIS
    # Stiffness degradation is diagnosed in drift space, pinching on the steady loop (rate independent).
    assert not T.StiffnessDegradation.steady and T.Pinching.steady
    assert ETA in T.DIAGNOSIS_CANDIDATES and PINCH in T.STEADY_TERM_NAMES
    with pytest.raises(InvalidParameterError, match="delta_eta"):
        T.StiffnessDegradation(-1e-3)
    for bad in (-0.1, 1.0):
        with pytest.raises(InvalidParameterError, match="zeta1"):
            T.Pinching(bad)
    for t in (eta, pin):
        assert T.term_from_dict(json.loads(json.dumps(t.to_dict()))) == t
    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.1, 1.0]), bw.BoucWen(1.2, 0.4, 1.5, alpha=2.0), terms=(eta, pin)
    )
    back = bw.WienerPlant.from_dict(json.loads(json.dumps(plant.to_dict())))
    assert back.terms == plant.terms
    # e = int w dx grows by alpha when x -> alpha x (delta_eta / alpha); the pinching band is in units of the
    # saturation level, which G -> alpha G keeps: zeta1 is unchanged. So y is unchanged.
    norm = plant.normalized()
    assert norm.term(ETA) == T.StiffnessDegradation(1e-3) and norm.term(PINCH) == pin
    plan = bw.SinePlan([2.0], [1.0], settle_periods=0, periods=4, samples_per_period=64, substeps=4)
    a, b = bw.simulate(plant, plan)[0], bw.simulate(norm, plan)[0]
    assert_allclose(a.y, b.y, rtol=0, atol=1e-6 * float(np.max(np.abs(a.y))))


@pytest.mark.parametrize("core", [_core, reference], ids=["rust", "numpy"])
@pytest.mark.parametrize(
    ("terms", "text"), [({ETA: -0.1}, ETA), ({PINCH: 1.0}, PINCH), ({PINCH: -0.2}, PINCH)]
)
def test_bad_values_are_named_errors(core: Any, terms: dict[str, float], text: str) -> None:
    args = (np.array([1.0]), np.array([1.0, 1.0]), 0.0, 1.0, 1.0, 0.2, 1.5, 0.0, 1.0, 2.0, 0.05, 50, 1)
    with pytest.raises(InvalidParameterError, match=text):
        core.simulate_sine(*args, terms=terms)


# ------------------------------------------------------------------ simulation: Rust vs the NumPy oracle

CASES = [
    {ETA: 0.05},
    {PINCH: 0.6},
    {ETA: 0.02, PINCH: 0.4, NU: 0.02, "play": 0.1, "sensor_lag": 0.02, "asymmetry": 0.3, "viscous": 0.1},
]


@pytest.mark.parametrize("terms", CASES, ids=["eta", "pinching", "with-others"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rust_matches_the_oracle(helpers: Any, terms: dict[str, float], seed: int) -> None:
    rng = np.random.default_rng([1818, seed])
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
    # The same RK4 stages in the same order; only libm's and short dot products' rounding differ.
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * float(np.max(np.abs(p))))
    u = amp * np.cos(omega * np.arange(n) * dt) + 0.1 * rng.standard_normal(n)
    xr, wr, yr = core.simulate_sampled(*args, u, dt, sub, terms=terms)
    xn, wn, yn = ref.simulate_sampled(*args, u, dt, sub, terms=terms)
    for r, p in ((xr, xn), (wr, wn), (yr, yn)):
        assert_allclose(r, p, rtol=1e-11, atol=1e-11 * float(np.max(np.abs(p))))
    # The new terms change w: the run without them differs (without the play, which may swallow a small x).
    full = {k: v for k, v in terms.items() if k != "play"}
    plain = {k: v for k, v in full.items() if k not in (ETA, PINCH)}
    _, w_plain, _ = core.simulate_sine(*args, amp, omega, dt, n, sub, terms=plain)
    _, w_full, _ = core.simulate_sine(*args, amp, omega, dt, n, sub, terms=full)
    assert float(np.max(np.abs(w_full - w_plain))) > 1e-5 * float(np.max(np.abs(w_plain)))


def test_zero_values_leave_the_run_bit_identical() -> None:
    # Absent and zero are the same run: the factors are applied only when present.
    rng = np.random.default_rng(5)
    args = (np.array([1.0]), np.array([0.3, 1.0]), 0.1, 1.0, 0.8, 0.3, 1.7, 0.0, 1.5, 2.0, 0.05, 300, 2)
    core: Any = _core
    base = core.simulate_sine(*args, terms={"play": 0.1, NU: 0.01})
    same = core.simulate_sine(*args, terms={"play": 0.1, NU: 0.01, ETA: 0.0, PINCH: 0.0})
    for a, b in zip(base, same):
        assert np.array_equal(a, b)
    assert rng is not None


# ------------------------------------------------------------------ an independent NumPy integrator

#: Saturation level 1 (beta + gamma = 1, alpha = 1).
BETA, GAMMA, MU = 0.7, 0.3, 1.8


class Plant:
    """x from G driven by u = U cos(omega (t - T)) (0 before T): first order ``tc x' = K u - x`` or
    resonant ``x'' + 2 z wn x' + wn^2 x = K wn^2 u``; the Baber-Noori element (nu, eta, Foliente's h)
    on x; y = w. Integrated here by classical RK4 on the whole state ``[x, (v), w, e]``, vectorised over
    the experiments, with x's derivative from the state (no play, no interpolation): another scheme than
    the library's (which integrates w beside a companion realisation, the input interpolated or analytic).
    """

    def __init__(self, kind: str, delay: float) -> None:
        self.kind, self.delay = kind, delay
        self.k, self.tc, self.z, self.wn = 1.0, 0.05, 0.15, TWO_PI * 3.0

    def tf(self) -> bw.TransferFunction:
        if self.kind == "first":
            return bw.TransferFunction([self.k], [self.tc, 1.0], self.delay)
        return bw.TransferFunction(
            [self.k * self.wn**2], [1.0, 2.0 * self.z * self.wn, self.wn**2], self.delay
        )

    def run(
        self,
        omegas: np.ndarray,
        amps: np.ndarray,
        n_periods: int,
        p: int,
        sub: int,
        nu: float = 0.0,
        eta: float = 0.0,
        zeta1: float = 0.0,
    ) -> np.ndarray:
        """w (= y) at the samples, shape (m, n_periods p)."""
        m = omegas.size
        h = TWO_PI / omegas / (p * sub)
        w_u = (1.0 / (BETA + GAMMA)) ** (1.0 / MU)
        q, z2 = T.PINCHING_CENTRE * w_u, T.PINCHING_WIDTH * w_u

        def u(t: np.ndarray) -> np.ndarray:
            tt = t - self.delay
            return np.where(tt >= 0.0, amps * np.cos(omegas * tt), 0.0)

        def f(t: np.ndarray, s: np.ndarray) -> np.ndarray:
            if self.kind == "first":
                xdot = (self.k * u(t) - s[0]) / self.tc
                lin = [xdot]
            else:
                xdot = s[1]
                acc = self.wn**2 * (self.k * u(t) - s[0]) - 2.0 * self.z * self.wn * s[1]
                lin = [xdot, acc]
            w, e = s[-2], s[-1]
            wm = np.abs(w) ** MU
            rate = xdot - (1.0 + nu * e) * (BETA * np.abs(xdot) * np.sign(w) * wm + GAMMA * xdot * wm)
            rate = rate / (1.0 + eta * e)
            rate = rate * (1.0 - zeta1 * np.exp(-((((w * np.sign(xdot)) - q) / z2) ** 2)))
            return np.array([*lin, rate, w * xdot])

        n_lin = 1 if self.kind == "first" else 2
        s = np.zeros((n_lin + 2, m))
        out = np.empty((m, n_periods * p))
        t = np.zeros(m)
        for k in range(n_periods * p):
            out[:, k] = s[-2]
            for _ in range(sub):
                k1 = f(t, s)
                k2 = f(t + h / 2, s + h / 2 * k1)
                k3 = f(t + h / 2, s + h / 2 * k2)
                k4 = f(t + h, s + h * k3)
                s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                t = t + h
        return out


def _records(
    plant: Plant, noise: float, seed: int, settle: int = 6, periods: int = 16, p: int = 64, **terms: float
) -> list[bw.Recording]:
    """Two frequencies by two amplitudes (x at 0.8 and 2 times saturation), from rest; noise sd ``noise``."""
    omegas = np.repeat(TWO_PI * np.array([0.5, 2.0]), 2)
    gains = plant.tf().gain_phase(omegas)[0]
    amps = np.tile([0.8, 2.0], 2) / gains
    n = settle + periods
    w = plant.run(omegas, amps, n, p, 16, **terms)
    rng = np.random.default_rng(seed)
    recs = []
    for i in range(omegas.size):
        t = np.arange(n * p) * TWO_PI / omegas[i] / p
        u = amps[i] * np.cos(omegas[i] * t)
        y = w[i] + noise * rng.standard_normal(t.size)
        recs.append(bw.Recording(t, u, y, amps[i], omegas[i], settle))
    return recs


@pytest.mark.parametrize("kind", ["first", "resonant"])
def test_library_simulation_matches_the_independent_integrator(kind: str) -> None:
    plant = Plant(kind, 0.02)
    omegas, amps = np.array([TWO_PI * 2.0]), np.array([1.5])
    lib = bw.WienerPlant(
        plant.tf(),
        bw.BoucWen(BETA, GAMMA, MU),
        terms=(T.StiffnessDegradation(0.02), T.Pinching(0.5), T.Degradation(0.01)),
    )
    plan = bw.SinePlan(omegas, amps, settle_periods=0, periods=6, samples_per_period=64, substeps=16)
    (rec,) = bw.simulate(lib, plan)
    ours = plant.run(omegas, amps, 6, 64, 16, nu=0.01, eta=0.02, zeta1=0.5)[0]
    # Two RK4 schemes at h = T/1024: they agree to the kinks' O(h^2) (measured ~1e-5 of the peak).
    scale = float(np.max(np.abs(ours)))
    assert float(np.max(np.abs(np.asarray(rec.y) - ours))) < 2e-4 * scale


@pytest.mark.parametrize("kind", ["first", "resonant"])
def test_pinching_is_recovered_from_independent_data(kind: str) -> None:
    """zeta1 by a scalar least squares of the library's simulation against the independent integrator's noisy
    record (the other parameters known): the simulator's term is the integrator's physics."""
    from scipy.optimize import minimize_scalar  # type: ignore[import-untyped]

    plant = Plant(kind, 0.03)
    truth = 0.45
    recs = _records(plant, 0.01, seed=11, settle=4, periods=4, zeta1=truth)
    omegas = np.array([r.frequency for r in recs])
    amps = np.array([r.amplitude for r in recs])

    def cost(z1: float) -> float:
        lib = bw.WienerPlant(plant.tf(), bw.BoucWen(BETA, GAMMA, MU), terms=(T.Pinching(z1),))
        plan = bw.SinePlan(omegas, amps, settle_periods=0, periods=8, samples_per_period=64, substeps=8)
        sims = bw.simulate(lib, plan)
        return float(sum(np.sum((np.asarray(s.y) - np.asarray(r.y)) ** 2) for s, r in zip(sims, recs)))

    res = minimize_scalar(cost, bounds=(0.0, 0.9), method="bounded", options={"xatol": 1e-4})
    # Noise 0.01 on 2048 samples: the estimate's sd is ~1e-3; 0.02 leaves room for the schemes' difference.
    assert abs(float(res.x) - truth) < 0.02, res.x
    assert cost(float(res.x)) < cost(0.0)


# ------------------------------------------------------------------ drift space: eta beside nu


def _fit(recs: list[bw.Recording]) -> tuple[Any, ...]:
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.fitting import fit_plain, scale_of, scaled, substeps_for

    exps = prepare(recs)
    s = scale_of(exps)
    sx = scaled(exps, s)
    sub = substeps_for([e.ybar.size for e in sx])
    return exps, sx, s, sub, fit_plain(exps, sx, s, sub)


def test_first_order_eta_drift_matches_the_independent_record() -> None:
    """Block deviations predicted as d E_i t_b K_i (K_i = -g dy/dg) against the independent integrator's."""
    rate = 5e-4
    recs = _records(Plant("first", 0.0), 1e-7, seed=1, eta=rate)
    exps, sx, s, sub, fit = _fit(recs)
    data = D.drift_data(exps, sx, fit, s.y, sub)
    for dd in data:
        pred = D.predicted_deviation(dd, rate * s.y**2, ETA)
        err = float(np.linalg.norm(dd.dev - pred) / np.linalg.norm(dd.dev))
        # First order in d (the stiffness change over the record is a few per cent).
        assert err < 0.1, (dd.index, err)
        # The strength column alone does not fit it: eta's signature is not nu's.
        other = D.predicted_deviation(dd, rate * s.y**2, NU)
        assert float(np.linalg.norm(dd.dev - other)) > 2 * float(np.linalg.norm(dd.dev - pred))
    test = D.compare(data, s.y, 0.05, family=11)
    assert test is not None and test.term == ETA
    assert test.value == pytest.approx(rate, rel=0.1)


CASES_DIAG: list[tuple[str, float, Callable[[], Plant]]] = [
    ("first", 3e-3, lambda: Plant("first", 0.02)),
    ("resonant", 3e-3, lambda: Plant("resonant", 0.04)),
]


@pytest.mark.parametrize(("name", "rate", "make"), CASES_DIAG, ids=[c[0] for c in CASES_DIAG])
def test_stiffness_degradation_is_named(
    name: str, rate: float, make: Callable[[], Plant], tmp_path: Any
) -> None:
    d = bw.diagnose(_records(make(), 0.01, seed=3, eta=rate))
    assert ETA in d.named_terms, d.summary()
    assert NU not in d.named_terms or any({a.term, a.rival} == {ETA, NU} for a in d.alternatives), d.summary()
    got = next(t for t in d.named if t.term == ETA)
    assert abs(got.value - rate) < max(5 * got.standard_error, 0.1 * rate), d.summary()
    assert d.degradation is not None and d.degradation.term == ETA
    assert json.loads(d.to_json())["degradation"]["term"] == ETA
    assert json.loads(d.to_json())["degradation"]["rival"]["term"] == NU
    summary = d.summary()
    assert f"{ETA} (drift space" in summary and f"rival {NU}:" in summary
    from bouc_wen_id.diagnosis.report import write_report

    write_report(d, tmp_path / "diag")
    page = (tmp_path / "diag" / "report.html").read_text(encoding="utf-8")
    assert f"<td>{ETA}</td>" in page and f"<td>{NU}</td>" in page


@pytest.mark.parametrize(("name", "rate", "make"), CASES_DIAG, ids=[c[0] for c in CASES_DIAG])
def test_strength_degradation_is_told_from_stiffness(
    name: str, rate: float, make: Callable[[], Plant]
) -> None:
    d = bw.diagnose(_records(make(), 0.01, seed=4, nu=rate))
    assert NU in d.named_terms, d.summary()
    assert ETA not in d.named_terms, d.summary()


@pytest.mark.parametrize("kind", ["first", "resonant"])
def test_null_names_neither_drift_term(kind: str) -> None:
    d = bw.diagnose(_records(Plant(kind, 0.03), 0.01, seed=8))
    assert ETA not in d.named_terms and NU not in d.named_terms, d.summary()
    assert d.degradation is not None and not d.degradation.passed
    assert d.degradation.rival is not None and not d.degradation.rival.passed


@pytest.mark.parametrize("kind", ["first", "resonant"])
def test_pinching_is_named_with_its_value(kind: str) -> None:
    """Pinching on the steady loop (the path loop with Foliente's factor): named on the independent
    integrator's pinched records, with zeta1 within 5 standard errors and 5 %, and nothing else named."""
    truth = 0.3
    d = bw.diagnose(_records(Plant(kind, 0.03), 0.01, seed=5, zeta1=truth))
    assert PINCH in d.settings["candidates"]
    assert d.named_terms == (PINCH,), d.summary()
    assert d.status == "explained", d.summary()
    got = d.named[0]
    # Measured 0.297 +- 0.004 (first order and resonant alike).
    assert abs(got.value - truth) < max(5 * got.standard_error, 0.05 * truth), d.summary()
    # Its signature before: odd harmonics 3 and 5 above the noise floor.
    assert {3, 5} <= set(d.before.significant_harmonics()), d.summary()
    assert d.degradation is not None and not d.degradation.passed
    assert d.degradation.rival is not None and not d.degradation.rival.passed


def _synthetic(jac_eta_of: Callable[[np.ndarray], np.ndarray], seed: int) -> list[D.DriftData]:
    """Block deviations made of strength drift d E t J plus unit-weight noise, with a chosen eta column."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(4):
        k, b = 6, 8
        jac = rng.standard_normal(k) + 1j * rng.standard_normal(k)
        jac[0] = jac[0].real
        t = np.arange(b) - (b - 1) / 2.0
        energy = 1.0 + i
        # Unit chi-square per real component under the drift space's inner product (DC real, the rest x 1/2).
        noise = math.sqrt(2.0) * (rng.standard_normal((b, k)) + 1j * rng.standard_normal((b, k)))
        noise[:, 0] = rng.standard_normal(b)
        dev = 0.2 * energy * t[:, None] * jac[None, :] + noise
        dev -= dev.mean(axis=0)
        grid = np.zeros(8)
        dev_c = np.asarray(dev, dtype=np.complex128)
        t_f = np.asarray(t, dtype=np.float64)
        out.append(D.DriftData(i, dev_c, t_f, np.ones(b), energy, jac, grid, 3.0, jac_eta=jac_eta_of(jac)))
    return out


def test_parallel_drift_columns_are_alternatives() -> None:
    """Where the record cannot tell stiffness from strength (parallel columns), the rival is an alternative;
    where the columns are orthogonal, strength is chosen and stiffness does not pass."""
    same = D.compare(_synthetic(lambda j: 1.001 * j, 0), 1.0, 0.05, family=2)
    assert same is not None and same.rival is not None
    assert same.passed and same.rival.passed and same.rival_alternative
    assert abs(same.correlation) > 0.999
    other = D.compare(_synthetic(lambda j: 1j * j, 0), 1.0, 0.05, family=2)
    assert other is not None and other.rival is not None
    assert other.term == NU and other.passed and not other.rival.passed and not other.rival_alternative
    assert json.loads(json.dumps(same.to_dict()))["rival_is_alternative"] is True
    # The diagnosis reports it with the experiment that separates the two.
    from bouc_wen_id.diagnosis.run import SEPARATING_DRIFT, _drift_alternatives

    (alt,) = _drift_alternatives(same, True)
    assert {alt.term, alt.rival} == {NU, ETA} and alt.separating_experiment == SEPARATING_DRIFT
    assert _drift_alternatives(other, True) == () and _drift_alternatives(same, False) == ()

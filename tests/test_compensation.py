"""Feedforward compensation (issue 21, item 1): the inverse composed with the forward model gives y_ref.

The claims are checked on forward models made another way where it matters: the hysteresis inverse against
an RK4 along the path written here, the whole compensator against the bench's plant simulator
(``benches/compensation.py``: ``scipy.signal.lsim`` for G, its own path RK4), besides the library's RK4.
"""

from __future__ import annotations

import importlib
import math
import sys
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.compensation import invert_hysteresis, saturation_levels
from bouc_wen_id.terms import (
    Asymmetry,
    Coulomb,
    Offset,
    Play,
    SensorLag,
    SeriesDashpot,
    Stiffness,
    StiffnessX,
    ViscousX,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("compensation")

TWO_PI = 2.0 * math.pi
HY = bw.BoucWen(0.7, 0.3, 1.5)


def _forward_path(x: np.ndarray, hy: bw.BoucWen, delta: float, sub: int = 64) -> np.ndarray:
    """Bouc-Wen by RK4 in x, ``sub`` steps per sample, x linear between samples (from x = 0, w = w0)."""

    def f(w: float, s: float) -> float:
        sw = math.copysign(1.0, w) if w != 0 else 0.0
        return float(hy.alpha - abs(w) ** hy.mu * (hy.beta * s * sw + hy.gamma + delta * sw))

    out = np.empty_like(x)
    w, prev = hy.w0, 0.0
    for k, xk in enumerate(x.tolist()):
        h = (xk - prev) / sub
        s = 1.0 if h > 0 else -1.0
        for _ in range(sub):
            k1 = f(w, s) * h
            k2 = f(w + 0.5 * k1, s) * h
            k3 = f(w + 0.5 * k2, s) * h
            k4 = f(w + k3, s) * h
            w += (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
        out[k], prev = w, xk
    return out


def _reference(
    n: int, seconds: float, hz: float, level: float, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """A faded-in two-tone reference (seeded phase), at ``level`` of saturation."""
    t = np.linspace(0.0, seconds, n, endpoint=False)
    ph = np.random.default_rng(seed).uniform(0, TWO_PI)
    r = np.sin(TWO_PI * hz * t) + 0.4 * np.sin(TWO_PI * 2.7 * hz * t + ph)
    fade = np.minimum(t / (0.15 * seconds), 1.0) ** 3
    return t, level * fade * r / np.max(np.abs(r))


def _interior_error(y: np.ndarray, ref: np.ndarray) -> float:
    k = ref.size // 10
    return float(np.sqrt(np.mean((y - ref)[k:-k] ** 2)) / np.std(ref[k:-k]))


@pytest.mark.parametrize("delta", [0.0, 0.25, -0.25])
@pytest.mark.parametrize("seed", [1, 2])
def test_hysteresis_inverse_composed_with_an_independent_forward_path(delta: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    down, up = saturation_levels(HY, delta)
    # A random walk of w with reversals, kept within 95 % of the saturation levels.
    steps = rng.normal(0, 0.02, 600)
    w = np.clip(np.cumsum(steps), -0.95 * down, 0.95 * up)
    x = invert_hysteresis(w, HY, delta)
    back = _forward_path(x, HY, delta)
    assert np.max(np.abs(back - w)) < 1e-8
    # The path does reach the steep part near saturation, where 1/h is large.
    assert np.max(np.abs(x)) > 1.5 * np.max(np.abs(w))


def test_hysteresis_inverse_refuses_the_saturation_and_non_finite_samples() -> None:
    _, up = saturation_levels(HY)
    with pytest.raises(bw.UnreachableReferenceError, match="outside its range"):
        invert_hysteresis([0.1, 0.5, up], HY)
    with pytest.raises(bw.NonFiniteError):
        invert_hysteresis([0.1, float("nan")], HY)
    # Asymmetry moves the two levels apart: delta > 0 lowers the upper one.
    d_down, d_up = saturation_levels(HY, 0.3)
    assert d_up < up < d_down


def test_relative_degree_zero_plant_is_reproduced_to_integration_accuracy() -> None:
    # G = 2 (s + 50)/(s + 200) with a 3 ms delay: no filter needed, the delay by preview.
    g = bw.TransferFunction([2.0, 100.0], [1.0, 200.0], 0.003)
    plant = bw.WienerPlant(g, HY)
    errors = []
    for n in (1000, 2000, 4000):
        t, ref = _reference(n, 1.0, 3.0, 0.8)
        c = bw.compensate(plant, ref, t)
        assert c.filter_order == 0 and math.isnan(c.cutoff) and c.preview == 0.003
        assert "preview" in c.choices["delay"] and "none needed" in c.choices["filter"]
        _, _, y = bw.simulate_input(plant, t, c.u, output=True)
        np.testing.assert_allclose(y, c.y_predicted, rtol=0, atol=1e-12)
        errors.append(float(np.max(np.abs(y - ref))))
    assert errors[-1] < 2e-5
    # Integration accuracy: the error falls with the step (a 4x finer step: about 9x, order ~1.6 at the
    # reversals, where the forward interpolant of u is not monotone within a sample).
    assert errors[0] / errors[-1] > 6


def test_resonant_delayed_plant_on_an_independent_simulator() -> None:
    case = bench.cases()[0]
    t, ref = _reference(6000, 0.6, 8.0, 0.7, seed=3)
    c = bw.compensate(case.plant, ref, t)
    assert c.filter_order == 4 and c.cutoff > TWO_PI * 8.0 * 10
    y = bench.plant_output(case.plant, t, c.u)
    err = _interior_error(y, ref)
    # The uncompensated (static gain) command misses by tens of percent; the compensated one by < 1 %.
    g0 = float(np.real(case.plant.linear(0.0)))
    y_none = bench.plant_output(case.plant, t, ref / g0)
    assert err < 0.01
    assert _interior_error(y_none, ref) > 20 * err


def test_nonminimum_phase_zero_stable_inversion_beats_mirroring() -> None:
    case = bench.cases()[1]  # the damper: a right-half-plane zero at 60 Hz, a resonance, a delay
    t, ref = _reference(8000, 2.0, 2.0, 0.8, seed=4)
    stable = bw.compensate(case.plant, ref, t)
    mirror = bw.compensate(case.plant, ref, t, nmp="mirror")
    assert "stable inversion" in stable.choices["nonminimum_phase"]
    assert "mirror" in mirror.choices["nonminimum_phase"]
    e_stable = _interior_error(bench.plant_output(case.plant, t, stable.u), ref)
    e_mirror = _interior_error(bench.plant_output(case.plant, t, mirror.u), ref)
    assert e_stable < 0.005
    assert e_mirror > 3 * e_stable


def test_terms_on_u_are_solved_jointly() -> None:
    case = bench.cases()[2]  # piezo with offset, stiffness, viscous damping and a sensor lag
    t, ref = _reference(6000, 0.6, 8.0, 0.7, seed=5)
    ref = ref + 0.05  # the offset: the reference starts at the rest output
    c = bw.compensate(case.plant, ref, t)
    for word in ("offset", "sensor lag", "stiffness", "viscous"):
        assert word in c.choices["terms"]
    assert c.iterations > 0
    y = bench.plant_output(case.plant, t, c.u)
    assert _interior_error(y, ref) < 0.01
    # Ignoring the terms (the plain plant's inverse) misses by far more.
    plain = bw.WienerPlant(case.plant.linear, case.plant.hysteresis)
    c0 = bw.compensate(plain, ref - 0.05, t)
    assert _interior_error(bench.plant_output(case.plant, t, c0.u), ref) > 10 * _interior_error(y, ref)


def test_terms_across_the_hysteretic_element_are_solved_through_g() -> None:
    """Review 36: a model from ``diagnose --model`` with a term named "on x" (to_model's StiffnessX,
    ViscousX) was refused ("does not handle this term yet") where the CLI's help promises compensate takes
    it. Checked on the bench's own plant simulator (scipy's lsim for G, its own path RK4)."""
    lin = bw.TransferFunction([1.0], [0.004, 1.0])
    plant = bw.WienerPlant(lin, HY, (StiffnessX(0.15), ViscousX(0.004)))
    t, ref = _reference(6000, 0.6, 8.0, 0.7, seed=11)
    c = bw.compensate(plant, ref, t)
    assert c.iterations > 0 and "viscous" in c.choices["terms"]
    y = bench.plant_output(plant, t, c.u)
    err = _interior_error(y, ref)
    assert err < 0.01
    # The plain plant's inverse, or the same terms taken on u, miss by far more.
    c0 = bw.compensate(bw.WienerPlant(lin, HY), ref, t)
    assert _interior_error(bench.plant_output(plant, t, c0.u), ref) > 10 * err
    on_u = bw.WienerPlant(lin, HY, (Stiffness(0.15), bw.terms.Viscous(0.004)))
    cu = bw.compensate(on_u, ref, t)
    assert _interior_error(bench.plant_output(plant, t, cu.u), ref) > 3 * err


def test_refinement_lowers_the_predicted_error_of_a_plain_model() -> None:
    plant = bench.cases()[0].plant
    t, ref = _reference(3000, 0.6, 8.0, 0.7, seed=6)
    direct = bw.compensate(plant, ref, t)
    refined = bw.compensate(plant, ref, t, refine=5)
    assert refined.iterations >= 1
    assert refined.tracking_error < direct.tracking_error


def test_identification_result_is_compensated_with_its_fitted_g() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [0.01, 1.0]), HY)
    plan = bw.SinePlan([5.0, 20.0, 50.0, 100.0, 300.0], 2.0, settle_periods=5, periods=10, noise_sd=0.005)
    res = bw.identify(bw.simulate(plant, plan))
    t, ref = _reference(4000, 2.0, 1.5, 0.7, seed=7)
    c = bw.compensate(res, ref, t)
    assert "G fitted to the identified points" in c.choices["model"]
    y = bench.plant_output(plant, t, c.u)
    assert _interior_error(y, ref) < 0.03


def test_amplitude_and_rate_limits_are_respected_and_reported() -> None:
    plant = bench.cases()[0].plant
    t, ref = _reference(3000, 0.6, 8.0, 0.7, seed=8)
    free = bw.compensate(plant, ref, t)
    peak = float(np.max(np.abs(free.u)))
    rate = float(np.max(np.abs(np.diff(free.u)))) / (t[1] - t[0])
    c = bw.compensate(plant, ref, t, u_max=0.8 * peak, rate_max=0.7 * rate)
    assert np.max(np.abs(c.u)) <= 0.8 * peak * (1 + 1e-12)
    assert np.max(np.abs(np.diff(np.concatenate(([0.0], c.u))))) <= 0.7 * rate * (t[1] - t[0]) * (1 + 1e-9)
    kinds = {h.kind: h for h in c.limits}
    assert set(kinds) == {"amplitude", "rate"}
    amp = kinds["amplitude"]
    assert amp.samples == int(np.sum(np.abs(free.u) > 0.8 * peak))
    assert amp.worst_excess == pytest.approx(0.2 * peak, rel=1e-9)
    assert amp.first_time == pytest.approx(t[np.argmax(np.abs(free.u) > 0.8 * peak)])
    assert kinds["rate"].worst_excess > 0 and kinds["rate"].spans
    np.testing.assert_array_equal(c.u_unlimited, free.u)
    assert "bound" in c.summary()
    # Limits that never bind are not reported.
    loose = bw.compensate(plant, ref, t, u_max=2 * peak, rate_max=2 * rate)
    assert loose.limits == ()
    np.testing.assert_allclose(loose.u, free.u)


def test_named_errors() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [0.01, 1.0]), HY)
    t, ref = _reference(500, 1.0, 2.0, 0.7)
    with pytest.raises(bw.UnreachableReferenceError, match="saturates"):
        bw.compensate(plant, ref / 0.7 * 1.01, t)
    bad = ref.copy()
    bad[10] = np.inf
    with pytest.raises(bw.NonFiniteError):
        bw.compensate(plant, bad, t)
    jitter = t.copy()
    jitter[100] += 0.3 * (t[1] - t[0])
    with pytest.raises(bw.TimeAxisError):
        bw.compensate(plant, ref, jitter)
    with pytest.raises(bw.InvalidParameterError, match="equal lengths"):
        bw.compensate(plant, ref[:-1], t)
    with pytest.raises(bw.InvalidParameterError, match="u_max"):
        bw.compensate(plant, ref, t, u_max=-1.0)
    with pytest.raises(bw.InvalidParameterError, match="nmp"):
        bw.compensate(plant, ref, t, nmp="zpetc")  # type: ignore[arg-type]
    with pytest.raises(bw.InvalidParameterError, match="does not handle"):
        bw.compensate(bw.WienerPlant(plant.linear, HY, (Play(0.1),)), ref, t)
    with pytest.raises(bw.InvalidParameterError, match="does not handle"):
        bw.compensate(bw.WienerPlant(plant.linear, HY, (SeriesDashpot(0.1),)), ref, t)
    with pytest.raises(bw.InvalidParameterError, match="inertia across the hysteretic element"):
        bw.compensate(bw.WienerPlant(plant.linear, HY, (bw.terms.InertiaX(0.001),)), ref, t)
    with pytest.raises(bw.UnreachableReferenceError, match="imaginary axis"):
        bw.compensate(bw.WienerPlant(bw.TransferFunction([1.0, 0.0], [1.0, 1.0]), HY), ref, t)
    with pytest.raises(bw.InvalidParameterError, match="WienerPlant or an IdentificationResult"):
        bw.compensate("plant", ref, t)  # type: ignore[arg-type]


def test_terms_accepted_and_reported() -> None:
    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.002, 1.0]),
        HY,
        (Offset(0.1), Asymmetry(0.2), SensorLag(0.001), Stiffness(0.1), Coulomb(0.01)),
    )
    t, ref = _reference(2000, 1.0, 2.0, 0.6)
    c = bw.compensate(plant, ref + 0.1, t)
    assert "asymmetry delta = 0.2" in c.choices["hysteresis"]
    assert "coulomb" in c.choices["terms"] and "offset y0 = 0.1" in c.choices["terms"]
    assert _interior_error(c.y_predicted, ref + 0.1) < 0.03


# ------------------------------------------------------------------------------------------------------
# Parity: the Rust kernels (rust/compensate.rs) against their NumPy oracle (reference/compensate.py)


@pytest.mark.parametrize("seed", range(6))
def test_invert_path_parity_on_random_inputs(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    beta = rng.uniform(0.2, 2.0)
    gamma = rng.uniform(-0.9 * beta, beta)
    alpha, mu = rng.uniform(0.5, 2.0), rng.uniform(1.0, 3.0)
    delta = rng.uniform(-0.8, 0.8) * (beta + gamma)
    hy = bw.BoucWen(beta, gamma, mu, alpha)
    down, up = saturation_levels(hy, delta)
    w = np.clip(np.cumsum(rng.normal(0, 0.05 * up, 500)), -0.97 * down, 0.97 * up)
    w0 = float(rng.uniform(-0.5 * down, 0.5 * up))
    x0 = float(rng.normal())
    args = (alpha, beta, gamma, mu, delta, w0, x0)
    rust = bw._backend.get_backend("rust").compensate.invert_path(w, *args)
    ref = bw._backend.get_backend("numpy").compensate.invert_path(w, *args)
    np.testing.assert_allclose(rust, ref, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(ref))))


@pytest.mark.parametrize("seed", range(4))
def test_rate_limit_parity_on_random_inputs(seed: int) -> None:
    rng = np.random.default_rng(200 + seed)
    target = np.cumsum(rng.normal(0, 1.0, 400))
    step, start = float(rng.uniform(0.1, 1.5)), float(rng.normal())
    rust = bw._backend.get_backend("rust").compensate.rate_limit(target, step, start)
    ref = bw._backend.get_backend("numpy").compensate.rate_limit(target, step, start)
    np.testing.assert_allclose(rust, ref, rtol=0, atol=1e-12)
    assert np.max(np.abs(np.diff(np.concatenate(([start], rust))))) <= step * (1 + 1e-12)


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_kernel_errors_are_the_same_named_ones(backend: str) -> None:
    core = bw._backend.get_backend(backend).compensate
    with pytest.raises(bw.NonFiniteError):
        core.invert_path(np.array([0.1, np.nan]), 1.0, 0.7, 0.3, 1.5, 0.0, 0.0, 0.0)
    with pytest.raises(bw.InvalidParameterError, match="invertible range"):
        core.invert_path(np.array([0.1, 1.0]), 1.0, 0.7, 0.3, 1.5, 0.0, 0.0, 0.0)
    with pytest.raises(bw.InvalidParameterError, match="invertible range"):
        core.invert_path(np.array([0.1]), 1.0, 0.3, 0.7, 1.5, 0.0, 0.0, 0.0)  # beta < gamma
    with pytest.raises(bw.InvalidParameterError, match="step"):
        core.rate_limit(np.array([1.0]), 0.0, 0.0)


def test_compensate_numpy_backend_agrees_with_rust() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [0.005, 1.0], 0.002), HY)
    t, ref = _reference(400, 1.0, 2.0, 0.7, seed=9)
    rust = bw.compensate(plant, ref, t, rate_max=5.0)
    ref_np = bw.compensate(plant, ref, t, rate_max=5.0, backend="numpy")
    np.testing.assert_allclose(rust.x_reference, ref_np.x_reference, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(rust.u, ref_np.u, rtol=1e-9, atol=1e-10)
    assert [h.kind for h in rust.limits] == [h.kind for h in ref_np.limits] == ["rate"]

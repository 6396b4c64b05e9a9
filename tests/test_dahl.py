"""Dahl friction (docs/diagnosis.md, "Dahl friction"): the registry's two-term element, the closed-form
steady loop and its Jacobian (Rust against the NumPy oracle and central differences), and the closed form
against an independent time integration of Dahl's ODE (scipy's solve_ivp, from rest, after settling)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id import terms as T
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.reference import augmented as ra
from bouc_wen_id.reference import dahl as rd
from numpy.testing import assert_allclose

DAHL, SIGMA = T.Dahl.kind, T.DahlSigma.kind
DAHL_X, SIGMA_X = T.DahlX.kind, T.DahlSigmaX.kind
TWO_PI = 2.0 * math.pi
core: Any = _core


# ------------------------------------------------------------------ the registry terms


def test_registry_pairs_places_ranges_and_candidacy() -> None:
    assert T.Dahl.at(T.Place.X) is T.DahlX and T.DahlSigma.at(T.Place.X) is T.DahlSigmaX
    assert T.DahlX.companion == SIGMA_X and T.DahlSigmaX.part_of == DAHL_X
    assert T.Dahl.companion == SIGMA and T.DahlSigma.part_of == DAHL
    # The element is one candidate per place: its second parameter is added with it, never alone.
    assert DAHL in T.DIAGNOSIS_CANDIDATES and DAHL_X in T.DIAGNOSIS_CANDIDATES
    assert SIGMA not in T.DIAGNOSIS_CANDIDATES and SIGMA_X not in T.DIAGNOSIS_CANDIDATES
    assert all(k in T.STEADY_TERM_NAMES for k in (DAHL, SIGMA, DAHL_X, SIGMA_X))
    with pytest.raises(InvalidParameterError, match="dahl fc"):
        T.Dahl(-0.1)
    with pytest.raises(InvalidParameterError, match="sigma"):
        T.DahlSigmaX(-1.0)
    # On x, sigma multiplies x: G -> alpha G divides it by alpha; Fc is a force and stays.
    assert T.DahlSigmaX(2.0).normalized(4.0) == T.DahlSigmaX(0.5)
    assert T.DahlX(0.3).normalized(4.0) == T.DahlX(0.3)
    assert T.term_from_dict(T.DahlX(0.25).to_dict()) == T.DahlX(0.25)


def test_start_pairs_span_the_shapes_at_the_residual_size() -> None:
    ctx = T.StartContext(
        (0.5, 2.0, 1.0), 10.0, 0.5, 0.5, lambda: 0.0, residual_rms=0.04, input_amplitudes=(3.0,)
    )
    for cls, amp in ((T.DahlX, 1.0), (T.Dahl, 3.0)):
        pairs = cls.start_pairs(ctx)
        shapes = [sigma * amp / fc for fc, sigma in pairs]
        assert_allclose(shapes, T.Dahl.START_SHAPES, rtol=1e-12)
        # The loop's top F_top = Fc tanh(r) is 2 (1 + r / 2) residual RMS: twice it for a spring-like loop,
        # more for a sharp one, whose square body the plain Bouc-Wen element takes, leaving its corners.
        tops = [fc * math.tanh(r) for (fc, _), r in zip(pairs, shapes)]
        assert_allclose(tops, [0.08 * (1.0 + 0.5 * r) for r in T.Dahl.START_SHAPES], rtol=1e-12)


# ------------------------------------------------------------------ steady loop: Rust vs oracle, Jacobian


OTHERS = ["offset", "sensor_lag", "stiffness@x", "coulomb@x", "viscous", "asymmetry", "play"]


def _case(rng: np.random.Generator, places: list[str], others: list[str]) -> tuple[Any, ...]:
    p = int(rng.integers(24, 80))
    beta = float(rng.uniform(0.3, 1.0))
    gamma = float(rng.uniform(-0.2, 0.9)) * beta
    mu = float(rng.uniform(1.2, 2.5))
    names: list[str] = []
    values: list[float] = []
    for tag in places:
        names += [f"{DAHL}{tag}", f"{SIGMA}{tag}"]
        # Fc and sigma over decades, 0 included (no friction; the sharp limit of Fc = 0).
        values += [float(rng.choice([0.0, 10 ** rng.uniform(-2, 0)])), float(10 ** rng.uniform(-2, 1.5))]
    extra = {
        "offset": float(rng.normal()),
        "sensor_lag": float(rng.uniform(0.0, 0.1)),
        "stiffness@x": float(rng.uniform(0.0, 0.5)),
        "coulomb@x": float(rng.uniform(0.0, 0.2)),
        "viscous": float(rng.normal()) * 0.1,
        "asymmetry": float(rng.uniform(-0.5, 0.5)) * (beta + gamma),
        "play": 0.05,
    }
    order = rng.permutation(len(names) + len(others))
    allnames = names + others
    allvalues = values + [extra[n] for n in others]
    names = [allnames[k] for k in order]
    shared = np.array([beta, gamma, mu, *(allvalues[k] for k in order)])
    amp = float(rng.uniform(0.5, 2.0)) * float(rng.choice([-1.0, 1.0]))
    omega, psi = float(rng.uniform(0.5, 6.0)), float(rng.uniform(-3, 3))
    gain, phase = float(rng.uniform(0.5, 2.0)) * float(rng.choice([-1.0, 1.0])), float(rng.uniform(-3, 3))
    return (p, amp, omega, psi, names, shared, gain, phase, int(rng.integers(1, 4)))


def _random_case(seed: int) -> tuple[Any, ...]:
    rng = np.random.default_rng([7151, seed])
    places = [["", "@x"], [""], ["@x"]][seed % 3]
    others = list(rng.permutation(OTHERS)[: rng.integers(0, 4)])
    return _case(rng, places, others)


@pytest.mark.parametrize("seed", range(12))
def test_steady_output_rust_matches_the_oracle(seed: int) -> None:
    args = _random_case(seed)
    r = core.augmented_output(*args)
    n = ra.augmented_output(*args)
    for a, b in zip(r, n):
        assert a.shape == b.shape
        assert_allclose(a, b, rtol=0, atol=1e-10 * max(1.0, float(np.max(np.abs(b)))))


@pytest.mark.parametrize("seed", range(6))
def test_jacobian_matches_central_differences(seed: int) -> None:
    p, amp, omega, psi, names, shared, gain, phase, sub = _random_case(100 + seed)
    # Away from the null: the columns are those of the closed form (Fc = 0 is its sharp limit).
    shared = np.array([v if v > 0 else 0.1 for v in shared[:3]] + [abs(v) + 0.05 for v in shared[3:]])
    for k, n in enumerate(names):
        if n in ("asymmetry", "viscous", "offset"):
            shared[3 + k] = 0.05
    _, js, jo = core.augmented_output(p, amp, omega, psi, names, shared, gain, phase, 256)
    h = 1e-6

    def y(sh: np.ndarray, g: float, ph: float) -> np.ndarray:
        out: np.ndarray = core.augmented_output(p, amp, omega, psi, names, sh, g, ph, 256)[0]
        return out

    cols = [k for k, n in enumerate(names) if n.split("@")[0] in (DAHL, SIGMA)]
    for k in cols:
        e = np.zeros(shared.size)
        e[3 + k] = h
        fd = (y(shared + e, gain, phase) - y(shared - e, gain, phase)) / (2 * h)
        assert_allclose(fd, js[:, 3 + k], rtol=0, atol=1e-6 * max(1e-3, float(np.max(np.abs(js[:, 3 + k])))))
    for c, (dg, dp) in enumerate(((h, 0.0), (0.0, h))):
        fd = (y(shared, gain + dg, phase + dp) - y(shared, gain - dg, phase - dp)) / (2 * h)
        assert_allclose(fd, jo[:, c], rtol=0, atol=1e-6 * max(1e-3, float(np.max(np.abs(jo[:, c])))))


def test_pairs_and_ranges_are_named_errors_in_both() -> None:
    base = (32, 1.0, 2.0, 0.3)
    for names, shared, text in (
        ([DAHL_X], [0.5, 0.2, 1.5, 0.1], "given together"),
        ([SIGMA, DAHL_X], [0.5, 0.2, 1.5, 0.1, 0.1], "given together"),
        ([DAHL, SIGMA], [0.5, 0.2, 1.5, -0.1, 0.1], ">= 0"),
        ([DAHL_X, SIGMA_X], [0.5, 0.2, 1.5, 0.1, -0.1], ">= 0"),
    ):
        for f in (core.augmented_output, ra.augmented_output):
            with pytest.raises(InvalidParameterError, match=text):
                f(*base, names, np.array(shared), 1.0, 0.2, 2)


# ------------------------------------------------------------------ the closed form against Dahl's ODE


def _ode_loop(a: float, omega: float, psi0: float, fc: float, sigma: float, p: int) -> np.ndarray:
    """Dahl's ODE ``F' = sigma v' (1 - sgn(v') F / Fc)`` under ``v = a cos(omega t + psi0)`` from rest
    (F = 0 at t = 0), by scipy's solve_ivp (LSODA at tight tolerances, steps below 1/400 period so that no
    reversal is stepped over) over 6 periods; the last period on the P-point grid."""
    from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

    def rhs(t: float, f: np.ndarray) -> list[float]:
        vd = -a * omega * math.sin(omega * t + psi0)
        return [sigma * vd * (1.0 - math.copysign(1.0, vd) * f[0] / fc)]

    period = TWO_PI / omega
    t_eval = 5 * period + period * np.arange(p) / p
    sol = solve_ivp(
        rhs,
        (0.0, 6 * period),
        [0.0],
        method="LSODA",
        t_eval=t_eval,
        rtol=1e-11,
        atol=1e-13,
        max_step=period / 400,
    )
    assert sol.success
    out: np.ndarray = sol.y[0]
    return out


@pytest.mark.parametrize(("a", "fc", "sigma"), [(1.0, 0.2, 0.3), (-1.5, 0.1, 2.0), (0.7, 0.05, 10.0)])
def test_closed_form_is_the_settled_ode(a: float, fc: float, sigma: float) -> None:
    p, omega, psi0 = 64, 2.0, 0.7
    ode = _ode_loop(a, omega, psi0, fc, sigma, p)
    # The oracle's closed form, and Rust's through the augmented model (its output minus the plain one's).
    f = rd.dahl_loop(a, psi0, fc, sigma, p)[0]
    sh = np.array([0.6, 0.3, 1.5])
    plain = core.augmented_output(p, a, omega, psi0, [], sh, 1.0, 0.4, 4)[0]
    with_dahl = core.augmented_output(
        p, a, omega, psi0, [DAHL, SIGMA], np.append(sh, [fc, sigma]), 1.0, 0.4, 4
    )[0]
    # A transient from rest decays as exp(-sigma travel / Fc): after 5 periods it is far below 1e-7.
    assert_allclose(f, ode, rtol=0, atol=1e-7 * fc)
    assert_allclose(with_dahl - plain, ode, rtol=0, atol=1e-7 * fc)
    # On x: the loop follows x = U g cos(theta - phi).
    g, phi = -0.8, 0.9
    on_x = core.augmented_output(
        p, 1.3, omega, psi0, [DAHL_X, SIGMA_X], np.append(sh, [fc, sigma]), g, phi, 4
    )[0]
    plain_x = core.augmented_output(p, 1.3, omega, psi0, [], sh, g, phi, 4)[0]
    assert_allclose(on_x - plain_x, _ode_loop(1.3 * g, omega, -phi, fc, sigma, p), rtol=0, atol=1e-7 * fc)


def test_limits_are_dry_friction_and_a_spring() -> None:
    p, a, psi0 = 128, 1.2, 0.3
    theta = TWO_PI * np.arange(p) / p + psi0
    # sigma -> inf: the sign of the velocity at level Fc (away from the reversals); Fc -> inf: sigma v.
    f_sharp = rd.dahl_loop(a, psi0, 0.3, 1e6, p)[0]
    away = np.abs(np.sin(theta)) > 0.05
    assert_allclose(f_sharp[away], -0.3 * np.sign(np.sin(theta[away])), atol=1e-6)
    f_spring = rd.dahl_loop(a, psi0, 1e6, 0.7, p)[0]
    assert_allclose(f_spring, 0.7 * a * np.cos(theta), atol=1e-5)


def test_simulation_takes_dahl_friction() -> None:
    """Its time-domain form is in the simulator (tests/test_simulation_dahl.py): the core gets its values."""
    for term in (T.Dahl(0.1), T.DahlSigmaX(1.0)):
        assert T.core_terms([term]) == {term.rust_kind: term.value}


@pytest.mark.parametrize("term", [T.Dahl(0.1), T.DahlX(0.1), T.DahlSigmaX(1.0)], ids=lambda t: t.kind)
def test_exporters_take_it_and_compensation_refuses_it_by_name(term: T.Term) -> None:
    """The exporters write its force as a state (tests/test_export_dahl.py); compensation refuses it with its
    reason."""
    import bouc_wen_id as bw
    from bouc_wen_id.compensation import compensate
    from bouc_wen_id.export import EXPORTED
    from bouc_wen_id.export._model import field_of, flatten

    assert type(term) in EXPORTED
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [0.1, 1.0]), bw.BoucWen(0.5, 0.5, 2.0), (term,))
    assert getattr(flatten(plant, "C export"), field_of(type(term))) == term.value
    t = np.arange(200) * 0.01
    with pytest.raises(InvalidParameterError, match=term.kind):
        compensate(plant, 0.1 * np.sin(TWO_PI * t), t)

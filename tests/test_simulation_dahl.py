"""Dahl friction's time-domain form (``rust/simulate/with_terms/dahl.rs``): its force ``F`` integrated as one
more RK4 state, ``F' = sigma v' (1 - sgn(v') F / Fc)``, on the measured input u or on x across the element.

Rust against the NumPy oracle on seeded random plants and inputs; the record against scipy's ``solve_ivp``
of the ODE (a state-space G written here, resonant with a delay, and first order); the last period of a long
sine against the closed-form steady loop of ``rust/dahl.rs`` (its oracle ``reference.dahl``, no time loop);
and the things that still refuse it, by name (the exporters take it: tests/test_export_dahl.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id.cli import main
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.model import BoucWen, SinePlan, TransferFunction, WienerPlant
from bouc_wen_id.terms import Dahl, DahlSigma, Place, SensorLag, Term, Viscous
from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

TWO_PI = 2.0 * math.pi
ON_U = (Dahl.kind, DahlSigma.kind)
ON_X = (Dahl.at(Place.X).kind, DahlSigma.at(Place.X).kind)


def _dahl(fc: float, sigma: float, place: Place = Place.INPUT) -> tuple[Term, ...]:
    """Dahl friction's two terms at ``place``."""
    return (Dahl.at(place)(fc), DahlSigma.at(place)(sigma))  # type: ignore[call-arg]


def _scale(a: np.ndarray) -> float:
    return float(np.max(np.abs(a)))


@pytest.mark.parametrize("order", [0, 1, 2])
@pytest.mark.parametrize("extra", [{}, {"sensor_lag": 0.04}, {"play": 0.1}], ids=["dahl", "lag", "play"])
@pytest.mark.parametrize("seed", [0, 1])
def test_rust_matches_the_oracle_with_dahl_friction(
    helpers: Any, order: int, extra: dict[str, float], seed: int
) -> None:
    rng = np.random.default_rng([2026, order, seed])

    def draw(rng: np.random.Generator) -> dict[str, float]:
        terms = {ON_U[0]: float(rng.uniform(0.05, 0.5)), ON_U[1]: float(rng.uniform(0.2, 3.0))}
        return terms | {ON_X[0]: float(rng.uniform(0.05, 0.5)), ON_X[1]: float(rng.uniform(0.2, 3.0))}

    run = helpers.rust_against_oracle(rng, order, draw, extra)
    args, u, dt, sub, terms, rust = run.args, run.u, run.dt, run.sub, run.terms, run.rust
    core: Any = _core
    # The friction changes y: the run without it differs.
    bare = {k: v for k, v in terms.items() if k not in ON_U + ON_X}
    assert _scale(rust[2] - core.simulate_sampled(*args, u, dt, sub, terms=bare)[2]) > 1e-3


@pytest.mark.parametrize("shape", ["resonant-delay", "first-order"])
def test_the_friction_force_matches_solve_ivp_of_the_ode(shape: str) -> None:
    """``y - w`` (the two friction forces) against ``solve_ivp`` of G's states and both forces."""
    if shape == "resonant-delay":
        wn, zeta, delay = 3.0, 0.15, 0.057
        a = np.array([[0.0, 1.0], [-(wn**2), -2 * zeta * wn]])
        b, c = np.array([0.0, wn**2]), np.array([1.0, 0.0])
        g_tf = TransferFunction([wn**2], [1.0, 2 * zeta * wn, wn**2], delay)
    else:
        tc, gain, delay = 0.3, 1.2, 0.0
        a, b, c = np.array([[-1.0 / tc]]), np.array([gain / tc]), np.array([1.0])
        g_tf = TransferFunction([gain], [tc, 1.0], delay)
    (fu, su), (fx, sx) = (0.3, 2.0), (0.2, 1.5)
    amp, omega, p = 1.4, 2.6, 200
    plan = SinePlan(
        [omega], [amp], settle_periods=3, periods=3, samples_per_period=p, substeps=4, noise_sd=0.0
    )
    plant = WienerPlant(g_tf, BoucWen(0.8, 0.2, 1.6), _dahl(fu, su) + _dahl(fx, sx, Place.X))
    (rec,) = bw.simulate(plant, plan)
    w = bw.simulate(WienerPlant(g_tf, BoucWen(0.8, 0.2, 1.6)), plan)[0].y

    def dahl_rate(fc: float, sigma: float, vdot: float, f: float) -> float:
        return sigma * vdot * (1.0 - math.copysign(1.0, vdot) * f / fc) if vdot != 0.0 else 0.0

    def rhs(t: float, z: np.ndarray) -> np.ndarray:
        s = z[:-2]
        v = amp * math.cos(omega * (t - delay)) if t >= delay else 0.0
        sdot = a @ s + b * v
        udot = -amp * omega * math.sin(omega * t)
        return np.concatenate(
            [sdot, [dahl_rate(fu, su, udot, z[-2]), dahl_rate(fx, sx, float(c @ sdot), z[-1])]]
        )

    n = a.shape[0]
    sol = solve_ivp(
        rhs, (0.0, rec.t[-1]), np.zeros(n + 2), t_eval=rec.t, rtol=1e-10, atol=1e-12, max_step=0.01
    )
    want = sol.y[-2] + sol.y[-1]
    got = rec.y - w  # the same plain w: the friction adds to y and does not feed back
    # RK4 at h = T/800 against the tight adaptive solver, over the last two periods: measured 1.8e-5 of the
    # peak (resonant, delay: x's reversals fall inside steps, where sgn(xdot) switches) and 7.9e-7 (first
    # order); over the whole record 2.5e-4 and 1.3e-5 (the delayed input steps at t = delay inside a step).
    last = rec.t > rec.t[-1] - 2 * TWO_PI / omega
    assert _scale((got - want)[last]) < 5e-5 * _scale(want)
    assert _scale(got - want) < 1e-3 * _scale(want)


@pytest.mark.parametrize("place", [Place.INPUT, Place.X])
def test_the_steady_state_is_the_closed_form_loop(place: Place) -> None:
    """The last period of a long sine against ``reference.dahl.dahl_loop`` (closed form, no time loop)."""
    g_tf = TransferFunction([4.0], [1.0, 0.8, 4.0], 0.03)
    amp, omega, p, fc, sigma = 1.1, 1.7, 128, 0.25, 1.8
    plan = SinePlan(
        [omega], [amp], settle_periods=20, periods=1, samples_per_period=p, substeps=8, noise_sd=0.0
    )
    (rec,) = bw.simulate(WienerPlant(g_tf, BoucWen(0.8, 0.2, 1.6), _dahl(fc, sigma, place)), plan)
    (plain,) = bw.simulate(WienerPlant(g_tf, BoucWen(0.8, 0.2, 1.6)), plan)
    f = (rec.y - plain.y)[-p:]
    theta0 = omega * rec.t[-p]
    if place == Place.INPUT:
        a, psi0 = amp, theta0
    else:
        gj = (
            np.polyval([4.0], 1j * omega)
            / np.polyval([1.0, 0.8, 4.0], 1j * omega)
            * np.exp(-1j * omega * 0.03)
        )
        a, psi0 = amp * abs(gj), theta0 + float(np.angle(gj))
    ref: Any = reference
    want = ref.dahl.dahl_loop(a, psi0, fc, sigma, p)[0]
    # Measured 2.0e-9 Fc on u (u's reversals fall on step boundaries) and 1.4e-5 Fc on x (x's fall inside RK4
    # steps, where sgn(xdot) switches: O(h^2) locally; r = sigma a / Fc = 18 there).
    assert _scale(f - want) < 3e-5 * fc


def test_what_still_refuses_dahl_friction_says_why() -> None:
    plant = WienerPlant(TransferFunction([1.0], [0.1, 1.0]), BoucWen(1.0, 0.5, 1.5), _dahl(0.2, 2.0))
    # Export takes it (tests/test_export_dahl.py): the force is one more state of the exported model.
    assert "static const double bouc_wen_model_sigma = 2.0;" in bw.to_c(plant)
    # Compensation: the inverse reads u off y stage by stage; the friction's state is in the way.
    t = np.arange(200) * 0.01
    with pytest.raises(InvalidParameterError, match="does not handle Dahl friction: its force has a memory"):
        bw.compensate(plant, t, np.sin(t))
    # Simulation takes it, with the other terms beside it.
    mixed = WienerPlant(plant.linear, plant.hysteresis, (*plant.terms, SensorLag(0.02), Viscous(0.01)))
    plan = SinePlan([2.0], [1.0], settle_periods=1, periods=1, samples_per_period=32, noise_sd=0.0)
    assert np.all(np.isfinite(bw.simulate(mixed, plan)[0].y))
    with pytest.raises(InvalidParameterError, match=">= 0"):
        bw.simulate(
            WienerPlant(plant.linear, plant.hysteresis, _dahl(0.2, 2.0)[:1] + (DahlSigma(-1.0),)), plan
        )


def test_the_cli_simulates_a_plant_with_dahl_friction(tmp_path: Path) -> None:
    """``bouc-wen-id simulate --plant`` with Dahl friction on u and on x: it runs, and the friction shows."""
    with_dahl = WienerPlant(
        TransferFunction([1.0], [0.1, 1.0]),
        BoucWen(1.0, 0.5, 1.5),
        _dahl(0.2, 2.0) + _dahl(0.1, 1.0, Place.X),
    )
    ys = []
    for name, plant in (("dahl", with_dahl), ("bare", WienerPlant(with_dahl.linear, with_dahl.hysteresis))):
        (tmp_path / f"{name}.json").write_text(json.dumps(plant.to_dict()))
        argv = [
            "simulate",
            "--plant",
            str(tmp_path / f"{name}.json"),
            "--frequencies",
            "1",
            "--amplitude",
            "0.8",
        ]
        assert main([*argv, "--noise", "0", "--out", str(tmp_path / name)]) == 0
        (rec,) = bw.load_recordings(tmp_path / name)
        ys.append(rec.y)
    assert np.all(np.isfinite(ys[0])) and _scale(ys[0] - ys[1]) > 0.1

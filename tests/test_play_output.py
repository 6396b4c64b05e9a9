"""The play (backlash) on the measured output, ``play@output`` (review 47, failure 2): a library term at
:attr:`Place.OUTPUT`, in the steady-loop model and in the time-domain simulation.

Rust against the NumPy oracle (simulation, seeded random plants); the simulation against the plain run with a
play applied here in a few lines; the last period of a long simulated sine against the steady-loop model with
the same term; the term's vocabulary (place, bounds, alpha normalisation); and a joint fit that recovers the
half-width from data made by a first-order G and an RK4 written here, apart from the library.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.model import BoucWen, SinePlan, TransferFunction, WienerPlant
from bouc_wen_id.terms import TERMS, Offset, Place, Play, PlayOutput, SensorLag

KIND = Play.at(Place.OUTPUT).kind


def _played(y: np.ndarray, c: float) -> np.ndarray:
    """The play of half-width c on samples, written here: each sample within c of the last output."""
    out = np.empty_like(y)
    p = min(max(0.0, y[0] - c), y[0] + c)
    for k, v in enumerate(y):
        p = min(max(p, v - c), v + c)
        out[k] = p
    return out


def test_the_term_is_the_play_at_the_output_place() -> None:
    cls = PlayOutput
    assert Play.at(Place.OUTPUT) is cls and Play(0.2).at(Place.OUTPUT) == cls(0.2)
    assert KIND in TERMS and cls.acts_on is Place.OUTPUT and cls.base_kind == Play.kind
    assert Place.OUTPUT in Play.places and "output" in cls.place_label()
    # Its half-width is in units of y at every alpha (G -> alpha G leaves the output alone); play on x scales.
    assert cls(0.2).normalized(3.0).value == 0.2
    assert Play(0.2).normalized(3.0).value != 0.2
    with pytest.raises(InvalidParameterError, match=">= 0"):
        cls(-0.1)
    with pytest.raises(Exception, match="cannot act"):
        _core.augmented_output(
            32, 1.0, 1.0, 0.0, ["offset@output"], np.array([1.0, 0.0, 2.0, 0.1]), 1.0, 0.0, 4
        )


@pytest.mark.parametrize("extra", [{}, {"sensor_lag": 0.04}, {"play": 0.1}], ids=["alone", "lag", "play"])
@pytest.mark.parametrize("seed", [0, 1])
def test_rust_matches_the_oracle_with_the_play_on_the_output(
    helpers: Any, extra: dict[str, float], seed: int
) -> None:
    rng = np.random.default_rng([4847, seed])
    run = helpers.rust_against_oracle(rng, 2, lambda r: {KIND: float(r.uniform(0.05, 0.2))}, extra)
    core: Any = _core
    bare = {k: v for k, v in run.terms.items() if k != KIND}
    plain = core.simulate_sampled(*run.args, run.u, run.dt, run.sub, terms=bare)
    # x and w untouched; y the plain run's seen through the play, as written here.
    np.testing.assert_array_equal(run.rust[0], plain[0])
    np.testing.assert_array_equal(run.rust[1], plain[1])
    np.testing.assert_allclose(run.rust[2], _played(plain[2], run.terms[KIND]), rtol=0, atol=1e-12)
    assert float(np.max(np.abs(run.rust[2] - plain[2]))) > 0.5 * run.terms[KIND]


@pytest.mark.parametrize("omega", [1.5, 3.2])
def test_the_last_period_of_a_long_sine_is_the_steady_model_with_the_play_on_the_output(omega: float) -> None:
    beta, gamma, mu, c, y0 = 0.8, 0.2, 1.6, 0.12, 0.3
    g_tf = TransferFunction([9.0], [1.0, 0.9, 9.0], 0.05)
    plant = WienerPlant(g_tf, BoucWen(beta, gamma, mu), (Offset(y0), PlayOutput(c)))
    p, amp = 128, 1.4
    plan = SinePlan(
        [omega], [amp], settle_periods=40, periods=1, samples_per_period=p, substeps=8, noise_sd=0.0
    )
    (rec,) = bw.simulate(plant, plan)
    gw = (
        np.polyval(g_tf.num, 1j * omega) / np.polyval(g_tf.den, 1j * omega) * np.exp(-1j * omega * g_tf.delay)
    )
    shared = np.array([beta, gamma, mu, y0, c])
    y_steady = _core.augmented_output(
        p, amp, omega, 0.0, ["offset", KIND], shared, abs(gw), -float(np.angle(gw)), 8
    )[0]
    last = rec.y[-p:]
    scale = float(np.max(np.abs(y_steady)))
    assert float(np.max(np.abs(last - y_steady))) < 1e-5 * scale
    # The dwell: after the period's top sample the output holds 2c tall, flat.
    top = int(np.argmax(y_steady))
    assert y_steady[(top + 1) % p] == y_steady[top]
    plain = bw.simulate(WienerPlant(g_tf, BoucWen(beta, gamma, mu), (Offset(y0),)), plan)[0].y[-p:]
    assert float(np.max(np.abs(last - plain))) > 0.9 * c


def _rk4_first_order(amp: float, omega: float, p: int, periods: int, b: float) -> np.ndarray:
    """The last period of y = w for G = 1/(0.1 s + 1), alpha = 1, beta 0.7, gamma 0.3, mu 2 by a plain RK4
    of the three lines below, 16 steps a sample, then played by ``b`` (written apart from the library)."""
    tau, beta, gamma = 0.1, 0.7, 0.3
    h = 2 * math.pi / omega / p / 16

    def f(t: float, s: np.ndarray) -> np.ndarray:
        x, w = s
        xd = (amp * math.cos(omega * t) - x) / tau
        return np.array([xd, xd - beta * abs(xd) * w * abs(w) - gamma * xd * w * w])

    s, t, out = np.zeros(2), 0.0, []
    for _ in range(periods * p):
        out.append(s[1])  # the sample at t = k dt, then the step to the next
        for _ in range(16):
            k1 = f(t, s)
            k2 = f(t + h / 2, s + h / 2 * k1)
            k3 = f(t + h / 2, s + h / 2 * k2)
            k4 = f(t + h, s + h * k3)
            s, t = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + h
    return _played(np.array(out), b)[-p:]


def test_a_joint_fit_recovers_the_output_half_width_from_an_independent_generator() -> None:
    rng = np.random.default_rng(48)
    p, c = 64, 0.08
    cases = [(a, om) for a in (0.8, 1.6) for om in (2.0, 6.0)]
    ys, amps, freqs, psis = [], [], [], []
    for a, om in cases:
        y = _rk4_first_order(a, om, p, 12, c)
        ys.append(y + 1e-3 * rng.standard_normal(p))
        amps.append(a)
        freqs.append(om)
        psis.append(0.0)
    gains = [1 / abs(1 + 0.1j * om) for _, om in cases]
    phases = [float(np.arctan(0.1 * om)) for _, om in cases]
    start = np.array([0.6, 0.4, 1.8, 0.02])
    out = _core.augmented_refine(
        ys, amps, freqs, psis, np.full(4, 1e6), [KIND], start, np.array(gains) * 1.05, np.array(phases)
    )
    assert abs(out[0][3] - c) < 0.05 * c
    assert abs(out[0][2] - 2.0) < 0.05
    # Without the term the same data leave a misfit far above the noise.
    plain = _core.augmented_refine(
        ys, amps, freqs, psis, np.full(4, 1e6), [], start[:3], np.array(gains) * 1.05, np.array(phases)
    )
    assert plain[3] > 20 * out[3]


def test_the_output_terms_compose_in_the_order_offset_lag_then_play() -> None:
    # The play acts last: a lag before it smooths F, the play then flattens every reversal of the lagged F.
    shared = np.array([0.8, 0.2, 1.6, 0.05, 0.1])
    y = _core.augmented_output(64, 1.2, 3.0, 0.4, [SensorLag.kind, KIND], shared, 0.9, 0.3, 4)[0]
    f = _core.augmented_output(64, 1.2, 3.0, 0.4, [SensorLag.kind], shared[:4], 0.9, 0.3, 4)[0]
    np.testing.assert_allclose(y, _played(np.concatenate([f, f]), 0.1)[64:], rtol=0, atol=1e-13)


def test_one_play_named_from_saturating_loops_names_the_other_place_as_its_alternative() -> None:
    from bouc_wen_id.diagnosis import caveats as C
    from bouc_wen_id.diagnosis import readings
    from bouc_wen_id.diagnosis.result import NamedTerm

    on_y = NamedTerm(KIND, "b", 0.7, 0.02, "")
    on_x = NamedTerm(Play.kind, "b", 0.1, 0.01, "")
    for named, other in ((on_y, Play), (on_x, Play.at(Place.OUTPUT))):
        text = C.family_text([named], [1.2, 2.5])
        assert C.PLAY_MARK in text and f"{other.place_label()} ({other.kind})" in text
        (r,) = readings.of_verdict("explained by: X" + text, [named.term], [])
        assert other.place_label() in r.words and r.instead_of == (named.term,)
    # Below saturation the selection compared them (the law refuses one b at every amplitude): not said;
    # both named: nothing to offer in their place.
    assert C.PLAY_MARK not in C.family_text([on_y], [0.6, 2.5])
    assert C.PLAY_MARK not in C.family_text([on_y, on_x], [1.2, 2.5])

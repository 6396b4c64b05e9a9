"""The blind bench's own generator (benches/blind.py), checked against what can be known without it.

Its G is checked against the frequency response written from each plant's PHYSICAL parameters (masses and
springs, tau and delay, wn and zeta), not from the realisation it integrates; its Bouc-Wen element against
the saturation levels (2a) implies and against SciPy's adaptive integrator in time (the bench integrates
along the path); its noise-free nulls must be periodic once settled; its sizing must hit the asked size.
"""

from __future__ import annotations

import importlib
import math
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
#: The blind bench, a script beside the package (not an installed module).
blind: Any = importlib.import_module("blind")


def _physical_response(g: Any, omega: float) -> complex:
    """G(j omega) from the plant's physical parameters (not from its state-space realisation)."""
    s = 1j * omega
    info = g.info
    if g.kind == "resonance":
        wn, zeta = info["wn"], info["zeta"]
        h = wn**2 / (s**2 + 2 * zeta * wn * s + wn**2)
    elif g.kind == "lag_delay":
        h = 1 / (1 + s * info["tau"])
    else:
        mm = np.diag([1.0, info["m2"]])
        kk = np.array([[info["k1"] + info["k2"], -info["k2"]], [-info["k2"], info["k2"]]])
        cc = info["a0"] * mm + info["a1"] * kk
        disp = np.linalg.solve(kk + s * cc + s**2 * mm, np.array([0.0, 1.0]))
        h = disp[0] / info["dc"]
    return complex(h * np.exp(-s * g.delay))


@pytest.mark.parametrize("kind", ["two_dof", "lag_delay", "resonance"])
def test_g_steady_response_is_the_physical_frequency_response(kind: str) -> None:
    rng = np.random.default_rng(11)
    g = blind.LINEAR[kind](rng)
    hy = blind.draw_hysteresis(rng)
    exps = blind.design("six_plus_one", g, hy, rng)
    for e in (exps[0], exps[3], exps[5]):  # the bottom, the middle and the top of the band
        sig = blind.signals(g, e)
        keep = slice(-2 * blind.SUB * int(round(2 * math.pi / e.omega / e.dt)), None)
        t = sig.t[keep]
        phasor = _physical_response(g, e.omega) * e.amplitude * np.exp(1j * e.omega * t)
        scale = abs(phasor[0])
        # the first-order hold of a sine is exact to (omega h)^2 / 12 (h the grid step): below 1e-4 here
        for got, factor in ((sig.x, 1.0), (sig.xd, 1j * e.omega), (sig.xdd, -(e.omega**2))):
            want = (factor * phasor).real
            assert np.abs(got[keep] - want).max() < 1e-4 * abs(factor) * scale


def test_delay_buffer_holds_x_at_zero_until_the_delay_has_passed() -> None:
    rng = np.random.default_rng(3)
    g = blind.lag_delay(rng)
    e = blind.design("grid3x3", g, blind.draw_hysteresis(rng), rng)[0]
    sig = blind.signals(g, e)
    before = sig.t < g.delay
    assert before.sum() > 2
    assert np.all(sig.x[before] == 0.0) and np.abs(sig.x[~before]).max() > 0


def _bw_time(x_amp: float, hy: Any, periods: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """w(t) of (2a) under x = X cos t by SciPy's adaptive Runge-Kutta in TIME (the bench's is in the path)."""

    def rhs(t: float, w: np.ndarray) -> np.ndarray:
        xd = -x_amp * math.sin(t)
        aw = abs(w[0])
        return np.array(
            [hy.alpha * xd - hy.beta * abs(xd) * aw ** (hy.mu - 1) * w[0] - hy.gamma * xd * aw**hy.mu]
        )

    t = np.arange(periods * n + 1) * (2 * math.pi / n)
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0], t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
    return t, sol.y[0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_path_integrator_agrees_with_an_adaptive_integrator_in_time(seed: int) -> None:
    hy = blind.draw_hysteresis(np.random.default_rng(seed))
    x_amp = 2.0 * hy.saturation / hy.alpha
    n = 400
    t, w_ref = _bw_time(x_amp, hy, 3, n)
    w = blind.hysteresis((x_amp * np.cos(t))[None, :], hy)[0]
    assert np.abs(w - w_ref)[-n:].max() < 2e-5 * hy.saturation


@pytest.mark.parametrize("seed", [4, 5])
def test_bouc_wen_saturates_at_the_levels_2a_implies(seed: int) -> None:
    hy = blind.draw_hysteresis(np.random.default_rng(seed))
    n = 2000
    path = 8 * hy.saturation / hy.alpha * np.cos(np.arange(4 * n) * 2 * math.pi / n)
    w = blind.hysteresis(path[None, :], hy)[0][-n:]
    assert abs(w.max() - hy.saturation) < 1e-6 * hy.saturation
    assert np.abs(w[: n // 2] + w[n // 2 :]).max() < 1e-6 * hy.saturation  # odd: w(theta + pi) = -w(theta)
    delta = 0.3 * (hy.beta + hy.gamma)
    wa = blind.hysteresis(path[None, :], hy, asym=delta)[0][-n:]
    top = (hy.alpha / (hy.beta + hy.gamma + delta)) ** (1 / hy.mu)
    bottom = (hy.alpha / (hy.beta + hy.gamma - delta)) ** (1 / hy.mu)
    assert abs(wa.max() - top) < 1e-6 * top and abs(wa.min() + bottom) < 1e-6 * bottom


def test_play_holds_w_after_each_reversal_for_two_half_widths_of_travel() -> None:
    hy = blind.draw_hysteresis(np.random.default_rng(6))
    n, b = 1000, 0.2 * hy.saturation / hy.alpha
    path = 3 * hy.saturation / hy.alpha * np.cos(np.arange(3 * n + 1) * 2 * math.pi / n)
    w = blind.hysteresis(path[None, :], hy, play=b)[0]
    top = 2 * n  # a maximum of x: w stays put while x falls by 2 b, then moves
    drop = path[top] - path[top : top + n // 2]
    held = w[top : top + n // 2][drop < 2 * b * 0.999]
    moved = w[top : top + n // 2][drop > 2 * b * 1.01]
    assert np.ptp(held) < 1e-12 and abs(moved[0] - held[0]) > 0


@pytest.mark.parametrize("kind", ["two_dof", "lag_delay", "resonance"])
def test_noise_free_null_is_periodic_after_settling(kind: str) -> None:
    rng = np.random.default_rng(21)
    g = blind.LINEAR[kind](rng)
    hy = blind.draw_hysteresis(rng)
    exps = blind.design("grid3x3", g, hy, rng)[::4]  # three of the nine: low, middle, high
    sig = [blind.signals(g, e) for e in exps]
    ys = blind.output(sig, hy, "null", 0.0)
    # a fiftieth of the smallest averaged noise sd the bench draws (0.5 % of the output RMS over 30 periods)
    tol = 0.02 * 0.005 * blind.rms(ys) / math.sqrt(blind.RECORD_PERIODS)
    for e, y in zip(exps, ys):
        p = int(round(2 * math.pi / e.omega / e.dt))
        assert abs(p * e.dt * e.omega - 2 * math.pi) < 1e-12
        assert np.abs(y[p:] - y[:-p]).max() < tol


@pytest.mark.parametrize(("effect", "seed"), [("viscous@x", 31), ("play", 32), ("sensor_lag", 33)])
def test_sizing_hits_the_asked_multiple_of_the_averaged_noise(effect: str, seed: int) -> None:
    made = blind.make_case(blind.Case(effect, 10.0, 0, seed))
    assert abs(made["info"]["size_got"] - 10.0) < 0.3
    again = blind.make_case(blind.Case(effect, 10.0, 0, seed))
    assert all(np.array_equal(a, b) for a, b in zip(made["y"], again["y"]))  # the seed decides everything


def _diag(status: str, named: list[str], alts: list[tuple[str, str]]) -> Any:
    return SimpleNamespace(
        status=status,
        named=[SimpleNamespace(term=t) for t in named],
        alternatives=[SimpleNamespace(term=a, rival=r) for a, r in alts],
    )


def test_score_reads_name_place_and_alternatives() -> None:
    case = blind.Case("viscous@x", 10.0, 0, 1)
    assert blind.score(case, _diag("explained", ["viscous@x"], []))[0] == "right"
    assert blind.score(case, _diag("explained", ["viscous"], [("viscous", "viscous@x")]))[0] == "right"
    assert blind.score(case, _diag("explained", ["viscous"], []))[0] == "place"
    assert blind.score(case, _diag("partly explained", ["inertia"], []))[0] == "wrong"
    assert blind.score(case, _diag("unexplained", [], []))[0] == "unexplained"
    null = blind.Case("null", 0.0, 0, 1)
    assert blind.score(null, _diag("adequate", [], []))[0] == "adequate"
    assert blind.score(null, _diag("explained", ["offset"], []))[0] == "named"
    outside = blind.Case("stribeck", 10.0, 0, 1)
    assert blind.score(outside, _diag("partly explained", ["coulomb"], []))[0] == "partly"


def test_score_counts_a_caveated_equivalent_as_family() -> None:
    """An outside loop named only as the term whose caveat names it (a PI loop as a spring on x with the
    Masing clause or as a viscous damping with the rate clause, an output backlash as play with play's
    clause) IN THE HEADLINE is "family"; with the clause only in the details, without it, with another term
    beside it, or for another effect, it is not."""
    from bouc_wen_id.diagnosis.caveats import PLAY_MARK
    from bouc_wen_id.diagnosis.masing import MASING_MARK
    from bouc_wen_id.diagnosis.rate_rival import RATE_MARK

    def d(named: list[str], verdict: str) -> Any:
        return SimpleNamespace(**vars(_diag("explained", named, [])), verdict=verdict)

    pi = blind.Case("prandtl_ishlinskii", 10.0, 0, 1)
    assert blind.score(pi, d(["stiffness@x"], f"explained by: k or {MASING_MARK}; more"))[0] == "family"
    # the caveat only in the details: a user who reads the headline was told a bare name
    assert blind.score(pi, d(["stiffness@x"], f"explained by: k; {MASING_MARK}"))[0] == "named"
    assert blind.score(pi, d(["stiffness@x"], "explained by: k"))[0] == "named"
    assert blind.score(pi, d(["stiffness@x", "viscous"], MASING_MARK))[0] == "named"
    # a PI loop is rate-independent: a viscous damping with the rate caveat in its headline names it too
    assert blind.score(pi, d(["viscous@x"], f"explained by: c or {RATE_MARK}; more"))[0] == "family"
    assert blind.score(pi, d(["viscous@x"], f"explained by: c; {RATE_MARK}"))[0] == "named"
    backlash = blind.Case("output_backlash", 10.0, 0, 1)
    assert blind.score(backlash, d(["play"], f"play or {PLAY_MARK}"))[0] == "family"
    assert blind.score(backlash, d(["viscous"], f"c or {RATE_MARK}"))[0] == "named"  # not of that effect
    assert blind.score(backlash, d(["stiffness@x"], MASING_MARK))[0] == "named"
    stribeck = blind.Case("stribeck", 10.0, 0, 1)
    assert blind.score(stribeck, d(["stiffness@x"], MASING_MARK))[0] == "named"
    assert "family" in blind.GOOD["outside"]


def _made(design: str, seed: int = 41, effect: str = "null") -> Any:
    return blind.make_case(blind.Case(effect, 10.0 if effect != "null" else 0.0, 0, seed, None, 1.0, design))


def test_first_order_design_keeps_x_nearly_in_phase_with_u() -> None:
    """The first-order design's G is 1/(tau s + 1) with no delay, tested at omega tau <= 0.3: x lags u by at
    most atan(0.3) = 16.7 degrees (written from the plant's tau, not the realisation)."""
    made = _made("first_order")
    info = made["info"]
    assert info["plant"] == "first_order" and info["delay"] == 0.0
    tau = info["g"]["tau"]
    assert max(e.omega for e in made["exps"]) * tau <= 0.3 * 1.03 + 1e-12
    assert info["phase_max_deg"] <= math.degrees(math.atan(0.3 * 1.03)) + 1e-9


def test_amplitude_sweep_is_one_frequency_at_five_levels() -> None:
    exps = _made("amp_sweep")["exps"]
    assert len(exps) == 5 and len({e.omega for e in exps}) == 1
    assert all(a.amplitude < b.amplitude for a, b in zip(exps, exps[1:]))


def test_unequal_design_records_unequal_periods_and_sizes_on_their_averaged_noise() -> None:
    made = _made("unequal", effect="viscous@x")
    periods = made["info"]["periods"]
    assert len(set(periods)) > 1
    for e, y in zip(made["exps"], made["y"]):
        assert y.size == e.n == e.periods * int(round(2 * math.pi / e.omega / e.dt))
    assert abs(made["info"]["size_got"] - 10.0) < 0.3


def test_few_periods_design_records_four_to_six_periods_after_a_short_settle() -> None:
    for e in _made("few_periods")["exps"]:
        period = int(round(2 * math.pi / e.omega / e.dt))
        assert 4 <= e.periods <= 6 and e.n == e.periods * period and e.settle <= 5 * period


def test_clipped_design_drives_g_with_the_flat_topped_input_it_writes() -> None:
    """The clipped experiments' u has flat tops at the actuator's limit (the rest are sines), they are
    written as measurements, and x is G applied to that clipped u: the steady x of a first-order G is
    checked against the exact lag of the clipped samples (a recursion of its own, not the bench's modes)."""
    rng = np.random.default_rng(5)
    g = blind.first_order(rng)
    hy = blind.draw_hysteresis(rng)
    exps = blind.design("clipped", g, hy, rng)
    clipped = [e for e in exps if e.clip > 0]
    assert len(clipped) == 3 and all(0.95 <= e.clip <= 0.98 for e in clipped)
    assert not any(e.recording for e in exps)
    e = clipped[0]
    sig = blind.signals(g, e)
    rec = slice(e.settle * blind.SUB, None)
    assert abs(np.abs(sig.u[rec]).max() - e.clip * e.amplitude) < 1e-12 * e.amplitude
    assert np.mean(np.abs(sig.u[rec]) >= e.clip * e.amplitude * (1 - 1e-12)) > 0.05  # flat tops
    # x' = (u - x) / tau, by a fine explicit Euler sub-stepping of the sampled u (linear between points)
    tau, h = g.info["tau"], e.dt / blind.SUB
    x = np.zeros(sig.u.size)
    m = 200
    for k in range(1, sig.u.size):
        xv = x[k - 1]
        for j in range(m):
            uj = sig.u[k - 1] + (sig.u[k] - sig.u[k - 1]) * (j + 0.5) / m
            xv += h / m * (uj - xv) / tau
        x[k] = xv
    assert np.abs(x[rec] - sig.x[rec]).max() < 1e-3 * np.abs(sig.x[rec]).max()


def test_score_reads_the_input_waveform_as_the_input_in_the_clipped_design() -> None:
    """Where the actuator clips, the measured input's waveform (`distortion`) is the input, not device
    physics: named alone with a passing model, a null is adequate; beside the truth, the truth is right."""
    null = blind.Case("null", 0.0, 0, 1, None, 1.0, "clipped")
    assert blind.score(null, _diag("explained", ["distortion"], []))[0] == "adequate"
    assert blind.score(null, _diag("explained", ["distortion", "offset"], []))[0] == "named"
    vis = blind.Case("viscous", 10.0, 0, 1, None, 1.0, "clipped")
    assert blind.score(vis, _diag("explained", ["viscous", "distortion"], []))[0] == "right"
    other = blind.Case("null", 0.0, 0, 1, None, 1.0, "grid3x3")
    assert blind.score(other, _diag("explained", ["distortion"], []))[0] == "named"


def test_score_counts_a_null_whose_verdict_names_the_distorted_input_apart() -> None:
    """A null left "unexplained" with the input clause of diagnosis.input_note and nothing named is "input"
    (counted apart from adequate); without the clause, or with a device term named, it is not."""
    from bouc_wen_id.diagnosis.input_note import MARK

    null = blind.Case("null", 0.0, 0, 1, None, 1.0, "clipped")

    def d(status: str, named: list[str], verdict: str) -> Any:
        out = _diag(status, named, [])
        out.verdict = verdict
        return out

    said = "unexplained structure remains at harmonics 3, 5" + MARK + " (recording 2: harmonic 3 at 4 %)"
    assert blind.score(null, d("unexplained", [], said))[0] == "input"
    assert blind.score(null, d("unexplained", [], "unexplained structure remains"))[0] == "unexplained"
    assert blind.score(null, d("partly explained", ["coulomb"], said))[0] == "partly"

"""A drive that is not a centred sine (review 35): a mean of its own (a preload) and a third harmonic
(amplifier distortion). The terms on u act on the measured u (fitting.input_shape, rust/augmented.rs
``MeasuredInput``): a spring sees the mean (no phantom output offset, diagnosis/input_dc.py), a dashpot its
harmonics; detection limits on a failed fit are void (limits_void.py); the input note says "above the tested
band" only when the harmonics are (input_note.band_text).

The plant is made here, apart from the package's simulators and the reviewer's: G = 1/(1 + s/3) without a
delay, Bouc-Wen (beta 0.8, gamma 0.2, mu 1.3) by RK4 on the analytic steady x = G u (harmonic included),
input U (cos + dc + h3 cos(3 theta + 0.4)).
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import input_dc
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.result import NamedTerm

FREQS = (1.0, 2.0, 3.5, 5.0)
P, SETTLE, PERIODS, SUB = 96, 6, 8, 8


def _loop(om: float, n: int, h3: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample times and the Bouc-Wen w on x = G u's steady state (G = 1/(1 + s/3), harmonic 3 included)."""
    g1, g3 = 1.0 / (1.0 + 1j * om / 3.0), 1.0 / (1.0 + 3j * om / 3.0)
    a1, l1, a3, l3 = abs(g1), math.atan2(g1.imag, g1.real), h3 * abs(g3), 0.4 + math.atan2(g3.imag, g3.real)
    h = 2.0 * math.pi / om / P / SUB
    t = np.arange(n) * (2.0 * math.pi / om / P)

    def f(w: float, s: float) -> float:
        v = -a1 * om * math.sin(om * s + l1) - 3.0 * a3 * om * math.sin(3.0 * om * s + l3)
        return float(v - 0.8 * abs(v) * abs(w) ** 0.3 * w - 0.2 * v * abs(w) ** 1.3)

    w, ws = 0.0, np.zeros(n)
    for j in range(n):
        ws[j] = w
        for i in range(SUB):
            s = t[j] + i * h
            k1 = f(w, s)
            k2 = f(w + 0.5 * h * k1, s + 0.5 * h)
            k3 = f(w + 0.5 * h * k2, s + 0.5 * h)
            w += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + f(w + h * k3, s + h))
    return t, ws


def _records(
    k_u: float, dc: float, seed: int, sd: float = 0.004, h3: float = 0.0, c_u: float = 0.0
) -> list[bw.Recording]:
    rng = np.random.default_rng(seed)
    out = []
    for om in FREQS:
        n = (SETTLE + PERIODS) * P
        t, ws = _loop(om, n, h3)
        u = np.cos(om * t) + dc + h3 * np.cos(3.0 * om * t + 0.4)
        ud = -om * np.sin(om * t) - 3.0 * om * h3 * np.sin(3.0 * om * t + 0.4)
        y = ws + k_u * u + c_u * ud + sd * rng.standard_normal(n)
        out.append(bw.Recording(t, u, y, amplitude=1.0, frequency=om, settle_periods=SETTLE))
    return out


def test_a_spring_on_a_preloaded_drive_is_no_sensor_offset() -> None:
    dg = bw.diagnose(_records(0.06, 0.25, 3))
    names = {t.term for t in dg.named}
    # The spring sees the drive's mean (fitting.input_shape): no offset (main: "output offset y0 = 0.0151").
    assert "stiffness" in names and "offset" not in names, dg.verdict
    k = next(t for t in dg.named if t.term == "stiffness")
    assert abs(k.value - 0.06) < 4 * k.standard_error, dg.verdict


def test_a_preloaded_drive_alone_stays_quiet() -> None:
    dg = bw.diagnose(_records(0.0, 0.25, 4))
    assert dg.status == "adequate", dg.verdict


def _term(term: str, sym: str, v: float, se: float) -> NamedTerm:
    return NamedTerm(term, sym, v, se, "")


def test_qualify_on_u_says_the_rest_and_on_x_gives_both_readings() -> None:
    exps = prepare(_records(0.0, 0.25, 5))
    assert all(abs(e.input_dc - 0.25) < 1e-3 for e in exps)
    off = _term("offset", "y0", 0.0151, 0.0002)
    said = "explained by: " + str(off) + ", k"
    on_u = input_dc.qualify(said, [off, _term("stiffness", "k", 0.06, 0.002)], exps)
    assert "which the model carries: a sensor zero or another preload" in on_u and on_u.startswith(said[:-3])
    on_x = input_dc.qualify(said, [off, _term("stiffness@x", "k", 0.06, 0.002)], exps)
    assert "cannot tell a sensor zero from a preloaded spring" in on_x and "G(0) = 1.01" in on_x
    # A centred drive, or an offset without a spring, leaves the verdict as it was.
    centred = prepare(_records(0.0, 0.0, 5))
    assert input_dc.qualify(said, [off, _term("stiffness", "k", 0.06, 0.002)], centred) == said
    assert input_dc.qualify(said, [off], exps) == said


def test_a_distorted_drive_alone_is_no_device_physics() -> None:
    dg = bw.diagnose(_records(0.0, 0.0, 7, h3=0.03))
    assert {t.term for t in dg.named} <= {"distortion"}, dg.verdict
    assert dg.status in ("adequate", "explained"), dg.verdict
    assert "outside the library" not in dg.verdict


def test_limits_on_a_failed_fit_are_void() -> None:
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import limits_void

    lim = SimpleNamespace(limit_90=0.0067, __str__=lambda: "x", summary_tail=lambda: "")
    final = SimpleNamespace(cost=1400.0, dof=620, p_value=1e-30)
    failed = SimpleNamespace(status="unexplained", limits=(lim,), final=final, settings={"alpha": 0.05})
    lines = limits_void.summary_lines(failed)
    assert limits_void.void(failed) and "void" in lines[-1] and "0.0067" not in "".join(lines)
    # A final model that passes (explained, or in part with a non-physical term left out) keeps them.
    passes = SimpleNamespace(cost=640.0, dof=620, p_value=0.24)
    fine = SimpleNamespace(status="partly explained", limits=(lim,), final=passes, settings={"alpha": 0.05})
    assert not limits_void.void(fine) and "0.0067" in "".join(limits_void.summary_lines(fine))


def test_the_input_note_says_above_the_band_only_when_it_is() -> None:
    from bouc_wen_id.diagnosis import input_note

    exps = prepare(_records(0.0, 0.0, 8, h3=0.03))
    inside, above = input_note.harmonic_frequencies(exps)
    # Harmonic 3 of 1 rad/s (3 rad/s) lies inside a band tested up to 5 rad/s; of 2, 3.5 and 5 above it.
    assert len(inside) == 1 and "3 rad/s" in inside[0] and len(above) == 3
    said = input_note.band_text(exps, 3)
    assert "1 inside the tested band" in said and "frequencies above the tested band" not in said
    assert "frequencies above the tested band" in input_note.band_text(exps[1:], 3)


def test_terms_on_u_see_the_measured_input_in_rust_and_in_the_reference() -> None:
    from bouc_wen_id import _core
    from bouc_wen_id.reference import augmented as RA

    shape = np.array([0.2, 0.0, 0.0, 0.03, -0.01])  # mean 0.2 U, no harmonic 2, harmonic 3 at 3.2 %
    p, amp, om, psi = 64, 1.3, 2.0, 0.7
    args = (p, amp, om, psi, ["stiffness", "viscous", "inertia"], np.array([0.8, 0.2, 1.4, 0.1, 0.2, 0.3]))
    y, js, _ = _core.augmented_output(*args, 1.1, 0.4, 4, None, shape)
    yr, jr, _ = RA.augmented_output(*args, 1.1, 0.4, 4, None, shape)
    assert np.max(np.abs(y - yr)) < 1e-9 and np.max(np.abs(js - jr)) < 1e-8
    z = 2.0 * np.pi * np.arange(p) / p + psi
    u = amp * (np.cos(z) + 0.2 + 0.03 * np.cos(3 * z) + 0.01 * np.sin(3 * z))
    ud = np.gradient(np.tile(u, 3), 2.0 * np.pi / p / om)[p : 2 * p]
    assert np.max(np.abs(js[:, 3] - u)) < 1e-12  # the spring sees the mean and the harmonics
    assert (
        np.max(np.abs(js[:, 4] - ud)) < 0.02 * amp * om
    )  # the dashpot the harmonics' velocity, not the mean
    y0, j0, _ = _core.augmented_output(*args, 1.1, 0.4, 4, None, None)
    assert abs(float(np.mean(js[:, 3] - j0[:, 3])) - 0.2 * amp) < 1e-12


def test_a_waveform_law_failing_alone_is_the_drive_not_outside_physics() -> None:
    # Main said "it stands in for physics outside the library" of a plain plant behind a distorted drive
    # and a resonant G (reviewer 35's null_h3r); other terms' words are unchanged.
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis.run import _law_text
    from bouc_wen_id.terms import Distortion, Viscous

    def steps(*terms: str) -> list[Any]:
        trials = [SimpleNamespace(term=t, law_p_value=1e-20) for t in terms]
        return [SimpleNamespace(trials=trials, law_failed=terms, alternatives=())]

    alone = _law_text(steps(Distortion.kind))
    assert "outside the library" in alone and "rather than physics outside the library" in alone
    assert "stands in for physics outside the library" not in alone
    assert "stands in for physics outside the library" in _law_text(steps(Viscous.kind))
    assert "stands in for physics outside the library" in _law_text(steps(Distortion.kind, Viscous.kind))


def test_no_spring_reading_that_needs_a_negative_dc_gain_or_one_drive_level_for_several() -> None:
    """The MR damper at 0 A: the spring-on-x reading of its offset needed G(0) = -919 (a G whose reported
    gains are positive): no reading. Drives at different means give a spring on x a DC each, which one offset
    does not: "cannot tell a sensor zero from a preloaded spring" would be false there."""
    from dataclasses import replace as _replace

    exps = prepare(_records(0.0, 0.25, 5))
    off = _term("offset", "y0", -0.0151, 0.0002)  # the spring reading would need G(0) < 0
    said = "explained by: " + str(off) + ", k"
    assert input_dc.qualify(said, [off, _term("stiffness@x", "k", 0.06, 0.002)], exps) == said
    spread = [_replace(e, input_dc=0.25 * (1 + 0.5 * i)) for i, e in enumerate(exps)]
    pos = _term("offset", "y0", 0.0151, 0.0002)
    said = "explained by: " + str(pos) + ", k"
    assert input_dc.qualify(said, [pos, _term("stiffness@x", "k", 0.06, 0.002)], spread) == said


def test_limits_keep_the_level_that_decided_the_verdict() -> None:
    """Review 36's null_spk: the plain model at p = 0.042 passes its global test (alpha / 2, gate.py) and
    reads "adequate" with its limits; the summary then called them void at alpha."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import gate, limits_void

    lim = SimpleNamespace(limit_90=0.0029, __str__=lambda: "x", summary_tail=lambda: "")
    final = SimpleNamespace(cost=700.0, dof=620, p_value=0.042)
    assert gate.plain_passes(final.p_value, 0.05)
    plain = SimpleNamespace(status="adequate", named=(), limits=(lim,), final=final, settings={"alpha": 0.05})
    assert not limits_void.void(plain) and "0.0029" in "".join(limits_void.summary_lines(plain))
    # with a named term the final model's own test is at alpha: the same p voids them
    named = SimpleNamespace(
        status="partly explained", named=("t",), limits=(lim,), final=final, settings={"alpha": 0.05}
    )
    assert limits_void.void(named)


def test_the_limit_line_of_a_named_term_gives_its_named_value() -> None:
    """Review 36b: "viscous ... |c| < 0.0026" under a verdict naming c = 0.007918 ± 0.000119."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import limits_void
    from bouc_wen_id.diagnosis.result import NamedTerm

    lim = SimpleNamespace(term="viscous", limit_90=0.0036, __str__=lambda: "x", summary_tail=lambda: "")
    other = SimpleNamespace(term="stiffness", limit_90=0.01, __str__=lambda: "x", summary_tail=lambda: "")
    final = SimpleNamespace(cost=640.0, dof=620, p_value=0.3)
    d = SimpleNamespace(
        status="explained",
        named=(NamedTerm("viscous", "c", 0.007918, 0.000119, "s"),),
        limits=(lim, other),
        final=final,
        settings={"alpha": 0.05},
    )
    lines = limits_void.summary_lines(d)
    assert "named in the verdict: c = 0.007918 ± 0.00012 s" in lines[2]
    assert "named in the verdict" not in lines[3]

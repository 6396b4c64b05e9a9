"""Lab-data preprocessing: sine analysis, steady segments, synchronous averaging (``bouc_wen_id.signal``).

The real recordings are read from ``../shared/data/real`` (see its README); the loaders below are private
to this test and follow each folder's PROVENANCE.md.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Callable

import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id import signal as sig
from bouc_wen_id.errors import (
    BoucWenIdError,
    DistortedInputWarning,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    NotPeriodicError,
    TimeAxisError,
    UndersampledError,
    ZeroAmplitudeError,
)
from bouc_wen_id.signal import (
    AveragedPeriod,
    SegmentReport,
    SineFit,
    _harmonic_ls,
    analyse_sine,
    find_steady_segments,
    synchronous_average,
)
from hypothesis import given, settings
from hypothesis import strategies as st

TWO_PI = 2.0 * math.pi

Arrays = tuple[np.ndarray, np.ndarray, np.ndarray]


def sine(
    n: int,
    samples_per_period: float,
    *,
    amp: float = 1.0,
    phase: float = 0.4,
    offset: float = 0.0,
    t0: float = 0.0,
    dt: float = 1e-3,
) -> tuple[np.ndarray, np.ndarray, float]:
    omega = TWO_PI / (samples_per_period * dt)
    t = t0 + np.arange(n) * dt
    return t, offset + amp * np.cos(omega * t - phase), omega


# ------------------------------------------------------------------------------------------------------
# analyse_sine


def test_analyse_sine_recovers_an_exact_sine_at_a_non_integer_period() -> None:
    t, u, omega = sine(3000, 123.456, amp=2.5, phase=2.0, offset=-0.7, t0=1234.5)
    fit = analyse_sine(t, u)
    assert fit.frequency == pytest.approx(omega, rel=1e-10)
    assert fit.amplitude == pytest.approx(2.5, rel=1e-9)
    assert fit.offset == pytest.approx(-0.7, abs=1e-9)
    assert 0.0 <= fit.phase < TWO_PI
    # The phase refers to the absolute time axis (u = A cos(omega t - phase)), even far from t = 0.
    assert abs(math.remainder(fit.phase - 2.0, TWO_PI)) < 1e-8
    np.testing.assert_allclose(
        fit.offset + fit.amplitude * np.cos(fit.frequency * t - fit.phase), u, atol=1e-8
    )
    assert fit.thd < 1e-6 and fit.residual_rms < 1e-8


@settings(max_examples=40, deadline=None)
@given(
    p=st.floats(16.5, 400.0),
    periods=st.floats(2.2, 30.0),
    amp=st.floats(1e-3, 1e3),
    phase=st.floats(0.0, 6.28),
    offset=st.floats(-10.0, 10.0),
)
def test_analyse_sine_property(p: float, periods: float, amp: float, phase: float, offset: float) -> None:
    t, u, omega = sine(int(p * periods), p, amp=amp, phase=phase, offset=offset, t0=0.37)
    fit = analyse_sine(t, u)
    assert fit.frequency == pytest.approx(omega, rel=1e-8)
    assert fit.amplitude == pytest.approx(amp, rel=1e-7)
    assert fit.offset == pytest.approx(offset, abs=1e-7 * (amp + abs(offset)))
    assert abs(math.remainder(fit.phase - phase, TWO_PI)) < 1e-6


def test_frequency_error_reaches_the_cramer_rao_bound() -> None:
    """Monte Carlo over 50 seeds: RMSE of omega against the CRB of a real sine in white noise.

    For ``u = A cos(omega t + phi) + noise`` with unknown amplitude, phase and offset the bound is
    ``var(omega) = 24 sigma^2 / (A^2 dt^2 n (n^2 - 1))`` (the ``12 sigma^2`` form is that of a complex
    exponential, whose power is A^2 rather than A^2/2).
    """
    n, dt, amp, sd, omega = 800, 0.01, 1.0, 0.3, TWO_PI * 3.217
    crb = math.sqrt(24.0 * sd**2 / (amp**2 * dt**2 * n * (n**2 - 1)))
    errors, ses = [], []
    for seed in range(50):
        rng = np.random.default_rng(seed)
        t = 7.0 + np.arange(n) * dt
        u = 0.2 + amp * np.cos(omega * t - rng.uniform(0, TWO_PI)) + sd * rng.normal(size=n)
        fit = analyse_sine(t, u)
        errors.append(fit.frequency - omega)
        ses.append(fit.frequency_se)
    ratio = math.sqrt(float(np.mean(np.square(errors)))) / crb
    assert ratio < 1.5, ratio
    # The reported standard error is the bound itself (to the scatter of the residual variance).
    assert float(np.mean(ses)) / crb == pytest.approx(1.0, rel=0.05)


def test_nominal_frequency_is_a_hint() -> None:
    # 2 % off nominal, as the lab's DAQ clock against the generator: found, reported as found.
    t, u, omega = sine(4000, 97.3)
    assert analyse_sine(t, u, nominal_frequency=1.02 * omega).frequency == pytest.approx(omega, rel=1e-9)
    # No peak in +-10 % of the hint: the global peak.
    assert analyse_sine(t, u, nominal_frequency=3.0 * omega).frequency == pytest.approx(omega, rel=1e-9)
    # A fundamental weaker than its second harmonic: the global peak is 2 omega, the hint picks omega.
    u2 = np.cos(omega * t) + 1.2 * np.cos(2.0 * omega * t + 0.3)
    with pytest.warns(DistortedInputWarning):
        hinted = analyse_sine(t, u2, nominal_frequency=omega)
    assert hinted.frequency == pytest.approx(omega, rel=1e-9)
    assert hinted.thd == pytest.approx(1.2, rel=1e-6)
    # Without the hint the global peak wins (the omega component then counts as a disturbance).
    assert analyse_sine(t, u2).frequency == pytest.approx(2.0 * omega, rel=1e-3)


def test_distortion_warns_above_ten_percent_only() -> None:
    t, u, omega = sine(4000, 97.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = analyse_sine(t, u + 0.05 * np.cos(3.0 * omega * t))
    assert fit.thd == pytest.approx(0.05, rel=1e-6)
    with pytest.warns(DistortedInputWarning, match="harmonic distortion"):
        fit = analyse_sine(t, u + 0.15 * np.cos(2.0 * omega * t) + 0.05 * np.sin(3.0 * omega * t))
    assert fit.thd == pytest.approx(math.hypot(0.15, 0.05), rel=1e-6)


def test_thd_is_corrected_for_noise() -> None:
    rng = np.random.default_rng(3)
    t, u, _ = sine(2000, 61.7)
    fit = analyse_sine(t, u + 0.3 * rng.normal(size=u.size))
    assert fit.thd < 0.05
    assert fit.residual_rms == pytest.approx(0.3, rel=0.1)


@pytest.mark.parametrize(
    ("case", "error"),
    [
        ("nan", NonFiniteError),
        ("inf_t", NonFiniteError),
        ("lengths", InvalidParameterError),
        ("constant", ZeroAmplitudeError),
        ("white_noise", NotPeriodicError),
        ("chirp", NotPeriodicError),
        ("short", InsufficientDataError),
        ("undersampled", UndersampledError),
        ("near_nyquist", UndersampledError),
        ("not_increasing", TimeAxisError),
        ("jitter", TimeAxisError),
        ("gap", TimeAxisError),
        ("nominal", InvalidParameterError),
    ],
)
def test_analyse_sine_errors(case: str, error: type[BoucWenIdError]) -> None:
    rng = np.random.default_rng(0)
    t, u, _ = sine(2000, 50.3)
    kwargs: dict[str, float] = {}
    if case == "nan":
        u[17] = np.nan
    elif case == "inf_t":
        t[5] = np.inf
    elif case == "lengths":
        u = u[:-1]
    elif case == "constant":
        u = np.full_like(t, 3.0)
    elif case == "white_noise":
        u = rng.normal(size=t.size)
    elif case == "chirp":
        tt = np.arange(4000) * 1e-3
        t, u = tt, np.cos(TWO_PI * (5.0 * tt + 40.0 * tt**2))  # 5 .. 325 Hz
    elif case == "short":
        t, u, _ = sine(75, 50.3)  # 1.5 periods
    elif case == "undersampled":
        t, u, _ = sine(2000, 10.0)
    elif case == "near_nyquist":
        t, u, _ = sine(2000, 2.1)
    elif case == "not_increasing":
        t[100], t[101] = t[101], t[100]
    elif case == "jitter":
        t = t + rng.uniform(-0.02, 0.02, size=t.size) * 1e-3
    elif case == "gap":
        t[1000:] += 0.5
    elif case == "nominal":
        kwargs["nominal_frequency"] = -1.0
    with pytest.raises(error):
        analyse_sine(t, u, **kwargs)


def test_small_jitter_is_accepted() -> None:
    rng = np.random.default_rng(1)
    t, u, omega = sine(2000, 50.3)
    t = t + rng.uniform(-0.004, 0.004, size=t.size) * 1e-3
    assert analyse_sine(t, u).frequency == pytest.approx(omega, rel=1e-4)


# ------------------------------------------------------------------------------------------------------
# find_steady_segments

P_SEG = 97.3  # samples per period of the synthetic records
DT = 1e-3
OMEGA = TWO_PI / (P_SEG * DT)


def bouc_wen_output(u: np.ndarray, dt: float = DT) -> np.ndarray:
    """Bouc-Wen response to the sampled u (static linear part): y = w + offset."""
    _, w = _core.simulate_sampled([2.0], [1.0], 0.0, 1.0, 0.8, 0.2, 1.6, 0.0, u, dt, 2)
    return np.asarray(w)


def composed(
    pieces: Sequence[tuple[str, float, float]], rng: np.random.Generator, noise: float = 2e-3
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """A record of (kind, periods, amplitude) pieces: "idle", "ramp" (from the previous amplitude to this
    one), "steady".  Returns t, u, y and the sample range of each piece."""
    bounds, env = [], []
    pos, last = 0, 0.0
    for kind, periods, amp in pieces:
        count = round(periods * P_SEG)
        if kind == "idle":
            env.append(np.zeros(count))
            last = 0.0
        elif kind == "ramp":
            env.append(np.linspace(last, amp, count, endpoint=False))
            last = amp
        else:
            env.append(np.full(count, amp))
            last = amp
        bounds.append((pos, pos + count))
        pos += count
    envelope = np.concatenate(env)
    t = 3.0 + np.arange(pos) * DT
    u_clean = envelope * np.cos(OMEGA * t - 1.0)
    y = bouc_wen_output(u_clean) + 0.4 + noise * rng.normal(size=pos)
    u = u_clean - 2.0 + noise * rng.normal(size=pos)
    return t, u, y, bounds


def reason_at(report: SegmentReport, k: int) -> str:
    for start, stop, why in report.dropped:
        if start <= k < stop:
            return why
    for seg in report.kept:
        if seg.start <= k < seg.stop:
            return "kept"
    raise AssertionError(f"sample {k} is neither kept nor dropped")


def check_tiling(report: SegmentReport, n: int) -> None:
    """Kept and dropped stretches cover [0, n) exactly once, in order, with no empty stretch."""
    spans = sorted([(s.start, s.stop) for s in report.kept] + [(a, b) for a, b, _ in report.dropped])
    assert spans[0][0] == 0 and spans[-1][1] == n
    for (_, b0), (a1, _) in zip(spans, spans[1:]):
        assert b0 == a1
    assert all(b > a for a, b in spans)
    assert len(report.fits) == len(report.kept)


def test_idle_ramp_steady_pause_steady() -> None:
    rng = np.random.default_rng(7)
    pieces = [
        ("idle", 3, 0.0),
        ("ramp", 4, 1.0),
        ("steady", 12, 1.0),
        ("idle", 5, 0.0),
        ("steady", 10, 0.6),
        ("idle", 2.4, 0.0),
    ]
    t, u, y, b = composed(pieces, rng)
    report = find_steady_segments(t, u, y)
    check_tiling(report, t.size)
    assert len(report.kept) == 2
    for seg, fit, (lo, hi), amp in zip(report.kept, report.fits, (b[2], b[4]), (1.0, 0.6)):
        # The hysteresis output needs a period or two to reach its steady loop after a ramp or a jump
        # (the first loops start from a smaller reversal); at 2e-3 noise over 10 periods that settling is
        # visible in the average, so it may be dropped as well.
        assert abs(seg.stop - hi) <= P_SEG and seg.start - lo <= 3 * P_SEG, (seg, lo, hi)
        assert lo <= seg.start and seg.stop <= hi  # never into the unsteady parts
        assert abs(seg.periods - round(seg.periods)) < 0.01
        assert fit.amplitude == pytest.approx(amp, rel=2e-3)
        assert fit.frequency == pytest.approx(OMEGA, rel=1e-4)
        assert fit.offset == pytest.approx(-2.0, abs=1e-3)
    mid = [(lo + hi) // 2 for lo, hi in b]
    assert [reason_at(report, k) for k in mid] == ["idle", "amplitude ramp", "kept", "pause", "kept", "idle"]
    assert {why for _, _, why in report.dropped} <= {
        "idle",
        "amplitude ramp",
        "pause",
        "transient",
        "partial period",
    }


def test_gap_in_time_axis_is_a_pause() -> None:
    rng = np.random.default_rng(8)
    pieces = [("steady", 8, 1.0), ("idle", 2, 0.0), ("idle", 2, 0.0), ("steady", 8, 1.0)]
    t, u, y, b = composed(pieces, rng)
    t[b[2][0] :] += 17.0  # the DAQ paused for 17 s between the two idle stretches
    with pytest.raises(TimeAxisError):
        analyse_sine(t, u)  # one sine cannot span the gap ...
    report = find_steady_segments(t, u, y)  # ... but the segment finder splits at it
    check_tiling(report, t.size)
    assert len(report.kept) == 2
    assert reason_at(report, b[1][1] - 1) == "pause" and reason_at(report, b[2][0]) == "pause"


def test_level_change_without_pause() -> None:
    rng = np.random.default_rng(9)
    pieces = [("steady", 10, 1.0), ("ramp", 1.5, 0.5), ("steady", 10, 0.5)]
    t, u, y, b = composed(pieces, rng)
    report = find_steady_segments(t, u, y)
    check_tiling(report, t.size)
    assert len(report.kept) == 2
    assert reason_at(report, (b[1][0] + b[1][1]) // 2) == "level change"
    assert [f.amplitude for f in report.fits] == pytest.approx([1.0, 0.5], rel=3e-3)


def test_output_change_under_a_steady_input_splits() -> None:
    """As an MR damper's coil current switched between two tests: same input, another loop."""
    rng = np.random.default_rng(10)
    t, u, y, _ = composed([("steady", 20, 1.0)], rng)
    half = t.size // 2
    y[half:] = 1.5 * (y[half:] - 0.4) + 0.4
    report = find_steady_segments(t, u, y)
    check_tiling(report, t.size)
    assert len(report.kept) == 2
    assert abs(report.kept[0].stop - half) <= P_SEG and abs(report.kept[1].start - half) <= P_SEG


def test_never_steady_raises_with_the_cause() -> None:
    rng = np.random.default_rng(11)
    t, u, y, _ = composed([("idle", 2, 0.0), ("ramp", 15, 1.0), ("idle", 2, 0.0)], rng)
    with pytest.raises(InsufficientDataError, match="amplitude ramp"):
        find_steady_segments(t, u, y)


def test_too_short_steady_stretch() -> None:
    rng = np.random.default_rng(12)
    t, u, y, b = composed(
        [("idle", 3, 0.0), ("ramp", 3, 1.0), ("steady", 3.5, 1.0), ("ramp", 3, 0.0), ("idle", 3, 0.0)], rng
    )
    report = find_steady_segments(t, u, y)
    assert len(report.kept) == 1 and 2.0 <= report.kept[0].periods <= 3.5
    with pytest.raises(InsufficientDataError, match="too short"):
        find_steady_segments(t, u, y, min_periods=5)


def test_find_steady_segments_errors() -> None:
    t, u, _ = sine(3000, 50.3)
    y = u**3
    with pytest.raises(InvalidParameterError):
        find_steady_segments(t, u, y[:-1])
    with pytest.raises(InvalidParameterError):
        find_steady_segments(t, u, y, min_periods=0.5)
    bad = y.copy()
    bad[3] = np.nan
    with pytest.raises(NonFiniteError):
        find_steady_segments(t, u, bad)
    with pytest.raises(ZeroAmplitudeError):
        find_steady_segments(t, np.ones_like(t), y)
    t_bad = t.copy()
    t_bad[10] = t_bad[9]
    with pytest.raises(TimeAxisError):
        find_steady_segments(t_bad, u, y)
    t2, u2, _ = sine(3000, 12.0)
    with pytest.raises(UndersampledError):
        find_steady_segments(t2, u2, u2)
    t3, u3, _ = sine(70, 50.3)
    with pytest.raises(InsufficientDataError):
        find_steady_segments(t3, u3, u3)


# ------------------------------------------------------------------------------------------------------
# synchronous_average


@pytest.mark.parametrize("path", ["qr", "moments"])
def test_reduces_to_the_periodic_average_for_integer_periods(
    path: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """(4a-b): integer odd P, whole periods, all harmonics -> the plain average minus its mean."""
    if path == "moments":
        monkeypatch.setattr(_harmonic_ls, "QR_WORK_MAX", 0.0)
    p, settle, periods = 33, 2, 7
    rng = np.random.default_rng(5)
    n = (settle + periods + 1) * p
    t = np.arange(n) * 0.01
    omega = TWO_PI / (p * 0.01)
    u = 1.3 * np.cos(omega * t)
    y = np.tanh(2 * u) + 0.2 * np.sin(3 * omega * t) + 0.7 + 0.1 * rng.normal(size=n)
    fit = SineFit(omega, 1.3, 0.0, 0.0, 0.0, 0.0, 0.0)
    k = (p - 1) // 2
    ap = synchronous_average(t, y, fit, start=settle * p, stop=(settle + periods) * p, harmonics=k)
    plain = reference.periodic_average(y, p, settle, periods)
    np.testing.assert_allclose(ap.ybar, plain - plain.mean(), rtol=0, atol=1e-12)
    assert ap.offset_y == pytest.approx(plain.mean(), abs=1e-12)
    assert ap.periods == pytest.approx(periods) and ap.noise_dof == periods * p - p
    # The period-to-period spread is the residual of the full harmonic fit: identification's formula.
    seg = y[settle * p : (settle + periods) * p].reshape(periods, p)
    assert ap.noise_var == pytest.approx(float(np.mean(np.var(seg, axis=0, ddof=1))), rel=1e-10)
    # Same with the input's phase estimated from u itself.
    ap2 = synchronous_average(
        t, y, analyse_sine(t, u), start=settle * p, stop=(settle + periods) * p, harmonics=k
    )
    np.testing.assert_allclose(ap2.ybar, plain - plain.mean(), rtol=0, atol=1e-9)


def test_moment_and_qr_paths_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(6)
    t, u, omega = sine(9000, 77.77, phase=0.9)
    y = np.sign(u) * np.abs(u) ** 0.7 + 0.05 * rng.normal(size=t.size)
    fit = analyse_sine(t, u)
    qr = synchronous_average(t, y, fit, start=13)
    monkeypatch.setattr(_harmonic_ls, "QR_WORK_MAX", 0.0)
    mom = synchronous_average(t, y, fit, start=13)
    assert mom.harmonics == qr.harmonics
    np.testing.assert_allclose(mom.ybar, qr.ybar, rtol=0, atol=1e-10)
    assert mom.noise_var == pytest.approx(qr.noise_var, rel=1e-9)


def steady_bouc_wen_record(
    samples_per_period: float, periods: int, noise: float, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float, float]:
    """``G(s) = 1/(0.1 s + 1)`` then Bouc-Wen (0.8, 0.2, 1.6) under ``u = 1.5 cos(3 t)``, sampled with a
    non-integer number of samples per period; returns t, u, y, the true |G|, phi and the settle index."""
    omega, amp = 3.0, 1.5
    dt = TWO_PI / (omega * samples_per_period)
    n = int((periods + 8) * samples_per_period)
    _, w = _core.simulate_sine([1.0], [0.1, 1.0], 0.0, 1.0, 0.8, 0.2, 1.6, 0.0, amp, omega, dt, n, 8)
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    y = np.asarray(w) + 0.25 + noise * rng.normal(size=n)
    g = 1.0 / complex(1.0, 0.1 * omega)
    return t, amp * np.cos(omega * t), y, abs(g), -math.atan2(g.imag, g.real), 8 * samples_per_period


@pytest.mark.parametrize("noise", [0.0, 0.01])
def test_non_integer_period_matches_the_known_loop(noise: float) -> None:
    t, u, y, gain, phi, settle = steady_bouc_wen_record(150.37, 30, noise, seed=2)
    fit = analyse_sine(t, u)
    ap = synchronous_average(t, y, fit, start=math.ceil(settle))
    p = ap.ybar.size
    assert p == 2 * ap.harmonics + 1
    loop = np.asarray(_core.steady_loop(1.5 * gain, 0.8, 0.2, 1.6, phi, p, max(2, 4096 // p))[0])
    err = ap.ybar - (loop - loop.mean())
    assert ap.offset_y == pytest.approx(0.25, abs=max(1e-5, 5 * noise / math.sqrt(ap.periods * p)))
    if noise == 0.0:
        assert ap.harmonics == math.floor(150.37 / 2 - 1)  # noise-free: every harmonic below Nyquist
        assert float(np.max(np.abs(err))) < 1e-4
    else:
        # Truncation leaves no visible bias: the misfit is the noise of ybar, sigma^2 / periods per point.
        assert ap.noise_var == pytest.approx(noise**2, rel=0.05)
        chi2 = float(np.sum(err**2)) / (ap.noise_var / ap.periods)
        assert chi2 / p < 1.5, (chi2, p, ap.harmonics)


@settings(max_examples=25, deadline=None)
@given(
    p=st.floats(16.5, 300.0),
    periods=st.floats(1.5, 20.0),
    coefs=st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=8),
    start=st.integers(0, 30),
)
def test_synchronous_average_property(p: float, periods: float, coefs: list[float], start: int) -> None:
    """A noise-free periodic y with harmonics up to 4 comes back exactly on the grid from u's phase zero,
    whatever the (non-integer) number of samples per period and the start sample."""
    n = start + int(p * periods)
    t, _, omega = sine(n, p, phase=1.1, t0=12.0)
    theta = omega * t - 1.1
    y = 0.5 + sum(c * (np.cos if i % 2 == 0 else np.sin)((i // 2 + 1) * theta) for i, c in enumerate(coefs))
    fit = SineFit(omega, 1.0, 1.1, 0.0, 0.0, 0.0, 0.0)  # u = cos(omega t - 1.1)
    ap = synchronous_average(t, y, fit, start=start, harmonics=6)
    grid = TWO_PI * np.arange(ap.ybar.size) / ap.ybar.size
    expected = sum(c * (np.cos if i % 2 == 0 else np.sin)((i // 2 + 1) * grid) for i, c in enumerate(coefs))
    np.testing.assert_allclose(ap.ybar, expected, atol=1e-8)
    assert ap.offset_y == pytest.approx(0.5, abs=1e-8)


def test_noise_variance_is_unbiased() -> None:
    sd, ratios = 0.05, []
    t, u, omega = sine(1500, 61.37, phase=0.3)
    fit = analyse_sine(t, u)
    clean = np.tanh(1.5 * u) + 0.3 * np.cos(2 * omega * t)
    for seed in range(60):
        rng = np.random.default_rng(100 + seed)
        ap = synchronous_average(t, clean + sd * rng.normal(size=t.size), fit)
        ratios.append(ap.noise_var / sd**2)
    # Each ratio has a standard deviation of about sqrt(2 / dof) ~ 0.04: the mean is good to 0.005.
    assert float(np.mean(ratios)) == pytest.approx(1.0, abs=0.02)


def test_time_origin_is_the_input_phase_zero() -> None:
    t, u, omega = sine(5000, 88.8, phase=2.2, t0=250.0, amp=0.7)
    y = 0.3 + np.cos(omega * t - 2.2 - 0.5) ** 3
    fit = analyse_sine(t, u)
    ap = synchronous_average(t, y, fit, start=321, stop=4321, source="file.csv segment 0")
    assert t[321] <= ap.time_origin < t[321] + TWO_PI / omega
    assert 0.7 * math.cos(omega * ap.time_origin - 2.2) == pytest.approx(0.7, abs=1e-9)
    theta = TWO_PI * np.arange(ap.ybar.size) / ap.ybar.size
    expected = np.cos(theta - 0.5) ** 3
    np.testing.assert_allclose(ap.ybar, expected - expected.mean(), atol=1e-9)
    np.testing.assert_allclose(ap.input_grid(), 0.7 * np.cos(theta), atol=1e-9)
    assert (ap.start, ap.stop, ap.source) == (321, 4321, "file.csv segment 0")
    assert ap.amplitude == pytest.approx(0.7) and ap.frequency == pytest.approx(omega)
    assert ap.offset_u == pytest.approx(0.0, abs=1e-9) and ap.offset_y == pytest.approx(0.3 + 0.0, abs=1e-9)
    assert ap.noise_dof == 4000 - ap.ybar.size and ap.periods == pytest.approx(4000 / ap.ybar.size)
    assert isinstance(ap, AveragedPeriod) and not ap.ybar.flags.writeable


def test_average_measurement_averages_every_kept_segment() -> None:
    """The bridge the identification uses for lab records (duck-typed: t, u, y, nominal_frequency, name)."""
    rng = np.random.default_rng(13)
    t, u, y, _ = composed(
        [
            ("idle", 2, 0.0),
            ("ramp", 2, 1.0),
            ("steady", 8, 1.0),
            ("idle", 3, 0.0),
            ("steady", 8, 0.7),
            ("idle", 2, 0.0),
        ],
        rng,
    )
    record = SimpleNamespace(t=t, u=u, y=y, nominal_frequency=1.02 * OMEGA, name="rig.csv")
    aps = sig.average_measurement(record)  # type: ignore[arg-type]
    report = find_steady_segments(t, u, y)
    assert [a.source for a in aps] == ["rig.csv segment 0", "rig.csv segment 1"]
    assert [(a.start, a.stop) for a in aps] == [(s.start, s.stop) for s in report.kept]
    assert [a.amplitude for a in aps] == pytest.approx([1.0, 0.7], rel=3e-3)


def test_synchronous_average_errors() -> None:
    t, u, omega = sine(2000, 50.3)
    fit = analyse_sine(t, u)
    with pytest.raises(InvalidParameterError):
        synchronous_average(t, u[:-1], fit)
    with pytest.raises(InvalidParameterError):
        synchronous_average(t, u, fit, start=10, stop=5)
    with pytest.raises(InvalidParameterError):
        synchronous_average(t, u, fit, harmonics=26)  # 26 omega is above Nyquist
    with pytest.raises(InvalidParameterError):
        synchronous_average(t, u, fit, harmonics=0)
    with pytest.raises(InsufficientDataError):
        synchronous_average(t, u, fit, stop=40)  # less than one period
    bad = u.copy()
    bad[4] = np.inf
    with pytest.raises(NonFiniteError):
        synchronous_average(t, bad, fit)
    t_bad = t.copy()
    t_bad[700:] += 0.01
    with pytest.raises(TimeAxisError):
        synchronous_average(t_bad, u, fit)
    with pytest.raises(UndersampledError):
        synchronous_average(t, u, SineFit(TWO_PI / (10 * 1e-3), 1.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    with pytest.raises(InsufficientDataError):
        reference.periodic_average(u, 50, 10, 40)
    with pytest.raises(InvalidParameterError):
        reference.periodic_average(u, 50, -1, 2)


# ------------------------------------------------------------------------------------------------------
# Real recordings (no crash: each file gives >= 1 steady segment or a named error)

BH_DT = {"50kHz": 5e-8, "100kHz": 2e-8, "200kHz": 1e-8, "250kHz": 1e-8}
MR_DISPLACEMENT_CHANNEL = {
    "ME25mm0x25Hz": 1,
    "ME25mm0x5Hz": 1,
    "ME2mm5Hz": 1,
    "ME10mm2Hz": 0,
    "ME5mm3Hz": 0,
    "ME5mm4Hz": 0,
}


def _load_bh_loop(path: Path) -> Arrays:
    """2 columns, no header, no time: dB/dt (output), reference current (input); dt from PROVENANCE."""
    d = np.loadtxt(path, delimiter=",")
    return np.arange(d.shape[0]) * BH_DT[path.stem], d[:, 1], d[:, 0]


def _load_friction(path: Path) -> Arrays:
    """JSON 'data' rows: time, displacement (input), friction force (output), ..."""
    d = np.asarray(json.loads(path.read_text())["data"], dtype=np.float64)
    return d[:, 0], d[:, 1], d[:, 2]


def _load_mr(path: Path) -> Arrays:
    """7 header lines; Sample Number, Date/Time (ms), CHANNEL0, CHANNEL1, Events.  Time from the clock, so
    the DAQ pauses between the five coil currents are gaps of the time axis."""
    times, c0, c1 = [], [], []
    for line in path.read_text().splitlines()[7:]:
        fields = line.split(",")
        if len(fields) < 4:
            continue
        _, clock, ampm = fields[1].split()
        h, m, s = clock.split(":")
        hour = int(h) % 12 + (12 if ampm == "PM" else 0)
        times.append(hour * 3600.0 + int(m) * 60.0 + float(s))
        c0.append(float(fields[2]))
        c1.append(float(fields[3]))
    t = np.array(times) - times[0]
    chans = (np.array(c0), np.array(c1))
    disp = MR_DISPLACEMENT_CHANNEL[path.stem]
    return t, chans[disp], chans[1 - disp]


def _load_wire_rope(path: Path) -> Arrays:
    """2 whitespace columns, no header, no time: force (output), displacement (input); 10240 Hz."""
    d = np.array(path.read_text().split(), dtype=np.float64).reshape(-1, 2)
    return np.arange(d.shape[0]) / 10240.0, d[:, 1], d[:, 0]


LOADERS: dict[str, tuple[str, Callable[[Path], Arrays]]] = {
    "bh-loop-microwire": ("*.csv", _load_bh_loop),
    "friction-damper-brfd": ("*.json", _load_friction),
    "mr-damper-utfsm": ("*.txt", _load_mr),
    "wire-rope-isolator": ("*.txt", _load_wire_rope),
}


@pytest.mark.real_data
def test_real_recordings_do_not_crash(real_data: Path) -> None:
    seen = 0
    for folder, (pattern, load) in LOADERS.items():
        files = sorted((real_data / folder).glob(pattern))
        assert files, f"no {pattern} files in {real_data / folder}"
        for path in files:
            seen += 1
            t, u, y = load(path)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", DistortedInputWarning)
                    report = find_steady_segments(t, u, y)
                    first = report.kept[0]
                    # A few harmonics keep this quick; the default choice is tested on synthetic data.
                    fit = report.fits[0]
                    spp = TWO_PI / (fit.frequency * float(np.median(np.diff(t))))
                    ap = synchronous_average(
                        t, y, fit, start=first.start, stop=first.stop, harmonics=min(20, int(spp / 2 - 1))
                    )
            except BoucWenIdError:
                continue  # a named refusal is an acceptable outcome
            assert report.kept, path
            check_tiling(report, t.size)
            assert np.all(np.isfinite(ap.ybar)) and ap.ybar.size == 2 * ap.harmonics + 1
    assert seen == 22


def test_settling_that_one_period_cannot_see_is_trimmed() -> None:
    # A lightly damped plant still settling after the ramp: a decaying change of the output's waveform of
    # 10 % of the fundamental at first, within the per-period tolerance of the run test, but it biases the
    # 40-period average by over 3 of its standard errors.
    trims = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        pieces = [("idle", 2, 0.0), ("ramp", 2, 1.0), ("steady", 40, 1.0), ("idle", 2, 0.0)]
        t, u, y, b = composed(pieces, rng, 0.05)
        lo = b[2][0]
        settle = np.where(np.arange(t.size) >= lo, np.exp(-(np.arange(t.size) - lo) / (2.0 * P_SEG)), 0.0)
        y_settling = y + 0.1 * settle * np.cos(OMEGA * t + 0.3)
        plain = find_steady_segments(t, u, y).kept[0]
        trimmed = find_steady_segments(t, u, y_settling).kept[0]
        assert plain.start - lo <= 1.5 * P_SEG  # without the settling: at most the first loop dropped
        trims.append((trimmed.start - plain.start) / P_SEG)
        assert abs(trimmed.stop - plain.stop) <= 1  # the end is untouched
    # At least one more period dropped (periods are 97.3 samples: 0.997 is one whole window), at most 4
    # time constants (8 periods).
    assert min(trims) >= 0.99 and max(trims) <= 8.0, trims

"""An output zero that drifts in a straight line (issue 18, honest verdicts).

A blind test written from the public docs (benches/blind.py, noise ``drift``: 1 noise sd from the first
recorded sample to the last, its sign per experiment) failed 38 of 40 library cases and 4 of 4 nulls: the
trend of the period means was read as a loop that has not settled ("record more settling periods", wrong
advice: only the DC moves), and even a tenth of a noise sd of drift shifted each experiment's DC beyond its
noise ("unexplained structure at the DC"). ``diagnosis.zero_drift`` finds the straight line (a trend of the
period means that goes on to the end of the record while the loop does not trend) and takes it out as the
wander is taken out; a settling centre (a transient that decays) is not taken for a drift.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import baseline, zero_drift

TWO_PI = 2.0 * math.pi
P = 128
SD = 0.01


def _recs(
    kind: str, seed: int, m: int = 6, periods: int = 16, settle: int = 4, size: float = 1.0
) -> list[Any]:
    """``m`` recordings of a saturating loop written down directly (``y = tanh(2 cos(wt - 0.4))``, no
    simulator) with white noise (sd 0.01) and: "drift" (a straight line of ``size`` noise sd from the first
    sample to the last, sign per recording), "settling" (a centre that settles exponentially over 3 periods,
    10 noise sd), "ar1" (phi = 0.8), "ar1 slow" (phi = 0.99), "fading" (the loop itself shrinking 2 % over
    the record, and the drift), "white" (nothing more)."""
    rng = np.random.default_rng([seed, 28])
    n = (settle + periods) * P
    out = []
    for i in range(m):
        om = TWO_PI * (0.5 + 0.25 * i)
        t = np.arange(n) * (TWO_PI / om / P)
        u = (1.0 + 0.2 * i) * np.cos(om * t)
        y = np.tanh(2.0 * np.cos(om * t - 0.4))
        e = rng.normal(0.0, SD, n)
        line = float(rng.choice([-1.0, 1.0])) * size * SD * np.linspace(0.0, 1.0, n)
        if kind in ("drift", "fading"):
            e = e + line
        if kind == "fading":
            y = y * (1.0 - 0.02 * np.linspace(0.0, 1.0, n))
        elif kind == "settling":
            e = e + 10.0 * SD * np.exp(-np.arange(n) / (3.0 * P))
        elif kind in ("ar1", "ar1 slow"):
            phi = 0.8 if kind == "ar1" else 0.99  # 0.99: correlated over about a period
            z = rng.normal(0.0, SD * math.sqrt(1.0 - phi**2), n)
            for k in range(1, n):
                z[k] += phi * z[k - 1]
            e = z
        out.append(bw.Recording(t, u, y + e, 1.0 + 0.2 * i, om, settle_periods=settle))
    return out


def test_a_straight_line_drift_is_found_and_measured() -> None:
    for seed in range(5):
        recs = _recs("drift", seed)
        assert baseline.detect(recs, 0.05 / 20) is None  # not rough: the wander test does not see it
        d = zero_drift.detect(recs, 0.05 / 20)
        assert d is not None, seed
        assert d.p_value < zero_drift.DRIFT_ALPHA and d.loop_p >= zero_drift.DRIFT_ALPHA
        # 1 noise sd over each record: the slopes' size, within their noise (about 0.1 sd of the total).
        assert 0.7 < d.largest / SD < 1.5, d.largest / SD
        assert 0.7 < d.sigma / SD < 1.3


@pytest.mark.parametrize("kind", ["white", "ar1", "ar1 slow", "settling"])
def test_noise_a_settling_centre_and_a_trending_loop_are_no_drift(kind: str) -> None:
    """White or AR(1) noise has no trend (noise correlated over a period, phi = 0.99, has its period means
    correlated, and their slope's error is inflated as much); a centre that settles has its first half
    steeper than its last (a transient decays)."""
    for seed in range(5):
        assert zero_drift.detect(_recs(kind, seed), 0.05 / 20) is None, (kind, seed)


def test_a_zero_drifting_beside_a_trending_loop_is_flagged(monkeypatch: pytest.MonkeyPatch) -> None:
    """Session 29 (zero_drift.BESIDE_LOOP_TREND): on, a loop whose fundamental trends (a degradation) while
    its zero drifts has the line taken out too, flagged (no centre kept), and the loop's trend left to the
    degradation and settling tests (tests/test_degradation_beside_drift.py); off, the drift is left in."""
    monkeypatch.setattr(zero_drift, "BESIDE_LOOP_TREND", False)
    for seed in range(2):
        assert zero_drift.detect(_recs("fading", seed), 0.05 / 20) is None, seed
    monkeypatch.setattr(zero_drift, "BESIDE_LOOP_TREND", True)
    for seed in range(5):
        d = zero_drift.detect(_recs("fading", seed), 0.05 / 20)
        assert d is not None and d.loop_trends and d.loop_p < zero_drift.DRIFT_ALPHA, seed


def test_removal_takes_out_the_line_and_the_period_means() -> None:
    recs = _recs("drift", 2)
    d = zero_drift.detect(recs, 0.05 / 20)
    assert d is not None
    out = baseline.removed(recs, d)
    clean = _recs("white", 2)  # the same loop and noise draw without the line (the rng draws the same)
    for r, o, c in zip(recs, out, clean):
        n = r.whole_periods
        rows = np.asarray(o.y).reshape(n, P)
        np.testing.assert_allclose(rows.mean(axis=1), d.centre, atol=1e-12)
        assert baseline.marked(o) and o.metadata[baseline.MARK] == repr(0.0)  # a line is no walk
        # The within-period ramp is gone too: the harmonics match the line-free data's to the slope's error.
        a = np.fft.rfft(np.asarray(c.y).reshape(n, P), axis=1)[:, 1:4].mean(axis=0)
        b = np.fft.rfft(rows, axis=1)[:, 1:4].mean(axis=0)
        assert np.max(np.abs(a - b)) / P < 0.2 * SD / math.sqrt(n * P / 2)


def _drifting(helpers: SimpleNamespace, seed: int, size: float) -> tuple[list[Any], list[Any]]:
    """The designs bench's base null (its own plant and RK4, white noise) as recorded, and with a straight
    line of ``size`` noise sd over each record added, its sign per recording."""
    dd = helpers.designs_bench()
    recs = helpers.designs_case("base", None, "", 0.0, seed)
    rng = np.random.default_rng([seed, 7])
    out = []
    for r in recs:
        line = (
            float(rng.choice([-1.0, 1.0])) * size * dd.NOISE_SD * np.linspace(0.0, 1.0, np.asarray(r.y).size)
        )
        out.append(
            bw.Recording(
                r.t, r.u, np.asarray(r.y) + line, r.amplitude, r.frequency, settle_periods=r.settle_periods
            )
        )
    return recs, out


@pytest.mark.parametrize("seed", [100002, 100003])
def test_a_drifting_zero_is_no_unsettled_loop(
    helpers: SimpleNamespace, monkeypatch: pytest.MonkeyPatch, seed: int
) -> None:
    """A null with a 1 sd drift: before, "not settled ... record more settling periods" (or structure at the
    DC); now the verdict the same data get without the drift, with the drift's clause and note. (Seed
    100001 is left out: its drift-free set passes at p = 0.021, and taking the period means out moves it to
    0.019.)"""
    clean, drifting = _drifting(helpers, seed, 1.0)
    ref = helpers.diagnose_quietly(clean)
    d = helpers.diagnose_quietly(drifting)
    assert d.status == ref.status == "adequate", d.summary()
    assert "zero drifts" in d.verdict and "not settled" not in d.verdict, d.verdict
    assert any(n.startswith("the output's zero drifts") for n in d.notes)
    monkeypatch.setattr(zero_drift, "detect", lambda items, level: None)  # the code before: no drift test
    old = helpers.diagnose_quietly(drifting)
    assert old.status != "adequate" or "not settled" in old.verdict, old.summary()


def test_a_settled_set_keeps_its_verdict(helpers: SimpleNamespace) -> None:
    """No drift, no clause: the designs bench's white-noise null is not taken for a drift."""
    clean, _ = _drifting(helpers, 100001, 1.0)
    assert zero_drift.detect(clean, 0.05 / 20) is None


def _lab(kind: str, seed: int, m: int = 6, periods: int = 20, spp: float = 100.37) -> list[Any]:
    """``m`` lab Measurements at a fixed sampling rate (``spp`` samples per period: no whole number) of the
    saturating loop written down directly, no simulator, with white noise (sd 0.01), a small input noise
    and: "drift" (1 noise sd over the record, sign per measurement), "settling" (10 noise sd decaying over
    3 periods), "fading" (the loop shrinking 2 % and the drift), "ar1" (phi = 0.8), "white"."""
    rng = np.random.default_rng([seed, 29])
    out = []
    for i in range(m):
        om = TWO_PI * (0.5 + 0.25 * i)
        n = int(periods * spp)
        t = np.arange(n) * (TWO_PI / om / spp)
        u = (1.0 + 0.2 * i) * np.cos(om * t) + rng.normal(0.0, 1e-4, n)
        y = np.tanh(2.0 * np.cos(om * t - 0.4))
        e = rng.normal(0.0, SD, n)
        line = float(rng.choice([-1.0, 1.0])) * SD * np.linspace(0.0, 1.0, n)
        if kind in ("drift", "fading"):
            e = e + line
        if kind == "fading":
            y = y * (1.0 - 0.02 * np.linspace(0.0, 1.0, n))
        elif kind == "settling":
            e = e + 10.0 * SD * np.exp(-np.arange(n) / (3.0 * spp))
        elif kind == "ar1":
            z = rng.normal(0.0, SD * 0.6, n)
            for k in range(1, n):
                z[k] += 0.8 * z[k - 1]
            e = z
        out.append(bw.Measurement(t, u, y + e, nominal_frequency=om, name=f"m{i}"))
    return out


def test_a_drift_on_the_lab_path_is_found_and_taken_out() -> None:
    """A fixed sampling rate (no whole number of samples per period): each whole period's mean from the
    least-squares fit on the input's phase; the line measured and taken out, the measurement marked."""
    for seed in range(3):
        meas = _lab("drift", seed)
        d = zero_drift.detect(meas, 0.05 / 20)
        assert d is not None, seed
        assert 0.7 < d.largest / SD < 1.5, d.largest / SD
        out = baseline.removed(meas, d)
        for o, c in zip(out, _lab("white", seed)):  # the same draws without the line
            assert baseline.MARK in o.metadata
            resid = np.asarray(o.y) - np.asarray(c.y)  # a constant left (the centre less the DC)
            assert float(np.ptp(resid)) < 0.2 * SD, float(np.ptp(resid)) / SD


@pytest.mark.parametrize("kind", ["white", "ar1", "settling"])
def test_lab_noise_a_settling_centre_and_a_trending_loop_are_no_drift(
    kind: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    for seed in range(3):
        assert zero_drift.detect(_lab(kind, seed), 0.05 / 20) is None, (kind, seed)
    monkeypatch.setattr(zero_drift, "BESIDE_LOOP_TREND", False)
    assert zero_drift.detect(_lab("fading", 0), 0.05 / 20) is None  # the old rule stands aside
    monkeypatch.setattr(zero_drift, "BESIDE_LOOP_TREND", True)
    for seed in range(3):  # a trending loop's drifting zero: found, flagged (session 29, the flag on)
        d = zero_drift.detect(_lab("fading", seed), 0.05 / 20)
        assert d is not None and d.loop_trends, seed


def test_a_drifting_lab_zero_is_no_unsettled_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """Before: "not settled ... record more settling periods" (wrong: only the zero moves); now the drift's
    note, and no such advice."""
    meas = _lab("drift", 0)
    d = bw.diagnose(meas)
    assert "not settled" not in d.verdict, d.verdict
    assert any(n.startswith("the output's zero drifts") for n in d.notes)
    monkeypatch.setattr(zero_drift, "detect", lambda items, level: None)  # the code before
    old = bw.diagnose(meas)
    assert "not settled" in old.verdict, old.verdict


def test_diagnose_across_takes_a_drifting_zero_out(
    helpers: SimpleNamespace, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``diagnose_across`` on two conditions of the designs bench's null (its own plant and RK4), each with a
    1 sd drift: its verdict says the zero drifts there and names nothing; before (the wander test alone) the
    drift was left in."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sets = [_drifting(helpers, s, 1.0)[1] for s in (100002, 100003)]
        a = bw.diagnose_across(sets, condition=[0.0, 1.0])
        monkeypatch.setattr(zero_drift, "detect", lambda items, level: None)  # the code before
        old = bw.diagnose_across(sets, condition=[0.0, 1.0])
    assert "the output's zero drifts at 0, 1" in a.verdict, a.verdict
    assert a.terms == () and a.status == "adequate", a.verdict
    assert "zero drifts" not in old.verdict, old.verdict


def _lab97(
    seed: int, slowing: float = 0.0, drift: float = 1.0, every: bool = False, first: int = 1
) -> list[Any]:
    """``m`` fixed-rate lab Measurements at 97.3 samples per period, written down directly (a first-order
    lag with a delay ahead of a saturating loop, ``0.8 tanh(2.5 cos(wt - phi)) + 0.1 cos(wt - phi)``), AR(1)
    noise (phi = 0.7, sd 0.01) and a straight drift of ``drift`` noise sd over each record (sign per
    measurement); the first ``first`` measurements (``every``: each) also carry a transient of ``slowing``
    noise sd decaying over a quarter of its record, in the direction that makes its first half steeper."""
    from scipy.signal import lfilter  # type: ignore[import-untyped]

    rng = np.random.default_rng([seed, 31])
    n = int(30 * 97.3)
    out = []
    for i in range(8):
        om = TWO_PI * (0.4 + 0.3 * i)
        t = np.arange(n) * (TWO_PI / om / 97.3)
        u = (1.0 + 0.1 * i) * np.cos(om * t) + rng.normal(0.0, 1e-4, n)
        ph = math.atan(om / 2.0) + 0.05 * om
        y = 0.8 * np.tanh(2.5 * np.cos(om * t - ph)) + 0.1 * np.cos(om * t - ph)
        e = lfilter([1.0], [1.0, -0.7], rng.normal(0.0, SD * math.sqrt(1.0 - 0.49), n))
        sign = float(rng.choice([-1.0, 1.0]))
        e = e + sign * drift * SD * np.linspace(0.0, 1.0, n)
        if i < first or every:
            e = e - sign * slowing * SD * np.exp(-np.arange(n) / (n / 4.0))
        out.append(bw.Measurement(t, u, y + e, nominal_frequency=om, name=f"m{i}"))
    return out


def test_one_slowing_measurement_does_not_sink_a_drift() -> None:
    """A drift in all eight measurements, one of them with a transient besides (its halves' slopes apart at
    p = 4e-4 to 5e-3): before, any one measurement whose first half was steeper (Bonferroni 0.05 / 8) sank
    the drift for the whole set (left in, read as 'not settled' or at the DC; blind play:30:5); now the decay
    test is pooled (Stouffer, 0.01), and every measurement's line is taken out."""
    for seed in range(3):
        meas = _lab97(seed, slowing=1.5)
        d = zero_drift.detect(meas, 0.05 / 20)
        assert d is not None, seed
        out = baseline.removed(meas, d)
        for j, (o, c) in enumerate(zip(out, _lab97(seed, slowing=1.5, drift=0.0))):
            assert baseline.MARK in o.metadata
            if j:  # the others: only their line and a constant differ from the same draws without it
                assert float(np.ptp(np.asarray(o.y) - np.asarray(c.y))) < 0.3 * SD, (seed, j)


def test_one_strong_transient_does_not_sink_a_drift() -> None:
    """As above with a 3 sd transient in the first measurement (its decay p 5e-8 to 8e-7): before the review,
    Stouffer's sum took its z whole (5-6) and the pooled p fell to 0.004-0.0008 (seeds 0, 1, 4; measured),
    the drift lost; now each z is capped at the slowing bound (that measurement is a slowing one, which the
    drift must stand without anyway)."""
    for seed in (0, 1, 4):
        d = zero_drift.detect(_lab97(seed, slowing=3.0), 0.05 / 20)
        assert d is not None and "m0" in d.decaying, seed


def _settling(seed: int, size: float, tau: float) -> list[Any]:
    """Eight recordings with NO zero drift, each settling (review of session 30): two fast (3 noise sd,
    decaying over a quarter of the record), six slowly (``size`` sd over ``tau`` records); a saturating loop
    at eight frequencies, white noise (sd 0.01)."""
    rng = np.random.default_rng([seed, 77])
    p, n, out = 64, 28 * 64, []
    for i in range(8):
        om = TWO_PI * (0.5 + 0.25 * i)
        t = np.arange(n) * (TWO_PI / om / p)
        e = rng.normal(0.0, SD, n)
        big, decay = (3.0, n / 4.0) if i < 2 else (size, n * tau)
        e -= big * SD * np.exp(-np.arange(n) / decay)
        y = np.tanh(2.0 * np.cos(om * t - 0.4)) + e
        out.append(bw.Recording(t, np.cos(om * t), y, 1.0, om, settle_periods=4))
    return out


def test_a_settling_set_is_no_drift() -> None:
    """The review of session 30: leaving the slowing minority (the two fast transients) out of the pooled
    decay test called such a set a drift (the six slow ones alone show too little decay): on seeds 1, 2 and
    4 of these five, and in 103 and 61 of 150 draws where the capped pool over all called 6 and 1
    (docs/degradation-beside-drift.md; seed 5 is one of the capped pool's few). All are pooled, capped."""
    for seed in range(5):
        for size, tau in ((5.0, 2.0), (4.0, 1.5)):
            assert zero_drift.detect(_settling(seed, size, tau), 0.05 / 20) is None, (seed, size, tau)


def test_the_pooled_decay_test_caps_each_recording() -> None:
    """The pool (zero_drift._pooled) over all that trend, each z capped at the slowing bound: two of eight
    at p = 1e-9 and six at 0.3 are a decay (p 0.002); without the cap the two alone would be (z 6 each)
    whatever the six showed, with it six at 0.7 (z -0.52 each) are not."""
    assert zero_drift._pooled([1e-9, 1e-9, *[0.3] * 6]) < zero_drift.DECAY_LEVEL
    assert zero_drift._pooled([1e-9, 1e-9, *[0.7] * 6]) >= zero_drift.DECAY_LEVEL


def test_a_short_recording_is_named_untested() -> None:
    """A recording of fewer than 8 periods after settling beside tested ones: its line is not tested (slope
    0, only its period means replaced) and the note says so rather than "each recording's line"."""
    short = _recs("drift", 1, m=1, periods=6)
    d = zero_drift.detect([*_recs("drift", 0), *short], 0.05 / 20)
    assert d is not None and d.slopes[-1] == 0.0
    label = zero_drift._label(short[0], 6)
    assert d.short == (label,) and f"{label} has fewer than" in d.note(), d.note()


def test_transients_in_every_measurement_are_no_drift() -> None:
    """The other side: the same transient in every measurement (and no line) adds up in the pooled test."""
    for seed in range(3):
        assert zero_drift.detect(_lab97(seed, slowing=1.5, drift=0.0, every=True), 0.05 / 20) is None, seed
    for seed in range(2):  # and a strong one, each z capped at the slowing bound, still adds up
        assert zero_drift.detect(_lab97(seed, slowing=3.0, drift=0.0, every=True), 0.05 / 20) is None, seed


def _stretches(seed: int, drift: float = 1.0) -> Any:
    """One fixed-rate Measurement (97.3 samples per period) of two stretches (amplitudes 1.0 and 0.6, 24
    periods each, idle between), white noise (sd 0.01) and a straight drift over the whole record."""
    rng = np.random.default_rng([seed, 32])
    om, spp = TWO_PI * 0.8, 97.3
    plan = [(0.0, 3), (1.0, 24), (0.0, 4), (0.6, 24), (0.0, 3)]
    t = np.arange(int(sum(k for _, k in plan) * spp)) * (TWO_PI / om / spp)
    amp, start = np.zeros(t.size), 0.0
    for a, k in plan:
        amp[(t >= start * TWO_PI / om) & (t < (start + k) * TWO_PI / om)] = a
        start += k
    u = amp * np.cos(om * t) + rng.normal(0.0, 1e-4, t.size)
    y = 0.8 * np.tanh(2.5 * amp * np.cos(om * t - 0.5)) + rng.normal(0.0, SD, t.size)
    y = y + float(rng.choice([-1.0, 1.0])) * drift * SD * np.linspace(0.0, 1.0, t.size)
    return bw.Measurement(t, u, y, nominal_frequency=om, name="rig")


def test_a_measurement_of_several_stretches_is_tested_and_detrended() -> None:
    """Before, a Measurement of more than one averaged stretch was not tested (the note still said every
    recording's line was taken out): one line over its time now, each stretch its own level. Two such files
    of one rig (a lone item is held to the per-recording decay test at 0.05, as before)."""
    from bouc_wen_id.signal import average_measurement

    for seed in range(3):
        meas = [_stretches(seed), _stretches(seed + 100)]
        assert [len(average_measurement(m)) for m in meas] == [2, 2]
        d = zero_drift.detect(meas, 0.05 / 20)
        assert d is not None and d.untested == (), seed
        assert 0.7 < d.largest / SD < 1.5, d.largest / SD
        out = baseline.removed(meas, d)
        for o, c in zip(out, [_stretches(seed, 0.0), _stretches(seed + 100, 0.0)]):
            resid = np.asarray(o.y) - np.asarray(c.y)
            assert float(np.ptp(resid)) < 0.3 * SD, float(np.ptp(resid)) / SD
    assert zero_drift.detect([_stretches(0, 0.0), _stretches(100, 0.0)], 0.05 / 20) is None

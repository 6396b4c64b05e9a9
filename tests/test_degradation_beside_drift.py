"""A degradation under a zero that drifts in a straight line (session 29): the drift is taken out, the loop's
trend named as the degradation it is (not "not settled"), on records written here in NumPy.

The records are not the library's simulator's: a Baber-Noori strength degradation on x from a first-order G
by classical RK4 on the whole state ``[x, w, e]`` (x's derivative from the state), uniform output noise (not
Gaussian; an AR(1) one's period means read as a wandering baseline, which takes the line out
first) and a straight-line drift of the output's zero, its sign per record. On main before this session the
zero-drift test stood aside (the fundamental trends) and the drift left in the blocks' DC hid the
degradation: "not settled: the loop of every experiment ... still drifts".
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import drift as D
from bouc_wen_id.diagnosis import zero_drift

TWO_PI = 2.0 * math.pi
BETA, GAMMA, MU = 0.7, 0.3, 1.8  # saturation level 1
NU = T.Degradation.kind
SD = 0.01
#: The strength degradation: a change of a few per cent over the record (about 10x the averaged noise sd).
RATE = 5e-4


def _w(
    omegas: np.ndarray, amps: np.ndarray, n_periods: int, p: float, nu: float, asym: float = 0.0
) -> np.ndarray:
    """w at the samples (m, n_periods p): ``0.05 x' = u - x``, u = U cos(omega t) from rest, the element's
    rate ``x' - (1 + nu e)(beta |x'| sgn(w) |w|^mu + gamma x' |w|^mu)``, ``e' = w x'``; 16 RK4 steps a
    sample."""
    sub = 16
    h = TWO_PI / omegas / (p * sub)

    def f(t: np.ndarray, s: np.ndarray) -> np.ndarray:
        xdot = (amps * np.cos(omegas * t) - s[0]) / 0.05
        w, e = s[1], s[2]
        wm = np.abs(w) ** MU * (1.0 + asym * np.sign(w))  # asym: the branches' strength apart
        rate = xdot - (1.0 + nu * e) * (BETA * np.abs(xdot) * np.sign(w) * wm + GAMMA * xdot * wm)
        return np.array([xdot, rate, w * xdot])

    s = np.zeros((3, omegas.size))
    t = np.zeros(omegas.size)
    total = int(n_periods * p)  # p need not be whole (a fixed sampling rate)
    out = np.empty((omegas.size, total))
    for k in range(total):
        out[:, k] = s[1]
        for _ in range(sub):
            k1 = f(t, s)
            k2 = f(t + h / 2, s + h / 2 * k1)
            k3 = f(t + h / 2, s + h / 2 * k2)
            k4 = f(t + h, s + h * k3)
            s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            t = t + h
    return out


def _records(
    seed: int, nu: float, drift: float, settle: int = 6, periods: int = 30, p: int = 128, asym: float = 0.0
) -> list[Any]:
    """Three frequencies by x at 0.8 and 2 times saturation; uniform white noise (sd ``SD``) and a line of
    ``drift`` noise sd from the first sample to the last (its sign per record)."""
    omegas = np.repeat(TWO_PI * np.array([0.5, 1.2, 3.0]), 2)
    gains = 1.0 / np.sqrt(1.0 + (0.05 * omegas) ** 2)
    amps = np.tile([0.8, 2.0], 3) / gains
    n = settle + periods
    w = _w(omegas, amps, n, p, nu, asym)
    rng = np.random.default_rng([seed, 2029])
    recs = []
    for i in range(omegas.size):
        t = np.arange(n * p) * TWO_PI / omegas[i] / p
        z = rng.uniform(-SD * math.sqrt(3.0), SD * math.sqrt(3.0), t.size)
        line = float(rng.choice([-1.0, 1.0])) * drift * SD * np.linspace(0.0, 1.0, t.size)
        u = amps[i] * np.cos(omegas[i] * t)
        recs.append(bw.Recording(t, u, w[i] + z + line, amps[i], omegas[i], settle))
    return recs


def _lab_records(
    seed: int, nu: float, drift: float, periods: int = 36, spp: float = 100.37, asym: float = 0.0
) -> list[Any]:
    """As :func:`_records`, as lab Measurements: a fixed sampling rate (``spp`` samples a period, not whole),
    the specimen virgin at the first sample, a small input noise; no settling periods declared."""
    omegas = np.repeat(TWO_PI * np.array([0.5, 1.2, 3.0]), 2)
    gains = 1.0 / np.sqrt(1.0 + (0.05 * omegas) ** 2)
    amps = np.tile([0.8, 2.0], 3) / gains
    w = _w(omegas, amps, periods, spp, nu, asym)
    rng = np.random.default_rng([seed, 2030])
    out = []
    for i in range(omegas.size):
        t = np.arange(w.shape[1]) * TWO_PI / omegas[i] / spp
        z = rng.uniform(-SD * math.sqrt(3.0), SD * math.sqrt(3.0), t.size)
        line = float(rng.choice([-1.0, 1.0])) * drift * SD * np.linspace(0.0, 1.0, t.size)
        u = amps[i] * np.cos(omegas[i] * t) + rng.normal(0.0, 1e-4, t.size)
        out.append(bw.Measurement(t, u, w[i] + z + line, nominal_frequency=omegas[i], name=f"m{i}"))
    return out


#: the clause said under a trending loop: the line taken out, read as neither a zero's nor the loop's
BESIDE = "the period means trend in a straight line while the loop trends"
#: the clause when the fitted model's own centre trend leaves no drift (session 30, loop_centre.py)
FIXED = "the output's zero is taken as fixed"
#: the clauses when a drift remains after it: the line taken out with the period means, or alone
DRIFTS = ("the output's zero drifts (taken out", "the output's zero drifts beyond the degrading loop")
#: ... said only when the model that predicted the loop's centre fits (status "explained"); else the line left
#: may be that model's misfit (session 43, loop_centre.CentreCheck.text)
UNSURE = "the fitted model does not fit well enough to say whether the zero drifts beyond it"


def _drift_said(d: Any) -> bool:
    """The drift beyond the loop's centre said as the zero's on a model that fits, else the qualified one."""
    if d.status == "explained":
        return any(c in d.verdict for c in DRIFTS) and UNSURE not in d.verdict
    return UNSURE in d.verdict and not any(c in d.verdict for c in DRIFTS)


@pytest.fixture
def beside() -> Iterator[None]:
    """The flag on (:data:`zero_drift.BESIDE_LOOP_TREND`, the default) whatever another test left."""
    old = zero_drift.BESIDE_LOOP_TREND
    zero_drift.BESIDE_LOOP_TREND = True
    yield
    zero_drift.BESIDE_LOOP_TREND = old


@pytest.mark.usefixtures("beside")
def test_a_drifting_zero_beside_a_trending_loop_is_found_and_flagged() -> None:
    recs = _records(1, RATE, 1.0)
    d = zero_drift.detect(recs, 0.05 / 16)
    assert d is not None and d.loop_trends  # the loop trends (p below the level) and the zero drifts
    assert d.loop_p < zero_drift.DRIFT_ALPHA
    assert 0.6 < d.largest / SD < 1.6, d.largest / SD  # 1 sd per record, within the slopes' noise
    assert "the loop trends too" in d.note() and "cannot tell apart" in d.note()
    assert not d.kept and "zero drifts" not in d.clause()  # no centre kept, the line not called the zero's


def test_the_old_rule_stands_aside(monkeypatch: pytest.MonkeyPatch) -> None:
    """The flag's other side: the rule before session 29, which left the drift in."""
    monkeypatch.setattr(zero_drift, "BESIDE_LOOP_TREND", False)
    assert zero_drift.detect(_records(1, RATE, 1.0), 0.05 / 16) is None


@pytest.mark.parametrize("flag", [False, True])
def test_an_asymmetric_degrading_loop_is_no_drifting_zero(flag: bool) -> None:
    """A degrading asymmetric loop (branch strengths 1.4 and 0.6) and no drift: its centre moves with the
    degradation in a near straight line, which the zero-drift test reads as a drift (p = 1e-20). With the
    flag on before the review its kept centre was named an output offset and the verdict said "the output's
    zero drifts", the asymmetry lost (measured, seed 1); now, on (the default), no offset named and the line
    not called the zero's; off (the rule before), the asymmetry and the degradation named."""
    old = zero_drift.BESIDE_LOOP_TREND
    try:
        zero_drift.BESIDE_LOOP_TREND = flag
        d = bw.diagnose(_records(1, RATE, 0.0, asym=0.4))
    finally:
        zero_drift.BESIDE_LOOP_TREND = old
    assert "zero drifts" not in d.verdict, d.verdict
    assert T.Offset.kind not in d.named_terms, d.summary()
    # Session 30 (loop_centre.py): on, the loop's own centre trend is predicted by the fitted model and
    # leaves no drift, so the records are diagnosed as they are; main named nothing here ("unexplained
    # ...; recording 1, recording 3, recording 5 left out (not settled)", measured).
    # Session 36 (bounds_said, review 36 problem 3): with mu held at its bracket's end and a misfit left,
    # a steady term is said as fitted there, not named; the drift term, tested on the drift, stays named.
    held = "fitted with mu held at the lower end of its bracket, not named: asymmetry" in d.verdict
    assert NU in d.named_terms and (T.Asymmetry.kind in d.named_terms or held), d.summary()
    assert "not settled" not in d.verdict, d.verdict
    if flag:
        assert FIXED in d.verdict, d.verdict


@pytest.mark.usefixtures("beside")
@pytest.mark.parametrize("seed", [3, 4])
def test_a_degradation_under_a_drifting_zero_is_named(seed: int) -> None:
    """Main before this session: "not settled: the loop of every experiment ... still drifts" (seeds 3, 4
    and 6; measured); now named, its value within 10 % (measured -0.5 % to +0.5 %, sd 1.3 %)."""
    d = bw.diagnose(_records(seed, RATE, 1.0))
    assert NU in d.named_terms, d.summary()
    assert not d.verdict.startswith("not settled"), d.verdict
    assert BESIDE in d.verdict, d.verdict  # taken out, said so
    assert "differs in sign" not in d.verdict, d.verdict  # no loop centres read from the drift
    # Session 30: the degrading loop's own centre trend (the fitted model simulated) is taken off the period
    # means and a drift remains: the zero's, said so (main: "a drifting zero or a degrading loop's centre"),
    # when that model fits (session 43).
    assert _drift_said(d) and FIXED not in d.verdict, d.verdict
    got = next(t for t in d.named if t.term == NU)
    assert abs(got.value - RATE) < 0.1 * RATE, d.summary()


@pytest.mark.usefixtures("beside")
def test_a_drifting_zero_beside_an_asymmetric_degrading_loop_is_found() -> None:
    """Session 30: the asymmetric degrading loop above (its centre moving with its strength) and a drifting
    zero of 1 noise sd besides. The fitted model's own centre trend taken off the period means, a drift
    remains (the zero's: its sign per record, not the loop's); that line alone is taken out, each period's
    mean kept, and the asymmetry and the degradation are named. Main: "unexplained ...; recording 1,
    recording 3, recording 5 left out (not settled); ... a drifting zero or a degrading loop's centre"
    (measured, seed 2)."""
    d = bw.diagnose(_records(2, RATE, 1.0, asym=0.4))
    # Session 36 (bounds_said, review 36 problem 3): with mu held at its bracket's end and a misfit left,
    # a steady term is said as fitted there, not named; the drift term, tested on the drift, stays named.
    held = "fitted with mu held at the lower end of its bracket, not named: asymmetry" in d.verdict
    assert NU in d.named_terms and (T.Asymmetry.kind in d.named_terms or held), d.summary()
    assert "not settled" not in d.verdict, d.verdict
    # Session 43: the model fits in part here (asymmetry and degradation, "42 % of the excess", measured):
    # the line left beyond its centre is not called the zero's drift, the clause says it cannot tell.
    assert _drift_said(d) and FIXED not in d.verdict, d.verdict
    assert T.Offset.kind not in d.named_terms, d.summary()


def test_a_drifting_zero_alone_names_no_degradation() -> None:
    """The null beside it: the same records without degradation; the zero's line is taken out as before (the
    loop does not trend, so the flag is not set) and no drift term is named."""
    recs = _records(5, 0.0, 1.0)
    z = zero_drift.detect(recs, 0.05 / 16)
    assert z is not None and not z.loop_trends
    d = bw.diagnose(recs)
    assert NU not in d.named_terms and T.StiffnessDegradation.kind not in d.named_terms, d.summary()


def test_a_lab_experiment_is_corrected_over_its_whole_periods() -> None:
    """The lab correction simulates the stretch's whole periods (its per-period record), not the averaging's
    weight ``periods`` (samples over grid points, several times more)."""
    from bouc_wen_id.diagnosis.data import prepare

    om, spp, n = TWO_PI * 1.0, 251.37, 24
    t = np.arange(int(n * spp)) * (TWO_PI / om / spp)
    rng = np.random.default_rng(7)
    y = np.tanh(2.0 * np.cos(om * t - 0.4)) + rng.normal(0.0, SD, t.size)
    meas = bw.Measurement(t, np.cos(om * t) + rng.normal(0.0, 1e-4, t.size), y, nominal_frequency=om)
    (e,) = prepare([meas])
    # The weight is not the cycles (samples over the grid's 2K + 1 points: on the full band,
    # lab_settle.full_band, a grid of 249 points against 251.37 samples a period; several times the cycles
    # on the averaging's default band).
    assert abs(e.periods - e.h1.size) > 0.5
    assert D.recorded_periods(e) == e.h1.size and e.h1.size <= n
    recs = _records(1, 0.0, 0.0, settle=2, periods=5, p=16)
    (r,) = prepare(recs[:1])
    assert D.recorded_periods(r) == int(r.periods) == 5  # a recording: as before


@pytest.mark.usefixtures("beside")
@pytest.mark.parametrize("seed", [3, 4])
@pytest.mark.filterwarnings("ignore::bouc_wen_id.errors.TransientWarning")  # virgin at the first sample:
# the lab path trims its first periods (diagnosis/lab_settle.py), as the recording path trims a transient
def test_a_lab_degradation_under_a_drifting_zero_is_named(seed: int) -> None:
    """The fixed-rate lab path (Measurements): main before this session said "not settled" on seeds 3 and 4
    (measured); now named (measured 4.87e-4 and 5.46e-4, se 1.7e-5), the zero's line taken out."""
    d = bw.diagnose(_lab_records(seed, RATE, 1.0))
    assert NU in d.named_terms, d.summary()
    assert BESIDE in d.verdict, d.verdict
    assert T.Offset.kind not in d.named_terms, d.summary()  # the drift's DC is no output offset
    got = next(t for t in d.named if t.term == NU)
    assert abs(got.value - RATE) < max(5.0 * got.standard_error, 0.15 * RATE), d.summary()


def test_across_a_trending_loop_is_not_said_a_drifting_zero() -> None:
    """diagnose_across says what diagnose says: under a trending loop the straight line of the period means
    is a drifting zero or a degrading loop's centre, not 'the output's zero drifts' (the review's
    asymmetric degrading loop, no drift)."""
    recs = _records(1, RATE, 0.0, asym=0.4)
    d = bw.diagnose_across([recs, recs], [0.0, 1.0], candidates=[T.Offset.kind])
    assert "zero drifts" not in d.verdict, d.verdict
    assert "a drifting zero or a degrading loop's centre" in d.verdict, d.verdict
    assert T.Offset.kind not in d.named, d.verdict

"""A sensor gain drifting over each record is said, divided out and every record kept (gain_out.py,
review 47 failure 5); a loop still settling, a decaying gain transient and a settling centre are not read
as one.

The data are this file's own few-line RK4 (a resonant G behind a delay, a Bouc-Wen element of exponent 2,
``y = w + K_X x``), apart from the library's, the benches' and the reviews' generators.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import gain_out

FREQS, AMPS = (0.5, 1.0, 0.5, 1.0), (0.8, 0.8, 1.6, 1.6)  # Hz, the drive's amplitude
P, PERIODS, K_X, SD = 64, 12, 0.2, 0.004


def _rk4(settle: int) -> tuple[Any, Any]:
    """(sample step per experiment, y per experiment and sample) from rest: x'' = wn^2 (u(t - d) - x) -
    2 zeta wn x', z' = x' (1 - (0.6 sgn(x' z) + 0.4) z^2), y = z + K_X x; four RK4 steps a sample."""
    om, amps, wn = 2 * np.pi * np.asarray(FREQS), np.asarray(AMPS), 9.0
    h = 2 * np.pi / om / P

    def f(t: Any, s: Any) -> Any:
        x, v, z = s
        dv = wn**2 * (amps * np.cos(om * (t - 0.02)) - x) - 0.3 * wn * v
        return np.array([v, dv, v * (1 - (0.6 * np.sign(v * z) + 0.4) * z**2)])

    s, t, ys = np.zeros((3, om.size)), np.zeros(om.size), np.zeros(((settle + PERIODS) * P, om.size))
    for i in range(ys.shape[0]):
        ys[i] = s[2] + K_X * s[0]
        for _ in range(4):
            k1 = f(t, s)
            k2 = f(t + h / 8, s + h / 8 * k1)
            k3 = f(t + h / 8, s + h / 8 * k2)
            k4 = f(t + h / 4, s + h / 4 * k3)
            s, t = s + h / 24 * (k1 + 2 * k2 + 2 * k3 + k4), t + h / 4
    return h, ys.T


def _records(settle: int, drift: float, seed: int, lab: bool = False) -> list[Any]:
    """Recordings (or lab Measurements of the whole record) whose output gain drifts linearly by ``drift``
    from the first sample to the last, plus white noise of sd :data:`SD`."""
    h, ys = _rk4(settle)
    rng = np.random.default_rng(seed)
    out: list[Any] = []
    for i, y0 in enumerate(ys):
        t = np.arange(y0.size) * h[i]
        y = y0 * (1 + drift * t / t[-1]) + SD * rng.normal(size=t.size)
        u, om, name = AMPS[i] * np.cos(2 * np.pi * FREQS[i] * t), 2 * np.pi * FREQS[i], f"r{i}"
        if lab:
            out.append(bw.Measurement(t, u, y, nominal_frequency=om, name=name))
        else:
            out.append(bw.Recording(t, u, y, AMPS[i], om, settle, metadata={"name": name}))
    return out


def _true_rate(drift: float, settle: int) -> float:
    """The gain's rate per period relative to the gain at the record's first sample."""
    return drift * P / ((settle + PERIODS) * P - 1)


@pytest.fixture(scope="module")
def drifting() -> Any:
    recs = _records(6, 0.03, 1)
    return recs, bw.diagnose(recs, value_stability=False)


def test_a_gain_drift_on_a_resonant_plant_is_said_divided_out_and_the_stiffness_named(drifting: Any) -> None:
    recs, d = drifting
    assert not d.settings.get("left_out")  # every record kept
    assert "the output's gain drifts" in d.verdict and "calibrate the sensor" in d.verdict
    assert "record more settling periods" not in d.verdict
    rates = d.settings[gain_out.SETTING]
    assert sorted(rates) == [r.metadata["name"] for r in recs]
    for row in rates.values():  # each record's own rate, within its standard error of the truth
        assert abs(row["rate_per_period"] - _true_rate(0.03, 6)) < 4 * row["se"]
    named = {t.term: t for t in d.named}
    assert "stiffness@x" in named, d.verdict
    assert abs(named["stiffness@x"].value - K_X) < 4 * named["stiffness@x"].standard_error
    assert all(np.array_equal(a.y, b.y) for a, b in zip(recs, _records(6, 0.03, 1)))  # the user's untouched


def test_a_loop_still_settling_is_not_read_as_a_gain_drift() -> None:
    """From rest, no settling periods: the resonance's free ring and the loop's centre still move."""
    settling = _records(0, 0.0, 2)
    names = [r.metadata["name"] for r in settling]
    assert gain_out.read(settling, names) is None
    assert gain_out.read(_records(6, 0.03, 2), names) is not None  # the same reader on a gain drift


def _steady(recs: list[Any], change: Any) -> list[Any]:
    """``recs`` with each sample's output passed through ``change(y, tau)`` (tau in periods from the end of
    settling)."""
    out = []
    for r in recs:
        tau = np.arange(r.y.size) / P - r.settle_periods
        out.append(bw.Recording(r.t, r.u, change(r.y, tau), r.amplitude, r.frequency, r.settle_periods))
    return out


@pytest.mark.parametrize(
    "change",
    [
        lambda y, tau: y * (1 + 0.03 * np.exp(-np.maximum(tau, 0) / 3)),  # a gain transient that decays
        lambda y, tau: y + 0.05 * np.exp(-np.maximum(tau, 0) / 4),  # a loop centre settling
    ],
    ids=["decaying gain", "settling centre"],
)
def test_a_transient_is_refused_where_a_line_is_read(change: Any) -> None:
    base = _records(6, 0.0, 3)
    names = [f"recording {i}" for i in range(len(base))]
    assert gain_out.read(_steady(base, change), names) is None
    line = _steady(base, lambda y, tau: y * (1 + 0.0015 * tau))
    got = gain_out.read(line, names)
    assert got is not None and all(r.gain_p < gain_out.GAIN_LEVEL for r in got.records.values())


def test_a_lab_measurement_of_the_whole_record_is_read_too() -> None:
    """The command line's path: each CSV a Measurement, settling included, the library finding the
    steady stretch; the verdict's advice is the sensor's."""
    recs = _records(6, 0.03, 4, lab=True)
    d = bw.diagnose(recs, value_stability=False)
    assert "the output's gain drifts" in d.verdict, d.verdict
    assert "record more settling periods" not in d.verdict
    assert not d.settings.get("left_out")
    assert math.isfinite(max(r["se"] for r in d.settings[gain_out.SETTING].values()))


def test_records_of_different_lengths_share_one_drift_over_each_record() -> None:
    """A 3 % drift over each record, the records 18 to 32 periods long: one rate on that clock (each record's
    rate per period is 3 % over its own length), where one per period or per second would not fit."""
    h, ys = _rk4(20)
    rng = np.random.default_rng(5)
    recs = []
    for i, settle in enumerate((6, 10, 14, 20)):
        y0 = ys[i][: (settle + PERIODS) * P]
        t = np.arange(y0.size) * h[i]
        y = y0 * (1 + 0.03 * t / t[-1]) + SD * rng.normal(size=t.size)
        u, om = AMPS[i] * np.cos(2 * np.pi * FREQS[i] * t), 2 * np.pi * FREQS[i]
        recs.append(bw.Recording(t, u, y, AMPS[i], om, settle, metadata={"name": f"r{i}"}))
    got = gain_out.read(recs, ["r0"])
    assert got is not None and got.clock == "over each record"
    for r, settle in zip(got.records.values(), (6, 10, 14, 20)):
        assert abs(r.rate - _true_rate(0.03, settle)) < 4 * r.se

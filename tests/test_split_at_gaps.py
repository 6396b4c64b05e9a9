"""Dropped samples and pauses: ``bw.split_at_gaps`` and the error that names it (review 35 ``null_drop``).

A record with 3 dropped samples was refused with "resample, or split the record at the gap", and the package
had no helper for either. ``split_at_gaps`` cuts a record at its gaps into uniformly sampled Measurements,
which diagnose takes; the refusal names it. Tested on dropped samples of a resonant plant with its own noise,
and on a real pause (the DAQ stopped for 1.3 s).
"""

from __future__ import annotations

import warnings

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.errors import InvalidParameterError, TimeAxisError


def _recs() -> list[bw.Recording]:
    lin = bw.TransferFunction([4.0], [1.0, 0.8, 4.0])
    om = np.array([1.0, 1.8, 3.0])
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om, 1.0 / g, settle_periods=10, periods=14, samples_per_period=64, substeps=8, noise_sd=0.004,
        seed=18,
    )  # fmt: skip
    return bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5)), plan)


def _dropped(r: bw.Recording, where: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    keep = np.ones(r.t.size, dtype=bool)
    keep[[int(f * r.t.size) for f in where]] = False
    return np.array(r.t[keep]), np.array(r.u[keep]), np.array(r.y[keep])


def test_the_refusal_names_the_helper() -> None:
    r = _recs()[0]
    t, u, y = _dropped(r, (0.6,))
    with pytest.raises(TimeAxisError, match=r"split_at_gaps\(t, u, y\).*Measurements"):
        bw.Measurement(t, u, y)
    with pytest.raises(TimeAxisError, match="split_at_gaps"):
        bw.Recording(t, u, y, amplitude=r.amplitude, frequency=r.frequency, settle_periods=r.settle_periods)


def test_dropped_samples_give_pieces_diagnose_takes() -> None:
    recs = _recs()
    pieces: list[bw.Measurement] = []
    for i, r in enumerate(recs):
        t, u, y = _dropped(r, (0.55, 0.8))
        given = [a.copy() for a in (t, u, y)]
        got = bw.split_at_gaps(t, u, y, nominal_frequency=r.frequency, name=f"e{i}", units={"y": "N"})
        assert len(got) == 3 and all(np.array_equal(a, b) for a, b in zip((t, u, y), given))  # untouched
        assert np.array_equal(np.concatenate([p.t for p in got]), t)
        assert np.array_equal(np.concatenate([p.y for p in got]), y)
        assert [p.name for p in got] == [f"e{i} piece {k} of 3" for k in (1, 2, 3)]
        assert got[0].metadata["piece"].startswith("1 of 3: samples 0..") and got[1].units["y"] == "N"
        assert all(p.nominal_frequency == r.frequency for p in got)
        pieces += got
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(pieces, candidates=[bw.terms.Stiffness.kind])
    assert d.status == "adequate", d.verdict  # a plain plant, the diagnosis runs on the pieces
    assert len(d.experiments) >= len(recs)


def test_a_pause_is_a_gap_and_times_are_kept() -> None:
    r = _recs()[1]
    t = np.array(r.t)
    half = t.size // 2
    t[half:] += 1.3  # the DAQ paused for 1.3 s
    a, b = bw.split_at_gaps(t, r.u, r.y)
    assert a.t[-1] == t[half - 1] and b.t[0] == t[half] and b.t.size == t.size - half
    whole = bw.Measurement(r.t, r.u, r.y, name="r")
    (one,) = bw.split_at_gaps(whole)  # a record object without a gap: one piece, its name and data kept
    assert one.name == "r" and np.array_equal(one.y, whole.y)


def test_what_is_no_gap_is_refused_by_name() -> None:
    r = _recs()[0]
    t = np.array(r.t)
    t[100] -= 0.3 * (t[1] - t[0])  # a short step: a jittering axis, not a gap
    with pytest.raises(TimeAxisError, match="resample"):
        bw.split_at_gaps(t, r.u, r.y)
    t, u, y = _dropped(r, (0.5, 0.5 + 2 / r.t.size))  # one sample alone between two gaps
    with pytest.raises(InvalidParameterError, match="lies alone between two gaps"):
        bw.split_at_gaps(t, u, y)
    with pytest.raises(InvalidParameterError, match="t, u and y"):
        bw.split_at_gaps(r.t, r.u)


def test_a_piece_too_short_to_analyse_is_left_out_and_said() -> None:
    """Review 35: 3 dropped samples left a 1-period piece, which stopped diagnose on the whole set."""
    r = _recs()[0]
    t, u, y = _dropped(r, (0.97,))  # the last ~0.7 period after the gap
    with pytest.warns(bw.errors.GapWarning, match=r"1 of 2 pieces of e left out.*samples \d+\.\.\d+"):
        (kept,) = bw.split_at_gaps(t, u, y, nominal_frequency=r.frequency, name="e")
    assert kept.t.size == int(0.97 * r.t.size)
    assert len(bw.split_at_gaps(t, u, y, nominal_frequency=r.frequency, min_periods=0)) == 2
    assert len(bw.split_at_gaps(t, u, y)) == 2  # no nominal frequency: nothing to measure periods by
    with pytest.raises(bw.errors.InsufficientDataError, match="nothing is left"):
        bw.split_at_gaps(t, u, y, nominal_frequency=r.frequency, min_periods=100)

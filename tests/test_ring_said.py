"""Session 46 (ring46): the ring-down check's words, and diagnose_across's words on what it left out.

- The note "a free ring-down ... was not checked" was in every real data set's notes (lab segments of 1-7
  periods, under the 11 its test reads): now the segments are in the settings (ring_unchecked.KEY) and the
  notes say them only where the diagnosis read a drift from period to period (ring_unchecked.py).
- diagnose_across said "the loop still drifts" with no p; now at drift_said's standard (each record's
  adjusted p; "still drifts" only below drift_said.FIRM), ringing records said as ringing.
- The ring majority was counted over every condition's items at once; now per condition over its
  experiments: a condition most of whose records ring is left out whole (across_settling.RINGS).

Data: lab Measurements made here (a loop of a few lines, seeded noise), drift_null_sim.py's RK4 records and
test_across_checks.py's resonant-G records (wiener_sim's RK4); none from the library's generator.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

NOTE = "was not checked in the steady segments"


def _quiet(f: Any, *a: Any, **kw: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return f(*a, **kw)


def _short_measurements(seed: int) -> list[Any]:
    """Four lab Measurements of 8 periods each (100.37 samples a period): a steady loop (a lag term makes
    it open), white noise from ``seed``; their steady segments hold 7 whole periods."""
    import bouc_wen_id as bw

    rng = np.random.default_rng(seed)
    out = []
    for k, (f, a) in enumerate([(1.0, 1.0), (2.0, 1.0), (1.0, 2.0), (3.0, 1.5)]):
        w = 2 * math.pi * f
        t = np.arange(int(8 * 100.37)) / (100.37 * f)
        u = a * np.sin(w * t)
        y = np.tanh(u) + 0.3 * u + 0.1 * a * np.cos(w * t) + rng.normal(0, 0.003, t.size)
        out.append(bw.Measurement(t, u, y, nominal_frequency=w, name=f"m{k}"))
    return out


def test_short_segments_of_a_steady_loop_are_recorded_not_noted() -> None:
    """Main: the note in every diagnosis of short lab segments. Here: no note (nothing in the verdict rests
    on a change from period to period), the segments and what to do in the settings."""
    import bouc_wen_id as bw

    ms = _short_measurements(3)
    d = _quiet(bw.diagnose, ms, candidates=["offset", "viscous"], value_stability=False)
    assert not any(NOTE in n for n in d.notes), d.notes
    from bouc_wen_id.diagnosis import ring_down, ring_unchecked

    short = _quiet(ring_down.checked, ms)[2]
    assert len(short) == len(ms), short  # every segment is too short: the check could not run
    assert ring_unchecked.drift_read(d) == "", d.settings
    got = d.settings[ring_unchecked.KEY]
    assert got["segments"] == short and str(ring_down.LEAST_PERIODS) in got["what_to_do"], got


def test_the_unchecked_segments_are_noted_where_a_drift_was_read() -> None:
    """A diagnosis that left records out as drifting: the note names the segments, the records and what to
    do; a record left out because it rang (its ring-down checked) is no drift read."""
    from bouc_wen_id.diagnosis import ring_unchecked
    from bouc_wen_id.diagnosis.settling import LEFT_OUT

    @dataclass(frozen=True)
    class Read:  # what ring_unchecked reads of a Diagnosis
        settings: dict[str, Any]
        notes: tuple[str, ...] = ("x",)
        named: tuple[Any, ...] = ()
        degradation: Any = None

    d = Read({LEFT_OUT: ["m2 segment 0"]})
    said = ring_unchecked.said(d, ["m0 segment 0 (3)"], ring_unchecked.drift_read(d))
    (note,) = [n for n in said.notes if NOTE in n]
    assert "m2 segment 0" in note and "m0 segment 0 (3)" in note and ring_unchecked.TODO in note, note
    assert said.settings[ring_unchecked.KEY]["segments"] == ["m0 segment 0 (3)"]
    assert ring_unchecked.drift_read(d, [SimpleNamespace(source="m2 segment 0")]) == ""


def test_a_weak_drift_left_out_across_says_may_drift_with_its_p() -> None:
    """Two conditions of drift_null_sim's records, a 0.4 % gain drift on one record at the first (adjusted p
    between FIRM and the leave-out level), 1 % on one at the second (firm). Main: "the loop still drifts"
    for both, no p. Here "may drift" with the weak one's p, "still drifts" with the firm one's."""
    import bouc_wen_id as bw
    import drift_null_sim as sim
    from bouc_wen_id.diagnosis import drift_said
    from bouc_wen_id.diagnosis.locate import LEVEL

    weak, firm = sim.recordings(1, n_exp=8, gain=(0.004, (3,))), sim.recordings(2, n_exp=8, gain=(0.01, (2,)))
    a = _quiet(bw.diagnose_across, [weak, firm], [0.0, 1.0], candidates=["offset", "viscous"])
    w, f = weak[3].metadata["name"], firm[2].metadata["name"]
    pw = re.search(
        rf"may drift from period to period \([^)]*adjusted p = {re.escape(w)} ([0-9.e+-]+)\)", a.verdict
    )
    pf = re.search(
        rf"still drifts from period to period \([^)]*adjusted p = {re.escape(f)} ([0-9.e+-]+)\)", a.verdict
    )
    assert pw is not None and pf is not None, a.verdict
    assert drift_said.FIRM <= float(pw.group(1)) < 0.5 * LEVEL and drift_said.firm(float(pf.group(1))), (
        a.verdict
    )
    assert any("may drift" in n and w in n for n in a.notes), a.notes


def test_a_condition_most_of_whose_records_ring_is_left_out_whole(monkeypatch: pytest.MonkeyPatch) -> None:
    """across_settling.drop: two of three records ring, the condition is left out (diagnose names nothing
    from such a set; main kept the one left and judged the condition on it); one of three, it is left out
    alone, said as ringing, not drifting."""
    from bouc_wen_id.diagnosis import across_settling

    monkeypatch.setattr(across_settling, "settled_only", lambda e, named: (list(range(len(e))), []))
    exps: Any = [SimpleNamespace(source=s) for s in ("a", "b", "c")]
    with pytest.raises(across_settling.NotSettled) as err:
        _quiet(across_settling.drop, exps, "1", lambda: None, frozenset({"a", "b"}))
    assert err.value.left_why == across_settling.RINGS and err.value.names == ("a", "b")
    text = across_settling.clause([], [err.value])
    assert "2 of its 3 experiments" in text and "ring-down" in text and "drifts" not in text, text
    g = SimpleNamespace(label="2", left_out=("b",), left_p=(math.nan,), rung=("b",), left_why="")
    text = across_settling.clause([g], [])
    assert "b still holds the free ring-down" in text and "drift" not in text, text


def test_a_ringing_condition_beside_settled_ones_is_left_out_across() -> None:
    """Review 44's design D (G resonant, zeta 0.05, 10 settle periods: 5 of 8 records ring) beside two null
    levels of a well-damped G. Main: the ring counted over all 24 records (a minority), the ringing
    condition judged on its 3 records left, "adequate across 3 conditions", its rings said as "still
    drifts". Here that condition is left out, said as ringing, and the joint verdict stands on the others."""
    import bouc_wen_id as bw
    from test_across_checks import levels

    ring = levels(6.0, 0.05, 0.003, 10, 4, 0.9, 13, [1.0])
    null = levels(5.0, 0.3, 0.008, 20, 8, 0.5, 1, [1.0, 1.5])
    a = _quiet(bw.diagnose_across, [*ring, *null], [1.0, 2.0, 3.0])
    assert "condition 1 left out" in a.verdict and "still hold the free ring-down" in a.verdict, a.verdict
    assert "across 2 conditions" in a.verdict and not a.named, a.verdict
    assert "still drifts" not in a.verdict, a.verdict

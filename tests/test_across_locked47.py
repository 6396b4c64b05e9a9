"""diagnose_across says a spike locked to the excitation and reads the conditions again with it bridged, as
diagnose does (locked_said.py; session 47, across47: diagnosis/across_locked.py).

Data made apart from the benches' generator: the tests' resonant G with a delay (wiener_sim.py, its own RK4)
at two drive amplitudes as two conditions, white noise 1 % of the output's rms from a seed, and a drive's EMI
of 20 standard errors of the averaged period at sample 37 of every period of one condition's records. Main
read "unexplained structure remains; nothing named" with no word of the spike; the records without it are
adequate.
"""

from __future__ import annotations

import math
import re
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np

NOTE = re.compile(r"^(\S+): (\S+) \(experiment (\d)\): sample (\d+) stands ([\d.]+) se off every model")


def _condition(seed: int, amp: float, size_se: float, at: int = 37) -> list[Any]:
    """Three records (1, 2, 4 Hz) of wiener_sim's plant driven at ``amp``, white noise 1 % of the output's
    rms, ``size_se`` standard errors of the averaged period added at sample ``at`` of every period."""
    from wiener_sim import PERIODS, SETTLE, P, simulate

    freqs = np.array([1.0, 2.0, 4.0])
    h, u, w = simulate(freqs, amp * np.ones(3))
    rng = np.random.default_rng(seed)
    recs = []
    for i, f in enumerate(freqs):
        t = np.arange(w[i].size) * h[i]
        sd = 0.01 * float(np.sqrt(np.mean(w[i] ** 2)))
        y = w[i] + rng.normal(0.0, sd, t.size)
        y[at::P] += size_se * sd / math.sqrt(PERIODS)
        meta = {"name": f"a{amp:g}r{i}"}
        recs.append(
            bw.Recording(t, u[i], y, amp, 2 * math.pi * float(f), settle_periods=SETTLE, metadata=meta)
        )
    return recs


def _across(size_se: float) -> Any:
    groups = [_condition(4701, 1.0, 0.0), _condition(4702, 1.5, size_se)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], held_out_test=False)


def test_a_spike_locked_to_every_period_at_one_condition_is_said_and_read_bridged() -> None:
    control = _across(0.0)
    assert control.status == "adequate" and "bridged" not in control.verdict, control.verdict
    assert not any(NOTE.match(n) for n in control.notes), control.notes
    a = _across(20.0)
    said = [m.groups() for n in a.notes if (m := NOTE.match(n))]
    # each of condition 1's three records, its own experiment number there, at sample 37, about 20 se
    assert sorted((c, r, e, s) for c, r, e, s, _ in said) == [
        ("1", f"a1.5r{i}", str(i + 1), "37") for i in range(3)
    ], a.notes
    assert all(15.0 < float(z) < 25.0 for *_, z in said), said
    assert a.status == "adequate" and "bridged (off every model" in a.verdict, a.verdict  # main: unexplained
    first = [n for n in a.notes if n.startswith("with sample 37 of a1.5r0")]
    assert len(first) == 1 and "left in, the diagnosis read: unexplained:" in first[0], a.notes

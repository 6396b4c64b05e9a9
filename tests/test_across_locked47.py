"""diagnose_across says a spike locked to the excitation and reads the conditions again with it bridged, as
diagnose does (locked_said.py; session 47, across47: diagnosis/across_locked.py).

Data made apart from the benches' generator: the tests' resonant G with a delay (wiener_sim.py, its own RK4)
as test_locked_spike.py's records, two seeds as two conditions, white noise 1 % of the output's rms, and a
drive's EMI of 20 standard errors of the averaged period at sample 37 of every period of one condition's
records. Main read "unexplained structure remains" with no word of the spike; the records without it are
adequate.
"""

from __future__ import annotations

import re
import warnings
from typing import Any

import bouc_wen_id as bw

NOTE = re.compile(r"^(\S+): (\S+) \(experiment (\d)\): sample (\d+) stands ([\d.]+) se off every model")


def _across(size_se: float) -> Any:
    from test_locked_spike import _resonant  # its records: three frequencies, the spike at sample 37

    groups = [_resonant(4701, 0.0, ()), _resonant(4702, size_se, (0, 1, 2))]
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
        ("1", f"rec{i}", str(i + 1), "37") for i in range(3)
    ], a.notes
    assert all(15.0 < float(z) < 25.0 for *_, z in said), said
    assert a.status == "adequate" and "bridged (off every model" in a.verdict, a.verdict  # main: unexplained
    first = [n for n in a.notes if n.startswith("with sample 37 of rec0")]
    assert len(first) == 1 and "left in, the diagnosis read: unexplained:" in first[0], a.notes

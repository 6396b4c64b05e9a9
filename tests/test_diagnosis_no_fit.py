"""A candidate with no fit says why in the step table and the JSON record (review 31a item 10)."""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import bouc_wen_id as bw
from bouc_wen_id.diagnosis.select import Step, Trial
from bouc_wen_id.terms import Dahl, Viscous

NAN = math.nan


def test_a_failed_fit_is_a_row_with_its_reason_not_nan() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.5], [0.2, 1.0]), bw.BoucWen(1.0, 0.3, 1.5, 1.0))
    plan = bw.SinePlan(
        frequencies=[2.0, 5.0], amplitudes=1.0, settle_periods=5, periods=6, samples_per_period=64
    )
    d = bw.diagnose(bw.simulate(plant, plan), candidates=[Viscous.kind])
    failed = [Trial(k, NAN, NAN, NAN, NAN, NAN, NAN, False) for k in (Dahl.kind, Viscous.kind)]
    d = replace(d, steps=(Step(10.0, 100, tuple(failed), None),))
    table = re.compile(rf"  ({Dahl.kind}|{Viscous.kind})\s\s")  # a row: the name padded to 12 characters
    rows = [line for line in d.summary().splitlines() if table.match(line)]
    assert len(rows) == 2 and all("no fit:" in r and "nan" not in r for r in rows)
    assert "shape" in rows[0] and "shape" not in rows[1]  # the two-term element's own reason
    record = json.loads(d.to_json())["steps"][0]["trials"]
    assert all(t["failure"].startswith("no fit:") for t in record)

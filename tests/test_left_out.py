"""Records left out as not settled: the JSON lists them with the reason and the statistics they were left out
of, and the status, the JSON's adequacy, the headline and the summary agree (diagnosis/left_out.py)."""

from __future__ import annotations

import json
import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis.left_out import UNSETTLED, WHAT_TO_DO, report_html

TWO_PI = 2.0 * math.pi
FIRST = bw.TransferFunction([1.0], [0.05, 1.0])
RESONANT = bw.TransferFunction([1600.0], [1.0, 24.0, 1600.0], delay=0.005)  # 40 rad/s, damping 0.3


def _settling(lin: bw.TransferFunction, settling: int, seed: int) -> list[bw.Recording]:
    """Four sine recordings of a null plant (white noise, sd 0.01), the last ``settling`` of them with a
    loop centre still settling: 0.08 decaying as exp(-t / 0.3 of the record) from the first kept period."""
    om = TWO_PI * np.array([0.5, 1.5, 4.0, 2.5])
    amps = np.array([0.8, 2.0, 1.2, 1.6]) / lin.gain_phase(om)[0]
    plan = bw.SinePlan(
        om, amps, settle_periods=8, periods=12, samples_per_period=64, substeps=8, noise_sd=0.0
    )
    rng = np.random.default_rng(seed)
    out = []
    for i, r in enumerate(bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.7, 0.3, 1.8)), plan)):
        y = r.y + rng.normal(0.0, 0.01, r.y.size)
        if i >= 4 - settling:
            start = r.settle_periods * r.samples_per_period
            y[start:] += 0.08 * np.exp(-np.arange(y.size - start) / (y.size - start) / 0.3)
        out.append(bw.Recording(r.t, r.u, y, r.amplitude, r.frequency, settle_periods=r.settle_periods))
    return out


def _agrees(d: Any, j: dict[str, Any]) -> None:
    """The status and the JSON's adequacy from one rule: "adequate" exactly when the plain model passes."""
    assert j["before"]["adequate"] == (d.status == "adequate"), (d.status, j["before"])
    if d.status == "unexplained":
        assert not j["after"]["adequate"], j["after"]


@pytest.mark.parametrize("lin", [FIRST, RESONANT], ids=["first-order", "resonant-delay"])
def test_two_settling_records_are_listed_and_the_headline_says_on_which_it_was_judged(
    lin: bw.TransferFunction,
) -> None:
    """2 of 4 records still settling: "adequate on recording 0, recording 1", the other two listed with
    their reason in the JSON, the summary and the report; before, the JSON had their names only (no reason)
    and the headline was a bare "adequate: ...", the left-out ones in the verdict's last clause."""
    d = bw.diagnose(_settling(lin, 2, seed=1))
    j = json.loads(d.to_json())
    assert j["settings"]["left_out"] == ["recording 2", "recording 3"], d.summary()
    assert [(r["record"], r["reason"]) for r in j["left_out_records"]] == [
        ("recording 2", UNSETTLED),
        ("recording 3", UNSETTLED),
    ]
    assert all("adequacy test" in r["left_out_of"] for r in j["left_out_records"])
    assert j["judged_on"] == ["recording 0", "recording 1"] == j["before"]["judged_on"]
    assert d.status == "adequate" and not j["before"]["not_judged"], d.summary()
    _agrees(d, j)
    assert d.headline.startswith("adequate on recording 0, recording 1: "), d.headline
    assert (
        d.details[0] == f"recording 2, recording 3 left out (not settled, or a drifting sensor): {WHAT_TO_DO}"
    )
    assert "unexplained" not in d.verdict
    text = d.summary()
    assert "left out: recording 2 (unsettled: " in text and "judged on: recording 0, recording 1" in text
    assert "recording 3: unsettled" in "".join(report_html(d))


def test_most_records_settling_is_not_adequate_in_the_json_either() -> None:
    """3 of 4 still settling: the status is "unexplained" (the verdict would rest on one record,
    drift_majority.py); before, the JSON said ``"before": {"adequate": true}`` beside it."""
    d = bw.diagnose(_settling(RESONANT, 3, seed=2))
    j = json.loads(d.to_json())
    assert d.status == "unexplained", d.summary()
    assert len(j["left_out_records"]) == 3 and j["judged_on"] == ["recording 0"]
    _agrees(d, j)
    assert "3 of 4" in j["before"]["not_judged"]
    assert "where the plain model misses: not judged: most records" in d.summary()


def test_degradation_is_still_named_and_nothing_left_out() -> None:
    """A drift that is physics (strength degradation, first-order G, white noise): named as degradation,
    no record left out, the headline as before."""
    om = np.repeat(TWO_PI * np.array([0.5, 2.0]), 2)
    amps = np.tile([0.8, 2.0], 2) / FIRST.gain_phase(om)[0]
    plant = bw.WienerPlant(FIRST, bw.BoucWen(0.7, 0.3, 1.8), terms=(T.Degradation(1e-3),))
    plan = bw.SinePlan(
        om, amps, settle_periods=6, periods=16, samples_per_period=64, substeps=8, noise_sd=0.01, seed=4
    )
    d = bw.diagnose(bw.simulate(plant, plan))
    j = json.loads(d.to_json())
    assert "degradation" in d.named_terms and d.status == "explained", d.summary()
    assert d.headline.startswith("explained by: ") and "degradation" in d.headline
    assert j["left_out_records"] == [] and len(j["judged_on"]) == 4
    assert j["after"]["adequate"] and not j["after"]["not_judged"]


def test_the_records_judged_on_never_split_the_status_phrase() -> None:
    # The wire rope read "unexplained on 16Hz_A2 segment 0, ... structure remains at harmonics ...".
    from bouc_wen_id.diagnosis.left_out import _on

    kept = "rec 0, rec 1"
    assert _on("unexplained structure remains at harmonics 1, 3", "unexplained", kept) == (
        "unexplained structure remains at harmonics 1, 3 (judged on rec 0, rec 1)"
    )
    assert (
        _on("adequate: the plain model fits", "adequate", kept)
        == "adequate on rec 0, rec 1: the plain model fits"
    )
    assert _on("explained by: viscous", "explained", kept) == "explained on rec 0, rec 1 by: viscous"
    assert (
        _on("explained in part by: x", "partly explained", kept) == "explained in part on rec 0, rec 1 by: x"
    )

"""The value check inside ``diagnose``: a named value that moves under preprocessing is not a finding."""

from __future__ import annotations

import math
from dataclasses import replace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import value_stability as vs
from bouc_wen_id.diagnosis.result import Diagnosis

FIRST = bw.TransferFunction([1.0], [0.05, 1.0])


def _recs(seed: int = 1) -> list[bw.Recording]:
    om = np.repeat(np.array([3.0, 9.0, 25.0]), 2)
    gain, _ = FIRST.gain_phase(om)
    plan = bw.SinePlan(
        om,
        np.tile([0.8, 2.0], 3) / gain,
        settle_periods=8,
        periods=16,
        samples_per_period=64,
        substeps=8,
        noise_sd=0.01,
        seed=seed,
    )
    plant = bw.WienerPlant(FIRST, bw.BoucWen(0.7, 0.3, 1.8), terms=(T.StiffnessX(0.3),))
    return bw.simulate(plant, plan)


@pytest.fixture(scope="module")
def true_term() -> tuple[list[bw.Recording], Diagnosis]:
    recs = _recs()
    return recs, bw.diagnose(recs)


def test_a_true_term_keeps_explained_and_the_check_ran(
    true_term: tuple[list[bw.Recording], Diagnosis],
) -> None:
    _, d = true_term
    assert d.status == "explained", d.summary()
    assert d.named_terms == ("stiffness@x",)
    info = d.settings[vs.KEY]
    assert info["checked"] and info["completed"] == ["early", "late"]
    assert info["unstable"] == []
    zs = [r["z"] for r in info["comparisons"]]
    assert len(zs) == 2 and all(math.isfinite(z) and z < info["z_threshold"] for z in zs)
    assert "unstable under preprocessing" not in d.verdict


def test_a_value_that_moves_through_the_record_is_not_a_finding(
    true_term: tuple[list[bw.Recording], Diagnosis],
) -> None:
    # The same records with the parallel stiffness rising 60 % through each one (a warming device): the
    # final model refitted on the early and the late two thirds gives values far apart.
    recs, d = true_term
    moved = []
    for r in recs:
        t, x = np.asarray(r.t), np.asarray(r.x)
        y = np.asarray(r.y) + 0.18 * t / t[-1] * x
        moved.append(bw.Recording(t, r.u, y, r.amplitude, r.frequency, r.settle_periods, metadata=r.metadata))
    off = replace(d, settings={k: v for k, v in d.settings.items() if k != vs.KEY})
    got = vs.checked(off, moved)
    assert got.settings[vs.KEY]["unstable"] == ["stiffness@x"]
    assert got.status == "partly explained"
    assert got.verdict.startswith("explained in part by: ")
    assert "unstable under preprocessing (k = 0.3" in got.verdict
    assert "the value is not a finding; physics outside the library likely" in got.verdict


def test_the_check_is_skipped_on_request_and_without_a_record(
    true_term: tuple[list[bw.Recording], Diagnosis],
) -> None:
    recs, d = true_term
    off = bw.diagnose(recs, value_stability=False)
    assert vs.KEY not in off.settings
    assert off.status == d.status and off.named_terms == d.named_terms
    skipped = vs.checked(off, [recs[0], "not a record"])  # a mix of kinds: nothing to cut
    assert skipped.settings[vs.KEY]["checked"] is False
    assert skipped.status == off.status and skipped.verdict == off.verdict


def test_recording_variants_cut_the_steady_stretch() -> None:
    r = _recs()[0]
    p, s, n = r.samples_per_period, r.settle_periods, r.whole_periods - r.settle_periods
    cuts = vs.variant_items([r])
    early, late = cuts["early"][0], cuts["late"][0]
    assert early.y.size == (s + n - n // 3) * p and early.settle_periods == s
    assert late.y.size == r.y.size and late.settle_periods == s + n // 3

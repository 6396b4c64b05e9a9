"""A drifting output gain is not degradation, nor ageing, and a set that mostly drifts is not "adequate"
(review 36, problem 2: y times ``1 + d t / t_end`` in every record, the plain plant otherwise).

On main 164dc3a the reviewer's generator gave, by noise draw, "explained by: stiffness degradation",
"explained by: degradation delta_nu" with "the specimen had aged before the first recorded period (F-test
p = 3.8e-40)", or "adequate" on 2 of 6 recordings after 4 were left out. The records here are the
library's simulator's (a resonant G with a delay, not the reviewer's Tustin-discretised one), the gain drift
applied after it; the drift test's rival reading is checked on hand-made block deviations too.
"""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import drift as D
from bouc_wen_id.diagnosis import drift_majority, gain_drift
from bouc_wen_id.diagnosis.settling import LEFT_OUT

OMEGAS = (1.2, 2.8, 5.5)
PERIODS, SETTLE, P = 8, 10, 128


def _records(drift: float, seed: int) -> list[bw.Recording]:
    """Six sine experiments (three frequencies at two amplitudes) of a resonant plant with a delay, each
    record's output times ``1 + drift t / t_end`` (a sensor's gain warming up)."""
    plant = bw.WienerPlant(bw.TransferFunction([25.0], [1.0, 2.0, 25.0], 0.04), bw.BoucWen(1.0, 0.3, 1.5))
    out = []
    for k, amp in enumerate((1.2, 0.6)):
        plan = bw.SinePlan(
            list(OMEGAS),
            amp,
            settle_periods=SETTLE,
            periods=PERIODS,
            samples_per_period=P,
            noise_sd=0.01,
            seed=seed * 10 + k,
        )
        for r in bw.simulate(plant, plan):
            y = r.y * (1.0 + drift * r.t / r.t[-1])
            out.append(bw.Recording(r.t, r.u, y, r.amplitude, r.frequency, settle_periods=SETTLE))
    return out


@pytest.mark.parametrize(("drift", "seed"), [(-0.03, 2), (0.03, 1), (0.03, 2), (-0.03, 3)])
def test_a_drifting_gain_names_no_degradation_no_age_and_no_verdict_on_a_minority(
    drift: float, seed: int
) -> None:
    d = bw.diagnose(_records(drift, seed))
    assert not any(t in D.DRIFT_TERMS for t in d.named_terms), d.verdict
    assert "had aged" not in d.verdict, d.verdict
    left = d.settings.get(LEFT_OUT, [])
    if drift_majority.most(len(left), len(d.experiments) + len(left)):
        # the verdict would rest on a minority: the drift is the finding, said first
        assert d.status == "unexplained" and d.headline.startswith("the recordings drift"), d.verdict
        assert f"{len(left)} of {len(d.experiments) + len(left)}" in d.headline
    assert d.status != "explained" or not left, d.verdict


def _data(dev_of: str, rng: np.random.Generator) -> list[D.DriftData]:
    """Hand-made block records of three experiments (5 blocks, harmonics 0..3): the deviations a drifting
    gain gives (``g t_b`` times the loop) or a degradation gives (``d E t_b J``, J a shape of its own beside
    a part along the loop), plus unit noise (the weights are 1)."""
    out = []
    for i, (energy, level) in enumerate(((3.0, 4.0), (2.0, 3.0), (1.0, 1.5))):
        t = np.arange(5.0) - 2.0
        loop = np.array([0.0, level, 0.3 * level, 0.1 * level], dtype=np.complex128)
        jac = -0.5 * loop + np.array([0.0, 0.0, 1.5j, 0.8], dtype=np.complex128)  # a shape of its own
        if dev_of == "gain":
            mean = -0.8 * t[:, None] * loop[None, :]  # a falling gain: the loop shrinks, as it degrades
        else:
            mean = 0.4 * energy * t[:, None] * jac[None, :]
        noise = rng.standard_normal((5, 4)) + 1j * rng.standard_normal((5, 4))
        noise[:, 0] = noise[:, 0].real
        dev = mean + 0.05 * noise
        out.append(
            D.DriftData(
                i, dev, t, np.full(5, 400.0), energy, jac, np.zeros(8), math.nan, jac_eta=jac, level=loop
            )
        )
    return out


@pytest.mark.parametrize("seed", range(3))
def test_the_rival_takes_a_gain_drift_and_leaves_a_degradation_named(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for kind, alternative in (("gain", True), ("degradation", False)):
        data = _data(kind, rng)
        test = D.degradation_test(data, 1.0, 0.05, 10)
        assert test is not None and test.passed  # both drifts pass the term's own test
        got = gain_drift.checked(test, data, 0.05, 10)
        assert got is not None
        assert got.gain_alternative is alternative, (kind, got.gain_p_adjusted)
        assert got.named is (not alternative)
        if kind == "gain":  # the rate per period of each record's gain: -0.8 in these units
            assert got.gain_rates == pytest.approx((-0.8, -0.8, -0.8), rel=0.05)
            assert "a drifting gain, neither named" in gain_drift.text(got)


def test_a_drift_left_beyond_a_named_degradation_is_explained_in_part_not_explained() -> None:
    """Review 36: "explained by: degradation delta_nu = 0.0006698" beside, in the same verdict, "the loop
    still drifts ... (recording 0's fundamental by -0.14 % per period ..., t = -13.8; not explained by the
    named terms)": a status the verdict's own clause contradicts."""
    from bouc_wen_id.diagnosis import run
    from bouc_wen_id.diagnosis.locate import DriftFinding, Localisation
    from bouc_wen_id.diagnosis.result import ModelSummary, NamedTerm

    def loc(slope: float, t: float, p: float, detected: bool) -> Localisation:
        found = (DriftFinding("recording 0", 8, slope, t, 0.0, 0.0, p, 1.0),)
        return Localisation(0.0, 1, 0.5, (), (), (), math.nan, math.nan, found, detected)

    deg = NamedTerm(D.DEGRADATION, "delta_nu", 6.7e-4, 5.2e-5, "1/[y]^2")
    final = ModelSummary((deg,), 1.0, 0.3, 1.5, 250.0, 249, 0.5, (0.01,), ())
    before = loc(-0.0018, -17.0, 1e-12, True)
    status, named, _, verdict = run._judged(
        "explained", final, (before, loc(-0.0014, -13.8, 1e-10, True)), 1.0, []
    )
    assert status == "partly explained" and verdict.startswith("explained in part by: degradation"), verdict
    assert "still drifts" in verdict and named == (deg,)
    # no drift left beyond it: explained, as before
    status, _, _, verdict = run._judged("explained", final, (before, loc(-1e-5, -0.1, 0.9, False)), 1.0, [])
    assert status == "explained" and verdict.startswith("explained by: degradation"), verdict

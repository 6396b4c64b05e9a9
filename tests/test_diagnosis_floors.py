"""Noise floors of noise-free data: a simulator's own discretisation error and the output's quantisation
(review 31a items 6 and 8)."""

from __future__ import annotations

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.settling import _noise_floors

H = bw.BoucWen(beta=1.0, gamma=0.3, mu=1.5, alpha=1.0)
PLANTS = {
    "demo": bw.demo_plant(),
    "resonant with delay": bw.WienerPlant(bw.TransferFunction([72.0], [1.0, 1.8, 36.0], delay=0.04), H),
    "first order": bw.WienerPlant(bw.TransferFunction([1.5], [0.2, 1.0]), bw.BoucWen(2.0, 1.0, 1.2, 1.0)),
}


def _plan(p: int, substeps: int, noise_sd: float = 0.0) -> bw.SinePlan:
    return bw.SinePlan(
        frequencies=[1.0, 3.0, 8.0], amplitudes=0.6, settle_periods=30, periods=4, samples_per_period=p,
        substeps=substeps, noise_sd=noise_sd,
    )  # fmt: skip


@pytest.mark.parametrize("name", sorted(PLANTS))
@pytest.mark.parametrize("p", [64, 128])
def test_the_floor_of_noise_free_data_covers_the_simulators_own_error(name: str, p: int) -> None:
    plant = PLANTS[name]
    coarse = bw.simulate(plant, _plan(p, 1))  # one RK4 step per sample
    fine = bw.simulate(plant, _plan(p, 32))
    floors, notes = _noise_floors(coarse, prepare(coarse))
    for e, a, b in zip(floors, coarse, fine):
        err = float(np.mean((a.y[-p:] - b.y[-p:]) ** 2))  # the steady period's discretisation error
        assert e.noise_var >= err
    assert notes


def test_noise_free_data_of_the_librarys_own_model_at_128_samples_fit_at_the_floor() -> None:
    recs = bw.simulate(bw.demo_plant(), bw.demo_plan(samples_per_period=128, periods=12, noise_sd=0.0))
    d = bw.diagnose(recs)
    assert d.verdict.startswith("adequate"), d.verdict


def test_a_quantised_noise_free_output_gets_the_quantisation_floor() -> None:
    q = 0.02
    recs = [
        bw.Recording(r.t, r.u, np.round(r.y / q) * q, amplitude=r.amplitude, frequency=r.frequency,
                     settle_periods=r.settle_periods)
        for r in bw.simulate(PLANTS["first order"], _plan(128, 4))
    ]  # fmt: skip
    exps, notes = _noise_floors(recs, prepare(recs))
    assert all(e.noise_var >= 0.99 * e.periods * q * q / 12.0 for e in exps)  # q as found: to rounding
    assert any("quantisation step" in n for n in notes)
    assert bw.diagnose(recs).verdict

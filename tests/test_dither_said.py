"""A quantiser dithered in part by the noise before it (sd q/4) is no structure (review 44 failure 4).

The records are the library's noise-free simulation passed through a converter made here: Gaussian noise of
sd q/4 added, then ``q round(. / q)``. Part of the rounding error then repeats every period; before session
45 the plain model's adequacy read it as "unexplained structure" (p 1e-60 on review 44's config C). The
diagnosis now takes it into the noise floor and says so, and a dashpot of 10 averaged-noise sd beside the
hysteresis is still named.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.terms import Viscous

Q = 0.02
SD = 0.25 * Q
PERIODS = 20


def _plan() -> bw.SinePlan:
    return bw.demo_plan(samples_per_period=200, periods=PERIODS, noise_sd=0.0)


def _converted(plant: bw.WienerPlant, seed: int) -> list[Any]:
    rng = np.random.default_rng([45, seed])
    return [
        bw.Recording(r.t, r.u, Q * np.round((r.y + rng.normal(0.0, SD, r.y.size)) / Q), amplitude=r.amplitude,
                     frequency=r.frequency, settle_periods=r.settle_periods)
        for r in bw.simulate(plant, _plan())
    ]  # fmt: skip


def _diagnosed(recs: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_null_quantised_under_a_quarter_step_of_noise_is_adequate_and_said(seed: int) -> None:
    d = _diagnosed(_converted(bw.demo_plant(), seed))
    assert d.status == "adequate", d.headline
    said = [n for n in d.notes if "repeats every period" in n]
    assert said and f"q = {Q:.3g}" in said[0], d.notes


def test_a_dashpot_of_ten_averaged_noise_sd_is_still_named() -> None:
    base = bw.simulate(bw.demo_plant(), _plan())
    unit = bw.WienerPlant(bw.demo_plant().linear, bw.demo_plant().hysteresis, terms=(Viscous(1e-3),))
    diff = np.concatenate(
        [(a.y - b.y)[a.settle_periods * 200 :] for a, b in zip(bw.simulate(unit, _plan()), base)]
    )
    averaged_sd = math.sqrt(SD**2 + Q**2 / 12.0) / math.sqrt(PERIODS)
    c = 1e-3 * 10.0 * averaged_sd / float(np.sqrt(np.mean(diff**2)))  # the dashpot that makes 10 averaged sd
    plant = bw.WienerPlant(bw.demo_plant().linear, bw.demo_plant().hysteresis, terms=(Viscous(c),))
    d = _diagnosed(_converted(plant, 3))
    assert "viscous" in [n.term for n in d.named], d.headline

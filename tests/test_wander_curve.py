"""A smooth wander of the zero is taken out as a curve, not as steps: the noise floor and the power stay
those of the same noise without the wander (session 47, wander47).

``dc_wander`` takes a smooth wander out; taken out period by period, its period means' differences (its slope)
were read as a random walk's steps and their leak put on the harmonics (``baseline.step_variance``): the noise
floor came out 1.1-3.3 times the true one on review 45's design C, and the detection limits widened.
``wander_curve`` fits a low-order polynomial in time through the period means, takes it out sample by sample
(its ramp within each period too) and leaves no walk level.

Data: tests/wiener_sim.py (RK4, not the library's simulator) with viscous damping on u, and
test_dc_wander.py's wander (two sines of 0.2-0.6 cycle over each record, random phases), here of 3 noise
sd; the same recordings without the wander are the reference.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from test_dc_wander import _changed
from wiener_sim import recordings

#: Viscous damping on u: about twice its detection limit on these data without the wander.
C = 6e-5
#: How far the wander's noise floor, standard error and limit may sit from the same noise's without it.
FACTOR = 1.15


def _diagnosed(seed: int, wander: bool) -> Any:
    recs = recordings(seed, [0.0] * 4, c=C)
    if wander:
        rng = np.random.default_rng([seed, 4646])
        recs = [replace(r, y=_changed(np.asarray(r.y, dtype=np.float64), "wander", 3.0, rng)) for r in recs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs, candidates=["offset", "viscous", "asymmetry"])


def _viscous(d: Any) -> Any:
    return next(t for t in d.named if t.term == "viscous")


def test_a_smooth_wander_leaves_the_noise_floor_and_the_power_as_without_it() -> None:
    """Before: the noise floor 1.9-2.3 times the reference's, the viscous term's standard error and detection
    limit 1.4 times."""
    got, ref = _diagnosed(6, True), _diagnosed(6, False)
    assert any("smooth curve through the period means" in n for n in got.notes), got.notes
    for a, b in zip(got.experiments, ref.experiments, strict=True):
        assert 1.0 / FACTOR < a.noise_var / b.noise_var < FACTOR, (a.noise_var, b.noise_var)
    v, r = _viscous(got), _viscous(ref)
    assert abs(v.value - C) < 3.0 * v.standard_error, (v.value, v.standard_error)
    assert v.standard_error < FACTOR * r.standard_error, (v.standard_error, r.standard_error)
    lim = next(x for x in got.limits if x.term == "viscous")
    lim_ref = next(x for x in ref.limits if x.term == "viscous")
    assert lim.limit < FACTOR * lim_ref.limit, (lim.limit, lim_ref.limit)


def test_a_random_walk_zero_keeps_its_steps_and_a_smooth_wander_gets_its_curve() -> None:
    """The curve is taken only where the period means sit on it within the noise: a random walk's means
    (test_diagnosis_baseline's, 16 periods) do not, and keep the walk's steps and leak."""
    from bouc_wen_id.diagnosis import wander_curve
    from test_diagnosis_baseline import _recs

    for seed in range(3):
        assert all(wander_curve.degree(r) is None for r in _recs("walk", seed)), seed
        rng = np.random.default_rng([seed, 4646])
        smooth = [
            replace(r, y=_changed(np.asarray(r.y, dtype=np.float64), "wander", 3.0, rng))
            for r in recordings(seed, [0.0] * 4)
        ]
        assert all(wander_curve.degree(r) is not None for r in smooth), seed

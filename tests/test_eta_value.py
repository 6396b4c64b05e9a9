"""Stiffness degradation's named value and its standard error (review 44 failure 2, session 45).

The records come from a few-line RK4 (tests/degradation_sim.py: the Baber-Noori element ``w' = [x' -
(beta |x'| |w|^(mu-1) w + gamma x' |w|^mu)] / (1 + delta_eta e)``, ``e' = w x'``, on ``x = U cos(omega t)``
from rest), not from the library's simulator. Before session 45 the value was refined on a steady cost that
was circular (its minimum at the first-order d, its curvature 10 times too sharp) after two unconverged
correction passes: on this design (eta about 3 at the record's end) it came out 9 % and 7 % low at z -17
and -12.5, the second with a steady term named beside it ("partly explained"); now z -1.0 and 0.1 (seeds
3, 4: -0.5, 0.6).
"""

from __future__ import annotations

import math

import pytest
from degradation_sim import named_z

ETA = "stiffness_degradation"


@pytest.mark.parametrize("seed", [1, 2])
def test_stiffness_degradation_value_within_its_standard_error(seed: int) -> None:
    truth = 0.01
    d, z = named_z(0.01, seed, ETA, truth, delta_eta=truth)
    assert math.isfinite(z), d.summary()
    # A Gaussian z: |z| > 3.5 once in 2000 draws.
    assert abs(z) < 3.5, (z, d.summary())
    # The periods brought back to the virgin stiffness leave nothing for a steady term.
    assert d.status == "explained", d.summary()

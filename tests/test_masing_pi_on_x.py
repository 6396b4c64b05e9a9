"""A Prandtl-Ishlinskii loop on x named as a spring on x must carry the Masing caveat (diagnosis/masing.py).

Review 43's d6pir: ten plays on x with thresholds spread over the stroke and weights falling with the
threshold, through a resonant G with a delay, AR(1) noise. The final model with a spring on x passes its
adequacy test (the Bouc-Wen branch absorbs the stops), so no residual test can see the loop; the caveat's
power test decides. Its reference loops had stops of uniform density only, and on this design the weakest
left a noncentrality just above its threshold (17.3 over 12.4): the design was said to separate a spring from
such a loop, the clause left out, and the verdict read "explained by: parallel stiffness across the
hysteretic element (on x)" alone. A loop of mostly narrow stops (the density falling with the width, as
here) is absorbed further (noncentrality 8.9). The records are made here: on_x_sim.py's RK4 and play
operators (not the library's simulator), AR(1) noise from a seeded generator.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis.masing import MASING_MARK
from on_x_sim import Lin, play_sum, simulate
from wiener_sim import ar1

P, SETTLE, PERIODS = 128, 8, 16
G = Lin(2, 10.0, zeta=0.2, delay=0.005)  # resonant at 10 Hz, damping ratio 0.2, 5 ms delay
FREQS = np.repeat([6.0, 8.0, 10.0, 12.0, 14.0], 2)
AMPS = np.tile([0.5, 1.0], 5)  # latent strokes 0.4-2.2 of saturation
THRESHOLDS = (np.arange(10) + 0.5) / 10 * 1.5  # spread over the stroke
WEIGHTS = np.exp(-np.arange(10) / 3.0)  # falling with the threshold


def _records(seed: int, pi: float = 0.0, spring: float = 0.0) -> list[bw.Recording]:
    """Ten records: Bouc-Wen plus a PI loop on x of total weight ``pi`` and a spring ``spring`` on x, noise
    1 % of each output's RMS, AR(1) with coefficient 0.5."""
    r = simulate(G, FREQS, AMPS, P, SETTLE, PERIODS)
    y = r.w + spring * r.x + play_sum(r.x, THRESHOLDS, pi * WEIGHTS / WEIGHTS.sum())
    rng = np.random.default_rng(seed)
    out = []
    for i in range(FREQS.size):
        sd = 0.01 * float(np.sqrt(np.mean(y[i] ** 2)))
        t = np.arange(y[i].size) * r.h[i]
        noisy = y[i] + ar1(rng, y[i].size, sd, 0.5)
        out.append(bw.Recording(t, r.u[i], noisy, float(AMPS[i]), 2 * math.pi * float(FREQS[i]), SETTLE))
    return out


def test_a_pi_loop_of_mostly_narrow_stops_is_not_a_confident_spring(helpers: Any) -> None:
    """main: "explained by: parallel stiffness across the hysteretic element (on x) k = 0.03215 ± 0.00146",
    nothing more."""
    d = helpers.diagnose_quietly(_records(2, pi=0.03))
    if "stiffness@x" in {n.term for n in d.named}:
        assert MASING_MARK in d.verdict and "too weak to separate" in d.verdict, d.verdict
        assert "most of them narrow" in d.verdict, d.verdict
    else:
        assert d.status == "unexplained", d.verdict


def test_a_spring_on_x_on_the_same_design_is_still_named(helpers: Any) -> None:
    d = helpers.diagnose_quietly(_records(3, spring=0.03))
    assert [n.term for n in d.named] == ["stiffness@x"], d.verdict

"""Tied candidates at two places: the one at the named terms' place goes first (diagnosis/place_tie.py).

Review 43's d2f: a Kelvin element on x (a spring and a dashpot across the hysteresis) through a first-order
G with a delay, AR(1) noise. Through a first-order G a spring on u is a spring on x plus a dashpot on x, so
once the spring on x is named, a spring on u and the dashpot on x tie; main took the lower cost and named a
spring at two places (stiffness on x with stiffness on u, the dashpot only as the alternative). The records
are made here: on_x_sim.py's RK4 (not the library's simulator), AR(1) noise from a seeded generator.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis.place_tie import named_place_first
from on_x_sim import Lin, simulate
from wiener_sim import ar1

P, SETTLE, PERIODS = 128, 8, 16
G = Lin(1, 3.0, delay=0.003)  # corner 3 Hz, 3 ms delay
FREQS = np.repeat(np.array([0.5, 0.75, 1.0, 1.5, 2.0]) * G.f, 2)  # around the corner
AMPS = np.tile([1.5, 3.0], 5)  # both past saturation at every frequency
K, C = 0.03, 0.0002  # review 43's Kelvin element: y = w + K x + C xdot


def _records(k: float, c: float, seed: int, phi: float) -> list[bw.Recording]:
    """Ten records of the Kelvin device, noise 1 % of each output's RMS, AR(1) with coefficient ``phi``."""
    r = simulate(G, FREQS, AMPS, P, SETTLE, PERIODS)
    y = r.w + k * r.x + c * r.v
    rng = np.random.default_rng(seed)
    out = []
    for i in range(FREQS.size):
        sd = 0.01 * float(np.sqrt(np.mean(y[i] ** 2)))
        t = np.arange(y[i].size) * r.h[i]
        noisy = y[i] + ar1(rng, y[i].size, sd, phi)
        out.append(bw.Recording(t, r.u[i], noisy, float(AMPS[i]), 2 * math.pi * float(FREQS[i]), SETTLE))
    return out


def test_a_kelvin_element_on_x_under_ar1_noise_is_named_at_one_place(helpers: Any) -> None:
    """main: "parallel stiffness across the hysteretic element (on x) k = 0.02606, parallel stiffness on the
    measured input u k = 0.004523 - or viscous damping across the hysteretic element (on x) instead of
    parallel stiffness on the measured input u" (the step's improvements 59.14 and 58.89)."""
    d = helpers.diagnose_quietly(_records(K, C, 1, 0.5))
    named = {n.term: n for n in d.named}
    assert set(named) == {"stiffness@x", "viscous@x"}, d.verdict
    for term, truth in (("stiffness@x", K), ("viscous@x", C)):
        n = named[term]
        assert abs(n.value - truth) < 3.0 * n.standard_error, (term, n.value, n.standard_error)
    # the tied reading stays said, with the experiment that would separate them
    alt = [a for a in d.alternatives if {a.term, a.rival} == {"viscous@x", "stiffness"}]
    assert alt and alt[0].separating_experiment, d.alternatives


def test_the_plain_device_under_ar1_noise_names_nothing(helpers: Any) -> None:
    d = helpers.diagnose_quietly(_records(0.0, 0.0, 2, 0.5))
    assert not d.named, d.verdict


def _t(term: str, improvement: float) -> SimpleNamespace:
    return SimpleNamespace(term=term, improvement=improvement)


def _tied(a: Any, b: Any) -> bool:
    return bool(a.improvement - b.improvement < 1.0)


def test_the_tied_candidate_at_the_named_place_goes_first() -> None:
    order = [_t("stiffness", 59.1), _t("viscous", 59.0), _t("viscous@x", 58.9)]
    assert [t.term for t in named_place_first(order, ["stiffness@x"], _tied)] == [
        "viscous@x",
        "stiffness",
        "viscous",
    ]


def test_untied_or_unplaced_orders_stay() -> None:
    order = [_t("stiffness", 70.0), _t("viscous@x", 58.9)]
    assert named_place_first(order, ["stiffness@x"], _tied) == order  # the data prefer the other place
    tied = [_t("stiffness", 59.1), _t("viscous@x", 58.9)]
    assert named_place_first(tied, [], _tied) == tied  # nothing named: no place to prefer
    assert named_place_first(tied, ["stiffness@x", "viscous"], _tied) == tied  # named at both places
    assert named_place_first(tied, ["offset"], _tied) == tied  # an output term has no mechanical place
    same = [_t("viscous@x", 59.1), _t("stiffness", 58.9)]
    assert named_place_first(same, ["stiffness@x"], _tied) == same  # the best already acts there

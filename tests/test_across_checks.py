"""diagnose_across runs diagnose's post-verdict checks (session 45): the free ring-down of G
(ring_down.py, across_ring.py) and the tie between two places (place_tie.py).

The ringing levels are review 44's design D at two drive levels: no term beyond the plain Wiener-Bouc-Wen
model, G = wn^2 / (s^2 + 2 zeta wn s + wn^2) with zeta 0.05 at 6 rad/s started from rest, 10 settle periods
and 4 averaged ones, AR(1) noise; made here (G's two states and the Bouc-Wen state by wiener_sim's RK4, a
pure delay on the drive), not by the library's simulator. Main named physics on them across the levels (a
loop that has not settled) where diagnose says "not settled". The Kelvin levels are test_place_tie.py's
records (on_x_sim.py's RK4) at two levels of the element: main named a spring at two places.
"""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from wiener_sim import ar1, hysteretic_states

P = 128
BETA, GAMMA, MU = 1.2, 0.3, 1.5
OMEGAS = np.array([2.0, 4.0, 7.0, 11.0] * 2)
AMPS = np.array([0.95] * 4 + [1.9] * 4)


def levels(
    wn: float, zeta: float, delay: float, settle: int, periods: int, phi: float, seed: int, scales: Any
) -> list[list[Any]]:
    """Per drive level in ``scales``: eight recordings of the plain plant (G resonant at ``wn``, damping
    ``zeta``, behind ``delay`` s, from rest), AR(1) noise of sd 0.01 and coefficient ``phi`` from ``seed``."""
    import bouc_wen_id as bw

    rng = np.random.default_rng(seed)
    h = 2 * math.pi / OMEGAS / P
    out = []
    for scale in scales:
        amps = scale * AMPS

        def rate(t: Any, s: Any, amps: Any = amps) -> Any:
            x, v, w = s
            pw = np.abs(w) ** MU
            dw = v - (BETA * np.abs(v) * pw * np.sign(w) + GAMMA * v * pw)
            drive = np.where(t >= delay, amps * np.cos(OMEGAS * (t - delay)), 0.0)
            return np.array([v, wn**2 * (drive - x) - 2 * zeta * wn * v, dw])

        w = hysteretic_states(rate, h, (settle + periods) * P).T
        recs = []
        for i, om in enumerate(OMEGAS):
            t = np.arange(w[i].size) * h[i]
            y = w[i] + ar1(rng, t.size, 0.01, phi)
            recs.append(bw.Recording(t, amps[i] * np.cos(om * t), y, float(amps[i]), float(om), settle))
        out.append(recs)
    return out


def across_quietly(groups: Any, condition: Any) -> Any:
    import bouc_wen_id as bw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, condition)


def test_ringing_levels_name_nothing_across() -> None:
    """main: terms named across the levels from the ring-down; diagnose of either level: "not settled"."""
    a = across_quietly(levels(6.0, 0.05, 0.003, 10, 4, 0.9, 13, [1.0, 1.5]), [1.0, 1.5])
    said = f"{a.status}: {a.verdict}"
    assert not a.named and not a.partial, said
    assert a.status != "explained", said
    assert "not settled" in a.verdict and "more settle periods" in a.verdict, said
    assert any("ring" in n for n in a.notes), a.notes


def test_a_minority_that_rings_is_left_out_across(monkeypatch: pytest.MonkeyPatch) -> None:
    """A recording that rings is left out of its condition's fit (across_settling.drop), as diagnose leaves
    it out; one that does not stays."""
    from bouc_wen_id.diagnosis import across_settling

    monkeypatch.setattr(across_settling, "settled_only", lambda e, named: (list(range(len(e))), []))
    exps: Any = [SimpleNamespace(source=s) for s in ("a", "b", "c")]
    kept, names, why, _ = across_settling.drop(exps, "1", lambda: None, frozenset({"b"}))
    assert [e.source for e in kept] == ["a", "c"] and names == ("b",) and why == ""


def test_kelvin_levels_tie_goes_to_x_across() -> None:
    """main (seed 2): "stiffness on x" with "stiffness on u", a spring at two places (test_place_tie.py's
    d2f, here at two levels of the element); the dashpot on x ties with the spring on u."""
    from test_place_tie import C, K, _records

    a = across_quietly([_records(K, C, 2, 0.5), _records(1.5 * K, 1.5 * C, 102, 0.5)], [1.0, 1.5])
    assert set(a.named) == {"stiffness@x", "viscous@x"}, a.verdict


def test_a_lab_segment_that_rings_is_found() -> None:
    """A Measurement (100.37 samples a period, no settle periods) whose steady segment still holds a free
    oscillation at 0.55 of the drive's frequency falling 0.85 a period: ring_down.rings finds it (main: a
    Measurement was never checked); the same loop without it rings not."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import ring_down

    om = 2 * math.pi
    t = np.arange(int(30 * 100.37)) / 100.37
    rng = np.random.default_rng(1)
    loop = np.cos(om * t) + 0.2 * np.cos(3 * om * t) + rng.normal(0.0, 0.001, t.size)
    for ring, rings in ((0.05 * 0.85**t * np.cos(0.55 * om * t), True), (0.0 * t, False)):
        m = bw.Measurement(t, np.sin(om * t), loop + ring, nominal_frequency=om, name="m")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found, notes = ring_down.rings([m])
        assert bool(found) == rings, (found, notes)
        if rings:
            assert 0.75 < found[0].rate < 0.95 and "steady segment" in notes[0], (found, notes)

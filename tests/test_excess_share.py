"""One convention for a term's share where the fit's cost shows no excess (review 43: under AR(1) noise a
negative-damping device had every candidate read share 1, so the material-share gate gated nothing).
excess_share.py.

Data made here: tests/wiener_sim.py's RK4 (a resonant G with a delay, Bouc-Wen), viscous damping on u of
either sign and AR(1) output noise of phi = 0.8 from a seeded generator: the fits weigh every harmonic with
the noise's largest level, so the cost sits below its dof while the adequacy test (each harmonic at its own
level) fails.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import pytest
import wiener_sim
from bouc_wen_id.diagnosis import excess_share
from bouc_wen_id.diagnosis.select import MATERIAL_SHARE


def test_the_share_reads_the_adequacy_statistic_where_the_cost_shows_no_excess() -> None:
    # the cost's excess, as before
    assert excess_share.share(150.0, 110.0, 100.0) == pytest.approx(0.8)
    # no excess in the cost: the statistic's (300 over 100 dof; the term takes it to 140, or to 290)
    assert excess_share.share(80.0, 60.0, 100.0, (300.0, 140.0)) == pytest.approx(0.8)
    assert excess_share.share(80.0, 60.0, 100.0, (300.0, 290.0)) == pytest.approx(0.05)
    # nothing to explain in either, or no statistic: 0; the targeted step: 1
    assert excess_share.share(80.0, 60.0, 100.0, (90.0, 70.0)) == 0.0
    assert excess_share.share(80.0, 60.0, 100.0) == 0.0
    assert excess_share.share(80.0, 60.0, 100.0, targeted=True) == 1.0
    # a floor (pairs.py: a partner refused alone)
    assert excess_share.share(100.0, 90.0, 100.0, floor=20.0) == pytest.approx(0.5)


def _first_step(c: float) -> Any:
    d = bw.diagnose(wiener_sim.recordings(1, [0.0] * 4, c=c, phi=0.8))
    st = d.steps[0]
    assert not st.targeted and st.before_cost < st.before_dof  # no excess in the cost, the test failing
    return d, st


@pytest.mark.parametrize("c", [4e-4, -4e-4])
def test_a_term_that_lowers_the_cost_by_a_noise_level_amount_does_not_pass_on_share_one(c: float) -> None:
    d, st = _first_step(c)
    by = {t.term: t for t in st.trials if math.isfinite(t.share)}
    truth = by["viscous"]
    assert truth.share > 0.9  # it fixes what the adequacy test sees
    small = [t for t in by.values() if 0 < t.improvement < 0.1 * truth.improvement]
    assert small  # main passed some of these (series dashpot at +c, inertia and sensor lag at -c), share 1
    for t in small:
        assert t.share < MATERIAL_SHARE and not t.passed, (t.term, t.share, t.improvement)
    assert not all(t.share == 1.0 for t in by.values())
    if c > 0:  # the term that fixes the adequacy statistic is still named
        assert [n.term for n in d.named] == ["viscous"], d.verdict

"""What would bring a detection limit down (diagnosis/design_hint.py), checked by independent projections.

The hint's single-experiment factor is solved on the per-experiment 4 x 4 sums; here the whole stacked
problem is projected again (diagnosis/limits.py ``_Profile``) with that experiment's weight raised, and the
non-centrality must grow by the stated ratio t90 / t50; the uniform factor must do the same with every weight
raised (and a refit of the plain model too, since a common weight leaves the refit unchanged).
"""

from __future__ import annotations

from dataclasses import replace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.augmented import AugExperiment, AugFit
from bouc_wen_id.diagnosis.design_hint import design_hint
from bouc_wen_id.diagnosis.limits import _Profile
from bouc_wen_id.planning._power import aug_params

PRIOR = bw.demo_plant()
NOISE = 0.01
DESIGN = ((3.0, 1.5, 20), (5.0, 1.0, 20), (8.0, 1.5, 40))  # omega, U, periods
T50, T90 = 9.0, 17.5


def _profile(weights: list[float]) -> _Profile:
    par = aug_params(PRIOR, [w for w, _, _ in DESIGN])
    exps = [AugExperiment(np.zeros(48), u, w, 0.0, k) for (w, u, _), k in zip(DESIGN, weights)]
    return _Profile(exps, AugFit(par, 0.0, 0, True, np.zeros((1, 1)), np.zeros((1, 1))), 8)


@pytest.mark.parametrize("term", ["sensor_lag", "viscous@x"])
def test_the_single_experiment_factor_reaches_the_stated_ratio(term: str) -> None:
    weights = [n / NOISE**2 for _, _, n in DESIGN]
    prof = _profile(weights)
    v = 2e-3 if term == "sensor_lag" else 0.01
    seconds = [n * 2 * np.pi / w for w, _, n in DESIGN]
    hint = design_hint(prof, term, v, T50, T90, seconds)
    assert hint.periods_factor == pytest.approx(T90 / T50)
    assert 0 <= hint.experiment < len(DESIGN) and hint.experiment_factor > 1.0
    lam0 = prof(term, v)[0]
    raised = list(weights)
    raised[hint.experiment] *= hint.experiment_factor
    assert _profile(raised)(term, v)[0] / lam0 == pytest.approx(T90 / T50, rel=0.01)
    everywhere = [k * hint.periods_factor for k in weights]
    assert _profile(everywhere)(term, v)[0] / lam0 == pytest.approx(T90 / T50, rel=1e-6)
    # The cheapest: no other single experiment reaches the ratio in less measured time.
    cost = (hint.experiment_factor - 1) * seconds[hint.experiment]
    for j in range(len(DESIGN)):
        more = list(weights)
        more[j] *= 1 + cost / seconds[j] * 0.97
        if j != hint.experiment:
            assert _profile(more)(term, v)[0] / lam0 < T90 / T50


def test_a_common_weight_scales_the_refitted_non_centrality() -> None:
    weights = [n / NOISE**2 for _, _, n in DESIGN]
    prof, prof2 = _profile(weights), _profile([3.0 * k for k in weights])
    assert prof2.exact("sensor_lag", 2e-3) == pytest.approx(3.0 * prof.exact("sensor_lag", 2e-3), rel=1e-3)


def test_nothing_the_user_gave_is_modified() -> None:
    prof = _profile([n / NOISE**2 for _, _, n in DESIGN])
    before = [replace(e) for e in prof.exps]
    design_hint(prof, "sensor_lag", 2e-3, T50, T90)
    assert [e.weight for e in prof.exps] == [e.weight for e in before]

"""simulate_input (any sampled input) against simulate (exact sine), and the errors' attributes."""

from __future__ import annotations

import math
import pickle

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference


@pytest.mark.parametrize("p", [256, 1024])
def test_simulate_input_matches_the_exact_sine(p: int) -> None:
    plant = bw.demo_plant()
    plan = bw.SinePlan(frequencies=[3.0], amplitudes=[1.0], settle_periods=2, periods=3, samples_per_period=p)
    (rec,) = bw.simulate(plant, plan)
    assert rec.x is not None and rec.w is not None
    x, w = bw.simulate_input(plant, rec.t, rec.u, substeps=plan.substeps)
    # The sampled input is interpolated by Catmull-Rom cubics: an O((omega dt)^3) error on u, within
    # (omega dt)^3 / 8 of its amplitude (and the linear part does not amplify it beyond max|x| / U).
    bound = (2 * math.pi / p) ** 3 / 8 * float(np.max(np.abs(rec.x)))
    assert np.max(np.abs(x - rec.x)) < bound
    assert np.max(np.abs(w - rec.w)) < bound
    assert np.max(np.abs(x - rec.x)) > 0  # a different path, not the same call


def test_simulate_input_validates() -> None:
    plant = bw.demo_plant()
    with pytest.raises(bw.InvalidParameterError, match="equal lengths"):
        bw.simulate_input(plant, np.arange(5.0), np.zeros(4))
    with pytest.raises(bw.InvalidParameterError, match="constant step"):
        bw.simulate_input(plant, np.array([0.0, 1.0, 3.0]), np.zeros(3))
    t = np.arange(10.0)
    u = np.zeros(10)
    u[3] = np.nan
    with pytest.raises(bw.NonFiniteError):
        bw.simulate_input(plant, t, u)


def test_search_at_bound_error_is_constructed_with_its_bracket_end() -> None:
    err = bw.SearchAtBoundError("at the end", bound=1.0, lower=True)
    assert (str(err), err.bound, err.lower) == ("at the end", 1.0, True)
    assert bw.SearchAtBoundError("no end known").bound is None
    back = pickle.loads(pickle.dumps(err))
    assert (str(back), back.bound, back.lower) == ("at the end", 1.0, True)
    with pytest.raises(bw.SearchAtBoundError) as info:
        reference.golden_section(lambda v: v, 1.0, 3.0, 1e-6)
    assert info.value.lower is True and info.value.bound == 1.0


def test_search_at_bound_from_rust_names_the_bracket_end() -> None:
    with pytest.raises(bw.SearchAtBoundError) as info:
        _core.golden_section(lambda v: v, 1.0, 3.0, 1e-6)
    assert info.value.lower is True and info.value.bound == 1.0
    with pytest.raises(bw.SearchAtBoundError) as info:
        _core.golden_section(lambda v: -v, 1.0, 3.0, 1e-6)
    assert info.value.lower is False and info.value.bound == 3.0

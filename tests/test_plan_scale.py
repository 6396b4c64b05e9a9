"""``check_scale`` judges a planned term against the plant where it would be measured, and only refuses what
is really out of scale.

- The prior's own errors pass through as they are: a prior with mu = 1 is told so, not that "the model output
  overflows" (every error of the plain model used to be turned into an infinite ratio).
- The comparison runs at the planner's resolution: at a large stroke (U = 200 on 1/(0.2 s + 1)) the coarse
  64-sample, 4-substep solve failed and plans main had made were refused as an overflow.
- A term is refused only where it dwarfs the plant's output at *every* frequency of the band: a spring that is
  about twice the plant's output at 0.1-1 rad/s is a plannable term, although G has rolled off at 100 rad/s.
- The words fit every kind of term (an offset is compared by its change of the output, as any term).
"""

from __future__ import annotations

from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.model import BoucWen, TransferFunction, WienerPlant
from bouc_wen_id.planning import OversizedTermError
from bouc_wen_id.planning._power import MAX_TERM_RATIO, check_scale

#: A stiff first-order plant driven at a large stroke (the reviewer's plan, which main planned before).
STROKE = WienerPlant(TransferFunction([1.0], [0.2, 1.0]), BoucWen(beta=0.5, gamma=0.5, mu=2.0, alpha=1.0))
FIRST = WienerPlant(TransferFunction([1.0], [1.0, 1.0]), BoucWen(beta=0.5, gamma=0.5, mu=1.5, alpha=1.0))


@pytest.mark.parametrize("term, size", [("sensor_lag", 1e-3), ("stiffness@x", 1e-3), ("stiffness@x", 0.5)])
def test_a_large_stroke_is_not_taken_for_an_overflow(term: str, size: float) -> None:
    ratio = check_scale(STROKE, term, size, (1.0, 10.0), 200.0)
    assert 0.0 < ratio <= MAX_TERM_RATIO


def test_the_plan_at_a_large_stroke_is_made() -> None:
    plan = bw.plan_detection(
        STROKE, 300.0, {"sensor_lag": 1e-3}, band=(1.0, 10.0), max_amplitude=200.0, noise_sd=0.05,
        sample_rate=100.0, settle_periods=10, n_frequencies=4, n_amplitudes=1, max_samples_per_period=64,
    )  # fmt: skip
    assert plan.experiments and plan.predicted.power > 0.0


def test_the_priors_own_error_is_said_as_such() -> None:
    prior = WienerPlant(TransferFunction([1.0], [1.0, 1.0]), BoucWen(beta=0.5, gamma=0.5, mu=1.0, alpha=1.0))
    lab: dict[str, Any] = dict(band=(1.0, 10.0), max_amplitude=1.0, noise_sd=0.05, sample_rate=100.0)
    with pytest.raises(InvalidParameterError, match="mu = 1 must be > 1") as err:
        bw.plan_detection(prior, 300.0, {"sensor_lag": 0.01}, settle_periods=10, **lab)
    assert not isinstance(err.value, OversizedTermError)


def test_a_term_is_judged_where_the_plant_is_measured() -> None:
    # at 100 rad/s G has rolled off and the spring is 125x the plant's swing; at 0.1-1 rad/s it is ~2x
    ratio = check_scale(FIRST, "stiffness", 2.5, (0.1, 100.0), 1.0)
    assert ratio < 5.0
    # where it dwarfs the plant at every frequency of the band (above G's corner), it is refused
    with pytest.raises(OversizedTermError, match="at every frequency"):
        check_scale(FIRST, "stiffness", 10.0, (30.0, 100.0), 1.0)


def test_an_offset_is_refused_in_words_that_fit_an_offset() -> None:
    with pytest.raises(OversizedTermError, match="change the output by more than") as err:
        check_scale(bw.demo_plant(), "offset", 500.0, (1.0, 10.0), 1.0)
    assert "hysteretic" not in str(err.value) and "every frequency of the band" in str(err.value)

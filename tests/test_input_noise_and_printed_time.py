"""Review 34: an input carrying noise was refused as "check the stated frequency", and a uniform time column
printed with 9 significant digits was refused as "not uniformly sampled"."""

from __future__ import annotations

from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.validation import EXACT_GRID_RTOL, check_time_axis, printed_quantum


def _recordings(u_noise: float, omega_factor: float = 1.0) -> list[bw.Recording]:
    plan = bw.SinePlan([2.0, 3.0, 5.0], [0.5, 0.5, 0.5], settle_periods=1, periods=6, seed=5)
    rng = np.random.default_rng(11)
    out = []
    for r in bw.simulate(bw.demo_plant(), plan):
        u = r.u + u_noise * float(np.std(r.u)) * rng.standard_normal(r.u.size)
        out.append(bw.Recording(r.t, u, r.y, r.amplitude, omega_factor * r.frequency, r.settle_periods))
    return out


@pytest.mark.parametrize("fit", [bw.diagnose, bw.identify])
def test_noise_on_the_input_is_named_as_noise(fit: object) -> None:
    with pytest.raises(bw.NoisyInputError, match="carries noise") as info:
        fit(_recordings(u_noise=0.12))  # type: ignore[operator]
    assert "check the stated frequency" not in str(info.value)
    assert isinstance(info.value, bw.FrequencyMismatchError)  # code catching the old class still catches it


def test_a_wrong_frequency_is_still_a_frequency_mismatch() -> None:
    recs = _recordings(u_noise=0.0)
    r = recs[0]
    # Period 2 pi / (2 omega) on a grid of whole samples: the input does not repeat at the stated omega.
    recs[0] = bw.Recording(r.t, r.u, r.y, r.amplitude, 2.0 * r.frequency, r.settle_periods)
    with pytest.raises(bw.FrequencyMismatchError, match="check the stated frequency") as info:
        bw.diagnose(recs)
    assert not isinstance(info.value, bw.NoisyInputError)


def test_times_printed_with_nine_digits_are_a_uniform_grid(tmp_path: Path) -> None:
    dt = 0.0490873852123405
    t = np.arange(3000, dtype=np.float64) * dt
    printed = np.array([float(f"{v:.9g}") for v in t], dtype=np.float64)
    assert np.ptp(np.diff(printed)) > 1e-5 * dt  # the printing itself makes the steps uneven
    assert printed_quantum(printed) == pytest.approx(1e-6)
    assert check_time_axis(printed, rtol=EXACT_GRID_RTOL) == pytest.approx(dt, rel=1e-6)  # a Recording's
    assert printed_quantum(t) == np.inf  # full doubles: nothing to forgive


def test_jitter_beyond_the_printing_is_still_refused() -> None:
    dt = 0.0490873852123405
    t = np.arange(3000, dtype=np.float64) * dt
    t[1500] += 0.002 * dt  # a real jitter of 0.2 % of a step, far above the 9-digit rounding
    printed = np.array([float(f"{v:.9g}") for v in t], dtype=np.float64)
    with pytest.raises(bw.errors.TimeAxisError, match="not uniformly sampled"):
        check_time_axis(printed, rtol=EXACT_GRID_RTOL)

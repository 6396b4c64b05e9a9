"""The place alternatives' separating experiment: x's lag behind u read as an angle (select.lag_arc).

The blind bench (benches/blind.py, a two-mass G whose x lags u by up to 3.3 rad) found the text saying
"x lags u by -3.00 to 1.15 rad here, a spread of 4.16 rad: G nearly flat over the band": a lag past pi
wrapped to near -pi, and a 4-rad spread called flat.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from bouc_wen_id.diagnosis import select as S


@pytest.mark.parametrize("shift", [0.0, 1.0, -2.5])
def test_lag_arc_is_the_shortest_arc_whatever_the_wrap(shift: float) -> None:
    lags = np.array([0.3, 1.15, 3.28]) + shift
    wrapped = np.angle(np.exp(1j * lags))
    start, spread = S.lag_arc(list(wrapped))
    assert spread == pytest.approx(2.98, abs=1e-12)
    assert np.angle(np.exp(1j * (start - lags[0]))) == pytest.approx(0.0, abs=1e-12)


def _separation(lags: list[float]) -> str:
    exps = [SimpleNamespace(grid_phase=0.0) for _ in lags]
    fit = SimpleNamespace(params=SimpleNamespace(gains=[1.0] * len(lags), phases=lags))
    return S._place_separation(exps, fit, "inertia")  # type: ignore[arg-type]


def test_a_wide_spread_past_pi_is_not_called_a_flat_g() -> None:
    text = _separation(list(np.angle(np.exp(1j * np.array([0.3, 1.15, 3.28])))))
    assert "a spread of 2.98 rad" in text and "nearly flat" not in text


def test_a_narrow_spread_is_called_a_flat_g() -> None:
    text = _separation([0.05, 0.12, 0.3])
    assert f"a spread of {0.25:.2f} rad" in text and "G nearly flat over the band" in text
    assert math.isclose(S.lag_arc([0.05, 0.12, 0.3])[1], 0.25)

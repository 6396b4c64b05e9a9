"""A frequency trend of the misfit is claimed only over a span and when significant (review 31a item 5)."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
from bouc_wen_id.diagnosis.locate import _growth


def _case(freqs: list[float], rms: list[float]) -> tuple[list[Any], list[np.ndarray]]:
    exps = [SimpleNamespace(noise_var=0.0, periods=10.0, frequency=f, amplitude=1.0) for f in freqs]
    resid = [r * np.sqrt(2.0) * np.sin(np.linspace(0.0, 2 * np.pi, 64, endpoint=False)) for r in rms]
    return exps, resid


def test_blocks_at_one_frequency_claim_no_trend() -> None:
    # five blocks of one record at about 3.05 Hz: the misfit differs by block, not by frequency
    freqs = [19.16, 19.17, 19.18, 19.19, 19.20]
    _, fexp, _ = _growth(*_case(freqs, [1.0, 0.4, 2.0, 0.7, 1.3]))
    assert math.isnan(fexp)
    assert max(freqs) / min(freqs) < 1.01


def test_a_real_power_law_is_found_and_scatter_is_not() -> None:
    freqs = [1.0, 2.0, 3.0, 4.5, 6.0, 8.0]
    _, fexp, _ = _growth(
        *_case(freqs, [0.01 * f**1.5 * (1.0 + 0.05 * (-1) ** i) for i, f in enumerate(freqs)])
    )
    assert abs(fexp - 1.5) < 0.1
    _, flat, _ = _growth(*_case(freqs, [1.0, 2.0, 1.0, 2.0, 1.0, 2.0]))
    assert math.isnan(flat)

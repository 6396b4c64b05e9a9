"""The loop-centre clause does not contradict a fitted output offset (review 31a item 9)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from bouc_wen_id.diagnosis.fit_notes import centre_clause


def _exps(dcs: list[float]) -> tuple[list[Any], list[np.ndarray]]:
    th = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
    exps = [
        SimpleNamespace(
            ybar=np.sin(th) + dc, noise_var=1e-4, periods=10.0, samples_per_period=64, source=f"e{i}"
        )
        for i, dc in enumerate(dcs)
    ]
    return exps, [np.sin(th) for _ in dcs]


def test_centres_of_both_signs_about_a_fitted_offset_are_said_beyond_it() -> None:
    exps, outs = _exps([0.05, -0.05, 0.0])
    plain = centre_clause(exps, outs, 1.0)
    assert "not one output offset" in plain
    about = centre_clause(exps, outs, 1.0, True)
    assert "about the fitted output offset" in about and "beyond one offset for all" in about
    assert "not one output offset" not in about
    assert "e0 +" in about and "e1 -" in about


def test_centres_of_one_sign_say_nothing() -> None:
    exps, outs = _exps([0.05, 0.04, 0.0])
    assert centre_clause(exps, outs, 1.0, True) == ""

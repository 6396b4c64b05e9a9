"""One fit of a start on the same periods per diagnosis (diagnosis/fit_share.py :func:`refit`,
:data:`speed.MEMO_REFITS`): a second call is the first one's result, the core not run again; a waveform
counts only for a model holding the distortion term.

Data from ``benches/generator.py`` (G solved exactly, its own RK4 of the hysteresis, its own noise).
"""

from __future__ import annotations

import importlib
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.diagnosis import fit_share, fitting, speed
from bouc_wen_id.diagnosis.data import prepare

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def _case(seed: int) -> tuple[list[Any], Any, int]:
    """A bench case's scaled experiments, its plain start and the substeps."""
    case = gen.make_case("library", "viscous", "u", 10.0, seed)
    exps = prepare(case.recordings)
    s = fitting.scale_of(exps)
    sx = fitting.scaled(exps, s)
    start = fitting.plain_start(exps, sx, s)[0]
    return sx, start, fitting.substeps_for([e.ybar.size for e in sx])


@pytest.fixture
def refines(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The core's refinements run (one entry a call)."""
    calls: list[int] = []
    real = _core.augmented_refine

    def counted(*args: Any, **kw: Any) -> Any:
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(_core, "augmented_refine", counted)
    return calls


def _waved(sx: list[Any], seed: int) -> list[Any]:
    """``sx`` with a made-up input waveform (harmonics 2 and 3) on each experiment."""
    rng = np.random.default_rng(seed)
    return [replace(e, waveform=rng.normal(0.0, 0.01, 4)) for e in sx]


def test_the_same_start_on_the_same_periods_is_fitted_once_in_a_scope(refines: list[int]) -> None:
    sx, start, steps = _case(21)
    with fit_share.scope():
        first = fitting.fit_from(sx, start, steps, max_iter=30)
        n = len(refines)
        again = fitting.fit_from(list(sx), start, steps, max_iter=30)
        assert n > 0 and len(refines) == n and again is first
        # A waveform the model does not read (no distortion term) is the same fit.
        assert fitting.fit_from(_waved(sx, 1), start, steps, max_iter=30) is first
        assert len(refines) == n
        # Another start, or another iteration cap, is another fit.
        moved = replace(start, beta=start.beta * 1.01)
        assert fitting.fit_from(sx, moved, steps, max_iter=30) is not first
        assert fitting.fit_from(sx, start, steps, max_iter=31) is not first
        assert len(refines) > n
    assert first is not None
    # Outside a scope nothing is kept: the same numbers, run again.
    k = len(refines)
    out = fitting.fit_from(sx, start, steps, max_iter=30)
    assert len(refines) > k and out is not None and out.cost == first.cost


def test_a_model_with_the_distortion_term_reads_the_waveform(refines: list[int]) -> None:
    sx, start, steps = _case(22)
    waved = _waved(sx, 2)
    dist = start.with_term("distortion", 0.1)
    with fit_share.scope():
        a = fitting.fit_from(waved, dist, steps, max_iter=20)
        n = len(refines)
        b = fitting.fit_from(_waved(sx, 3), dist, steps, max_iter=20)
        assert len(refines) > n and a is not None and b is not None and a is not b
        assert a.cost != b.cost  # the waveform changed the fit: a shared result would have been wrong


def test_the_switch_off_fits_every_call(refines: list[int], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(speed, "MEMO_REFITS", False)
    sx, start, steps = _case(23)
    with fit_share.scope():
        first = fitting.fit_from(sx, start, steps, max_iter=20)
        n = len(refines)
        again = fitting.fit_from(sx, start, steps, max_iter=20)
    assert len(refines) > n and first is not None and again is not None and again is not first
    assert again.cost == first.cost

"""The loop-centre check's pieces (diagnosis/loop_centre.py, session 30) without a diagnosis run: the line
taken off a record (the user's records unmodified) and no prediction without a named drift term."""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, cast

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import loop_centre, zero_drift

TWO_PI = 2.0 * math.pi


def _recs(slope: float) -> list[Any]:
    out = []
    rng = np.random.default_rng(30)
    for i in range(3):
        om, p, n = TWO_PI * (0.5 + 0.5 * i), 64, 12
        t = np.arange(n * p) * (TWO_PI / om / p)
        y = np.tanh(2.0 * np.cos(om * t - 0.4)) + slope * np.arange(t.size) + rng.normal(0.0, 1e-3, t.size)
        out.append(bw.Recording(t, np.cos(om * t), y, 1.0, om, settle_periods=2))
    return out


def test_the_predicted_line_is_taken_off_and_the_records_kept() -> None:
    recs = _recs(2e-5)
    before = [np.array(r.y) for r in recs]
    out = loop_centre.less_trend(recs, [2e-5] * len(recs))
    for r, o, b in zip(recs, out, before):
        np.testing.assert_array_equal(np.asarray(r.y), b)  # the user's record untouched
        rows = np.asarray(o.y)[2 * 64 :].reshape(-1, 64).mean(axis=1)
        assert abs(np.polyfit(np.arange(rows.size), rows, 1)[0]) < 0.05 * 2e-5 * 64  # 5 % of the line left
        # the mean over the periods after settling is kept
        assert abs(float(np.mean(np.asarray(o.y)[2 * 64 :]) - np.mean(b[2 * 64 :]))) < 1e-12
    assert zero_drift.detect(out, 0.05 / 20) is None  # the line was all the drift there was
    assert zero_drift.detect(recs, 0.05 / 20) is not None


def test_nothing_is_predicted_without_a_named_drift_term() -> None:
    d = SimpleNamespace(degradation=None, named=(), final_fit=None, experiments=())
    assert loop_centre.predicted_slopes(_recs(0.0), cast(Any, d)) is None
    assert loop_centre.check(_recs(0.0), cast(Any, d), 0.05 / 20) is None


def test_a_fixed_zero_is_qualified_when_the_predicting_model_fits_in_part(monkeypatch: Any) -> None:
    """Review of session 30: "the output's zero is taken as fixed" was said even when the model that
    predicted the loop's centre failed its adequacy test (a diagnosis "partly explained"); then it is said
    with that qualification, and without it when the model fits ("explained")."""
    recs = _recs(0.0)
    monkeypatch.setattr(loop_centre, "predicted_slopes", lambda items, d: ([0.0] * len(items), 0.01))
    texts = {}
    for status in ("partly explained", "explained"):
        got = loop_centre.check(recs, cast(Any, SimpleNamespace(status=status)), 0.05 / 20)
        assert got is not None and got.remaining is None
        texts[status] = got.text()
    assert (
        "taken as fixed" in texts["partly explained"]
        and "fits the records only in part" in texts["partly explained"]
    ), texts
    assert "taken as fixed" in texts["explained"] and "only in part" not in texts["explained"], texts


def test_a_drift_beyond_an_unfit_model_is_not_called_the_zeros(monkeypatch: Any) -> None:
    """Session 43 (eps42): "the output's zero drifts" was said whenever a line was left beyond the predicted
    centre, even when the model that predicted it failed its adequacy test; then the clause says the
    loop's centre moves and that model does not fit well enough to say whether the zero drifts."""
    recs = _recs(2e-5)  # a line the zero-drift test reads (the predicted centre flat: all of it is left)
    monkeypatch.setattr(loop_centre, "predicted_slopes", lambda items, d: ([0.0] * len(items), 0.01))
    texts = {}
    for status in ("partly explained", "explained"):
        got = loop_centre.check(recs, cast(Any, SimpleNamespace(status=status)), 0.05 / 20)
        assert got is not None and got.remaining is not None
        texts[status] = got.text()
    assert "the output's zero drifts" not in texts["partly explained"], texts
    assert "does not fit well enough to say whether the zero drifts" in texts["partly explained"], texts
    assert "the output's zero drifts" in texts["explained"], texts


@dataclass(frozen=True)
class _Said:
    """The fields of a diagnosis that :func:`loop_centre.resolved` reads and replaces."""

    verdict: str
    status: str
    notes: tuple[str, ...] = ()
    named: tuple[Any, ...] = ()
    degradation: Any = None


def test_an_unfit_model_sends_no_line_out_as_the_zeros(monkeypatch: Any) -> None:
    """The third branch of :func:`loop_centre.resolved`: ``beside`` names no drift term, the records' own
    model leaves a line and fails its adequacy test; that line is not taken out as the zero's (no third
    diagnosis), and ``beside``'s undecided clause becomes the qualified one."""
    recs = _recs(2e-5)
    wander = zero_drift.detect(recs, 0.05 / 20)
    assert wander is not None
    # only the records' own model (status "partly explained") predicts a centre; ``beside`` names no drift
    monkeypatch.setattr(
        loop_centre,
        "predicted_slopes",
        lambda items, d: None if d.status == "beside" else ([0.0] * len(items), 0.01),
    )
    beside = _Said("explained in part by: x" + wander.clause(), "beside")
    runs: list[int] = []

    def run(items: Any) -> Any:
        runs.append(len(items))
        return _Said("explained in part by: y", "partly explained")

    got = cast(Any, loop_centre.resolved(recs, 0.05 / 20, wander, cast(Any, beside), run))
    assert len(runs) == 1, runs  # the records as they are only; no line taken out as the zero's
    assert got.verdict.startswith("explained in part by: x"), got.verdict
    assert "the output's zero drifts" not in got.verdict and wander.clause() not in got.verdict, got.verdict
    assert "does not fit well enough to say whether the zero drifts" in got.verdict, got.verdict

"""Records too short to test the output's zero for drift (issue 18, honest verdicts; blind ``few_periods``).

The zero-drift test (``diagnosis.zero_drift``) needs 8 periods after settling: its decay test compares two
halves of 4, which tells a drifting zero (a line that goes on) from a loop still settling (a trend that
decays). With 4-6 recorded periods it tested nothing, and the drift's half in each experiment's DC (its sign
per experiment) was read as physics: a blind test named an offset as an asymmetry and the reverse, and
nulls offsets. Now the period means' trend is tested alone there (``zero_drift.short_trend``): a trend is
taken out with the DC, which is then not used, and the verdict says it may be either. And where every
experiment but one was left out as not settled, nothing is named from the one left (``run._from_one``).

Data: the bench's own generator (``benches/generator.py``: its plants, G and noise), its records cut to 5
periods after 4 settling ones, a straight drift of the output's zero added (1 noise sd over the record, its
sign per experiment, as the blind generator draws it).
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import run, settling, zero_drift

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

PERIODS, SETTLE = 5, 4


def _recs(seed: int, name: Any = None, value: float = 0.0, drift_sd: float = 1.0) -> list[Any]:
    """The generator's plant ``seed`` with ``name`` at ``value`` (None: nothing hidden), 5 recorded periods,
    its zero drifting by ``drift_sd`` noise sd over each record (sign per experiment)."""
    p = gen.make_plant(seed)
    eff = gen.Effect(name=name, values=np.array([value])) if name else gen.Effect()
    y = gen.run(p, eff, total=(SETTLE + PERIODS) * gen.P)[0]
    rng = np.random.default_rng([seed, 11])
    sign = rng.choice([-1.0, 1.0], size=y.shape[0])
    y = y + sign[:, None] * drift_sd * gen.NOISE_SD * np.linspace(0.0, 1.0, y.shape[-1])[None, :]
    recs: list[Any] = gen.recordings(p, y, seed, settle=SETTLE)
    return recs


def _diagnose(recs: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


@pytest.mark.parametrize("seed", [1, 3])
def test_a_null_of_short_records_under_a_drifting_zero_is_adequate_and_says_why(seed: int) -> None:
    """Nothing hidden, a zero drifting by 1 noise sd: before, "unexplained" (the offset's and the
    asymmetry's laws failing on the drift's DCs, read as "physics outside the library"); now the trend is
    taken out, the plain model is adequate, and the verdict says a drifting zero and a settling loop cannot
    be told apart here, and what would tell them (8 periods per experiment)."""
    d = _diagnose(_recs(seed))
    assert d.status == "adequate", d.verdict
    assert "a drifting zero or a loop still settling" in d.verdict
    assert f"at least {zero_drift.MIN_PERIODS} periods per experiment" in d.verdict


def test_no_dc_borne_term_is_named_from_short_records_under_a_drifting_zero() -> None:
    """An output offset and a drifting zero on 5-period records: the DC cannot tell them apart, so neither
    the offset nor the asymmetry (whose DC varies by experiment, as the drift's does) is named."""
    d = _diagnose(_recs(2, "offset", 0.02))
    named = {t.term for t in d.named}
    assert not named & {T.Offset.kind, T.Asymmetry.kind}, d.verdict
    assert "a drifting zero or a loop still settling" in d.verdict


def test_an_offset_in_short_records_without_drift_is_still_named() -> None:
    """The guard: without a drift the period means do not trend, the DC is used, and the offset is named
    (the short records' test takes nothing from a zero that stays put)."""
    recs = _recs(2, "offset", 0.02, drift_sd=0.0)
    assert zero_drift.short_trend(recs, 0.01) is None
    d = _diagnose(recs)
    assert T.Offset.kind in {t.term for t in d.named}, d.verdict


def test_short_trend_needs_a_trend_and_short_records() -> None:
    """``short_trend`` reads only records shorter than the drift test's 8 periods (and at least 4)."""
    recs = _recs(1)
    got = zero_drift.short_trend(recs, 0.01)
    assert got is not None and got.too_short and not got.kept
    assert got.p_value < zero_drift.DRIFT_ALPHA
    assert zero_drift.detect(recs, 0.01) is not None  # detect falls back to it when nothing is long enough


def test_nothing_is_named_from_the_one_experiment_left_when_the_rest_are_unsettled(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Every experiment but the first left out as not settled (the per-experiment drift test replaced, so
    the rule, not a noise draw, decides): an offset the first one's DC shows is not named from it alone
    (its law untested, its DC not to be told from the unsettled centres), and the verdict says the one
    experiment it would rest on. Before, "explained by: output offset" from that one experiment."""
    recs = _recs(2, "offset", 0.05, drift_sd=0.0)

    def rest(exps: Any) -> list[int]:
        return list(range(1, len(exps)))

    monkeypatch.setattr(run, "_unsettled", rest)
    monkeypatch.setattr(settling, "_unsettled", rest)  # the rule both paths read (settling.settled_only)
    d = _diagnose(recs)
    assert not d.named, d.verdict
    assert d.status == "unexplained"
    assert "would rest on exp0 alone" in d.verdict
    assert T.Offset.kind in {t.term for t in d.partial}


def test_the_short_trend_floor_follows_the_noise_level_near_the_dc() -> None:
    """A period mean's variance is the noise's spectrum near zero over P: for AR(1) noise (phi = 0.8) the
    residual's harmonics 1-3 sit several times above the white level, and the floor follows them; for
    white noise it stays at 1."""
    from scipy.signal import lfilter  # type: ignore[import-untyped]

    rng = np.random.default_rng(4)
    n, p, phi = 6, 128, 0.8
    white = rng.normal(0.0, 1.0, n * p).reshape(n, p)
    ar = np.asarray(lfilter([1.0], [1.0, -phi], rng.normal(0.0, np.sqrt(1 - phi**2), n * p))).reshape(n, p)

    def level(rows: np.ndarray) -> float:
        dc = rows.mean(axis=1)
        return float(np.mean(np.diff(rows - dc[:, None], axis=0) ** 2)) / 2.0 * p / (p - 1)

    assert zero_drift._low_colour(white, level(white)) < 1.6
    assert 3.0 < zero_drift._low_colour(ar, level(ar)) < (1 + phi) / (1 - phi) * 1.5

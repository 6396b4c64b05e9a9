"""``diagnose_across`` says single ``diagnose``'s one-amplitude caveat (diagnosis/one_amplitude.py, issue 18):
a loop-shape term named across conditions none of which records a frequency at two amplitudes carries the
family caveat in its headline; a second amplitude at one frequency of a condition lifts it. Amplitudes that
differ only between conditions do not test the amplitude law (the term's value is free per condition)."""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import one_amplitude as O
from bouc_wen_id.diagnosis import readings
from bouc_wen_id.diagnosis.result import NamedTerm
from bouc_wen_id.diagnosis.verdict_text import headline

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def _exps(pairs: list[tuple[float, float]]) -> list[SimpleNamespace]:
    return [SimpleNamespace(frequency=w, amplitude=a) for w, a in pairs]


def test_the_across_clause_needs_one_amplitude_per_frequency_at_every_condition() -> None:
    pinch = NamedTerm(T.Pinching.kind, "zeta1", 0.05, 0.01, "")
    a, b = _exps([(3.0, 2.0), (6.0, 2.0)]), _exps([(3.0, 1.0), (6.0, 1.0)])
    said = O.across_text([pinch], [a, b])
    assert O.ONE_AMPLITUDE_MARK in said and "U = 1" in said  # half the largest amplitude of all conditions
    assert O.text([pinch], [*a, *b]) == ""  # pooled, the conditions' amplitudes would read as a tested law
    assert O.across_text([pinch], [a, _exps([(3.0, 1.0), (3.0, 2.0)])]) == ""  # tested at one condition
    assert O.across_text([NamedTerm(T.Viscous.kind, "c", 0.1, 0.01, "")], [a, b]) == ""
    assert O.across_text([pinch], []) == ""


def _groups(levels: tuple[float, ...], seeds: tuple[int, ...], monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    monkeypatch.setattr(gen, "FREQ_FACTORS", (0.5, 1.0, 2.0))
    monkeypatch.setattr(gen, "X_LEVELS", levels)
    return [gen.make_case("library", "pinching", "", 30.0, s).recordings for s in seeds]


def _across(groups: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=[T.Pinching.kind, T.Viscous.kind])


def test_pinching_named_across_one_amplitude_conditions_carries_the_caveat(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The bench's generator, pinching, three frequencies at one amplitude, two conditions (seeds 4001,
    4002): before across40 the across headline named pinching with no caveat."""
    a = _across(_groups((3.0,), (4001, 4002), monkeypatch))
    assert T.Pinching.kind in a.named, a.verdict
    assert O.ONE_AMPLITUDE_MARK in headline(a.verdict), a.verdict
    assert "not the only reading" in readings.status_text(a.status, a.readings), a.verdict


def test_a_second_amplitude_at_a_condition_lifts_the_caveat_across(monkeypatch: pytest.MonkeyPatch) -> None:
    """The same, each condition's frequencies at two amplitudes (latent 1.5 and 3.0): pinching named, no
    one-amplitude caveat."""
    a = _across(_groups((1.5, 3.0), (4003, 4004), monkeypatch))
    assert T.Pinching.kind in a.named, a.verdict
    assert O.ONE_AMPLITUDE_MARK not in a.verdict, a.verdict


def test_an_iwan_loop_named_pinching_across_carries_the_caveat(monkeypatch: pytest.MonkeyPatch) -> None:
    """Data made another way: the bench's outside Iwan loop (distributed stops) through a first-order G with
    AR(1) output noise (phi 0.7, studies/outside_design.py's), three frequencies at one amplitude, 30x, two
    conditions (seeds 3801, 3802). Before across40: "explained" by pinching, no rival reading."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
    od: Any = importlib.import_module("outside_design")
    monkeypatch.setattr(gen, "FREQ_FACTORS", (0.5, 1.0, 2.0))
    monkeypatch.setattr(gen, "X_LEVELS", (3.0,))
    monkeypatch.setattr(gen, "recordings", od.ar1_recordings(0.7))
    plant = gen.make_plant
    monkeypatch.setattr(
        gen, "make_plant", lambda seed, _s=None, low_amplitude=False: plant(seed, "first", low_amplitude)
    )
    groups = [gen.make_case("outside", "iwan", "", 30.0, s).recordings for s in (3801, 3802)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, [0.0, 1.0])
    assert T.Pinching.kind in a.named, a.verdict
    assert O.ONE_AMPLITUDE_MARK in headline(a.verdict), a.verdict
    assert "not the only reading" in readings.status_text(a.status, a.readings), a.verdict

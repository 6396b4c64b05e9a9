"""The rate caveat of a named viscous damping (diagnosis/rate_rival.py, review 33 ``pi_u_10``).

A Prandtl-Ishlinskii loop on u (outside the library) was said "explained by: viscous damping across the
hysteretic element (on x)" with no caveat: the law test (one value for every experiment, against every
direction) passed at p = 0.11. A rate-independent loop needs a damping that falls as 1/frequency; these tests
give the caveat the per-experiment values directly (the law test's step stubbed) so that the rule, not a noise
draw, decides."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import rate_rival
from bouc_wen_id.diagnosis.result import NamedTerm
from bouc_wen_id.diagnosis.select import LAW_ALPHA

OM = np.array([1.5, 3.0, 6.0, 1.5, 3.0, 6.0])
AMP = np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5])
GAIN = np.array([0.94, 0.8, 0.55, 0.94, 0.8, 0.55])


def _case(monkeypatch: pytest.MonkeyPatch, term: str, values: np.ndarray, se: np.ndarray) -> tuple[Any, Any]:
    exps = [SimpleNamespace(frequency=w, amplitude=a, waveform=np.zeros(0)) for w, a in zip(OM, AMP)]
    c0 = float(np.mean(values))
    fit = SimpleNamespace(params=SimpleNamespace(terms=(term,), values=np.array([c0]), gains=GAIN))
    step = (values - c0, np.diag(se**2), np.ones(OM.size), [np.arange(OM.size)])
    monkeypatch.setattr(rate_rival, "freed_step", lambda *a: step)
    return exps, fit


def _said(exps: Any, fit: Any, term: str, value: float) -> str:
    return rate_rival.rate_text([NamedTerm(term, "c", value, 0.1 * value, "s")], exps, fit, 3)


@pytest.mark.parametrize("term", [T.ViscousX.kind, T.Viscous.kind])
def test_values_falling_as_one_over_frequency_within_their_errors_get_the_caveat(
    monkeypatch: pytest.MonkeyPatch, term: str
) -> None:
    """Values that follow 1/omega (a rate-independent loop), a few tenths wide: the rival is not refused,
    the verdict says what the damping may stand for and which experiment would tell."""
    vals = 0.006 / OM
    exps, fit = _case(monkeypatch, term, vals, 0.3 * vals)
    p = rate_rival.rival_p_values(exps, fit, term, 3)
    assert p is not None and max(p) >= LAW_ALPHA
    said = _said(exps, fit, term, float(np.mean(vals)))
    assert rate_rival.RATE_MARK in said and T.TERMS[term].place_label() in said and "1.5-6 rad/s" in said


@pytest.mark.parametrize("term", [T.ViscousX.kind, T.Viscous.kind])
def test_one_value_at_every_frequency_refuses_the_rival_and_says_nothing(
    monkeypatch: pytest.MonkeyPatch, term: str
) -> None:
    """A true viscous damping: one value over frequencies a factor 4 apart, 10 % wide per experiment: the
    1/omega law is refused (under either reading of the loop's place) and no caveat is said."""
    vals = np.full(OM.size, 0.006)
    exps, fit = _case(monkeypatch, term, vals, 0.1 * vals)
    p = rate_rival.rival_p_values(exps, fit, term, 3)
    assert p is not None and max(p) < LAW_ALPHA
    assert _said(exps, fit, term, 0.006) == ""


def test_one_frequency_per_amplitude_cannot_test_the_rival(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each amplitude at one frequency: the rival's factor per amplitude takes every value, nothing to
    compare: no p and no caveat (not a claim the data cannot back)."""
    exps, fit = _case(monkeypatch, T.ViscousX.kind, 0.006 / OM, 0.3 * 0.006 / OM)
    for e, a in zip(exps, (1.0, 0.9, 0.8, 0.7, 0.6, 0.5)):
        e.amplitude = a
    assert rate_rival.rival_p_values(exps, fit, T.ViscousX.kind, 3) is None
    assert _said(exps, fit, T.ViscousX.kind, 0.003) == ""


def test_other_terms_get_no_rate_caveat(monkeypatch: pytest.MonkeyPatch) -> None:
    exps, fit = _case(monkeypatch, T.Stiffness.kind, 0.006 / OM, 0.3 * 0.006 / OM)
    assert _said(exps, fit, T.Stiffness.kind, 0.003) == ""

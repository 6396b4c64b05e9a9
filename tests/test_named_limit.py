"""Detected is not named (issue 18, review 34 problem 6): a detection limit is its own F-test's 90 %-power
value; the verdict names the term only if it also beats the other candidates and passes the held-out and law
tests. diagnosis/named_limit.py gives the value at which a candidate is named over a rival sharing its trace
(inf for a twin); resolution.py says it, says what the quoted 90 % is about, and says a candidate the data
detected but the verdict did not name instead of listing it as "not excluded below" its limit."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from bouc_wen_id.diagnosis import named_limit, resolution
from bouc_wen_id.diagnosis.limits import Z_90, DetectionLimit
from bouc_wen_id.diagnosis.result import TERM_LABELS
from bouc_wen_id.diagnosis.select import HeldOut, Trial

THR = 10.0  # the F-test's threshold (chi-square units), s2 = 1
T90 = (math.sqrt(THR) + Z_90) ** 2  # the unabsorbed size at the 90 % value


def _unit(rng: np.random.Generator, n: int) -> Any:
    v = rng.standard_normal(n)
    return v / np.linalg.norm(v)


def _rival(a: Any, b: Any, share: float) -> Any:
    """A trace whose share c2 of ``a`` is ``share`` (``b`` orthogonal to ``a``), at an arbitrary scale."""
    return 3.7 * (math.sqrt(share) * a + math.sqrt(1.0 - share) * b)


def test_without_a_rival_the_named_value_is_the_tests_own_90_percent_value() -> None:
    rng = np.random.default_rng(1)
    a = _unit(rng, 50)
    b = _unit(rng, 50)
    b -= (b @ a) * a
    sep = named_limit.separation(a, {"r": b / np.linalg.norm(b)}, 2.0, T90, THR, 1.0)
    assert sep.named_90 == pytest.approx(2.0, rel=1e-2)


def test_an_exact_twin_is_never_told_apart_and_a_refused_one_takes_nothing() -> None:
    rng = np.random.default_rng(2)
    a = _unit(rng, 50)
    twin = named_limit.separation(a, {"r": -2.0 * a}, 1.0, T90, THR, 1.0)
    assert twin.twin and twin.rival == "r" and twin.named_90 == math.inf
    # the same twin confined to >= 0: it takes the trace only with a negative value, refused by its bound
    refused = named_limit.separation(a, {"r": -2.0 * a}, 1.0, T90, THR, 1.0, one_sided={"r"})
    assert refused.rival == "" and refused.named_90 == 1.0


def test_the_named_value_is_calibrated_by_simulating_the_selection() -> None:
    """At the named value, the term passes its test and fits better than the rival in 90 % of noise draws
    (the two-term choice simulated directly: the least-squares fit of each trace alone)."""
    rng = np.random.default_rng(3)
    n = 40
    a = _unit(rng, n)
    b = _unit(rng, n)
    b -= (b @ a) * a
    b /= np.linalg.norm(b)
    share = 0.8
    r = _rival(a, b, share)
    sep = named_limit.separation(a, {"r": r}, 1.0, T90, THR, 1.0)
    assert 1.2 < sep.named_90 < math.inf
    rh = r / np.linalg.norm(r)

    def rate(x: float, draws: int = 4000) -> float:
        mean = math.sqrt(T90) * x * a
        e = rng.standard_normal((draws, n))
        y = mean + e
        drop_t, drop_r = (y @ a) ** 2, (y @ rh) ** 2
        return float(np.mean((drop_t > THR) & (drop_t > drop_r)))

    assert rate(sep.named_90) == pytest.approx(0.9, abs=0.03)
    assert rate(1.0) < 0.8  # at the test's own 90 % value the rival takes it too often


def _lim(**kw: Any) -> DetectionLimit:
    base = DetectionLimit(
        term="stiffness@x",
        symbol="k",
        unit="",
        limit=0.039,
        limit_90=0.056,
        value=0.0669,
        standard_error=0.0096,
        level=1e-3,
        one_sided=False,
        absorbed=0.0,
    )
    return replace(base, **kw)


class _D:
    experiments: tuple[Any, ...] = ()


def test_the_quoted_limit_says_it_is_the_tests_power_and_when_naming_needs_more(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(resolution, "resolution_text", lambda d, alpha, unit: "")
    plain = resolution.adequate_tail([_lim()], _D(), 0.05)
    assert "its own test detects with 90 % power" in plain and "held-out" in plain
    # the 90 % is a linearisation: simulated at it, the test passed in 166 of 200 cases (docs/diagnosis.md)
    # ... so the power is overstated and the size a test needs larger (review 35m, F3: "which may overstate
    # it", the size, said the opposite direction); the report's HTML says the same
    assert "may overstate the power" in plain and "can be larger" in plain
    assert "overstate it" not in plain
    far = resolution.limit_text(_lim(named_90=0.12, rival="inertia", rival_share=0.63))
    # a better fit, not the alternatives' separation (review 35m, F4: "told from X ... above 0.0059" beside a
    # named 0.0063 the verdict said could not be told from X)
    assert "fits better than " + TERM_LABELS["inertia"] in far
    assert "with 90 % probability only above 0.12" in far
    assert "told from" not in far.split("(a better fit")[0]
    twin = resolution.limit_text(_lim(named_90=math.inf, rival="inertia@x", rival_share=1.0))
    assert "not separable from " + TERM_LABELS["inertia@x"] in twin
    near = resolution.limit_text(_lim(named_90=0.057, rival="inertia", rival_share=0.1))
    assert "only above" not in near


def test_a_candidate_detected_here_but_not_named_is_said_not_listed_as_not_excluded(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Review 34's case: its test passed (p adj 4.1e-09) with k = 0.0669, its held-out was worse, and the
    verdict said "adequate ... not excluded below (90 % power): ... |k| < 0.056"."""
    monkeypatch.setattr(resolution, "resolution_text", lambda d, alpha, unit: "")
    lim = _lim(p_adjusted=4.1e-9, not_named="its held-out prediction was worse than the plain model's")
    other = _lim(term="viscous", symbol="c", value=1e-4)
    tail = resolution.adequate_tail([lim, other], _D(), 0.05)
    said, rest = tail.split("not excluded below")
    assert "detected by its own test on these data but not named" in said
    assert "k = 0.0669" in said and "held-out" in said and "4.1e-09" in said
    assert lim.label not in rest and other.label in rest


def test_why_a_detected_candidate_was_not_named() -> None:
    ho = HeldOut((0, 1), (1.0, 1.0), (2.0, 2.0), (0.1, 0.1), (0.2, 0.2))
    tr = Trial("stiffness@x", 700.0, 40.0, 41.0, 1e-10, 4e-9, 0.7, True, held_out=ho)
    assert "held-out" in named_limit.why_not_named(tr)
    assert "range" in named_limit.why_not_named(replace(tr, passed=False))
    law = replace(tr, held_out=None, law_p_value=1e-4)
    assert "law" in named_limit.why_not_named(law)
    # review 34's seed 3: inertia on u named at the step, the spring on x never reached
    instead = named_limit.why_not_named(replace(tr, held_out=None), "inertia")
    # the step's choice, which later checks may drop: not "named" (review 35m, F2: negku's sensor lag)
    assert "the first step chose " + TERM_LABELS["inertia"] + " instead" in instead
    assert "named" not in instead.replace("final verdict", "")

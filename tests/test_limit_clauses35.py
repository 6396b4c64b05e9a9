"""Review 35m's findings on the detection-limit clauses (F1, F8): no limit line says "not detectable" beside
"its own test passed on these data", and the "adequate" verdict's detected-but-not-named clause says that
several candidates are alternative readings of one misfit, keeps a value within 2 se of zero, at its null or
outside its range apart as no detection, and does not follow "fits at the noise floor"."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest
from bouc_wen_id.diagnosis import limits, limits_void, named_limit, resolution
from bouc_wen_id.diagnosis.gate import ADEQUATE
from bouc_wen_id.diagnosis.limits import DetectionLimit
from bouc_wen_id.diagnosis.result import SEEN_NOT_NAMED, status_text


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
        p_adjusted=4.1e-9,
        not_named="its held-out prediction was worse than the plain model's",
    )
    return replace(base, **kw)


class _D:
    experiments: tuple[Any, ...] = ()
    settings: dict[str, Any] = {"alpha": 0.05}

    class final:  # noqa: N801 (a stand-in for the final fit)
        p_value = 0.5
        cost = 1.0
        dof = 1

    def __init__(self, lims: list[DetectionLimit]) -> None:
        self.limits = lims


def test_a_limit_whose_own_test_passed_is_not_said_not_detectable() -> None:
    """degr_both_res: "Dahl friction ... (on x): no detection limit (not detectable within the term's
    admissible range); 90 %: inf; its own test passed on these data (p adj 5.5e-14)"."""
    assert "not detectable" in limits.infinite_note(False)
    seen = limits.infinite_note(True)
    assert "not detectable" not in seen and "no limit could be computed" in seen
    inf = float("inf")
    lim = _lim(term="dahl@x", limit=inf, limit_90=inf, note=seen, p_adjusted=5.5e-14)
    (line,) = limits_void.summary_lines(_D([lim]))[2:]
    assert "its own test passed on these data (p adj 5.5e-14)" in line and "not detectable" not in line


def test_several_detected_candidates_are_alternative_readings_and_a_null_value_is_no_detection(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """mx1f condition 1: six candidates each "detected" with values, one of them fc = 0.271 ± 3.2 whose reason
    is "at its null value or outside its range"."""
    monkeypatch.setattr(resolution, "resolution_text", lambda d, alpha, unit: "")
    one = _lim()
    two = _lim(term="viscous", symbol="c", value=0.00267, standard_error=0.00063)
    null = _lim(term="dahl", symbol="fc", value=0.271, standard_error=3.2, not_named=named_limit.NOT_PASSED)
    near = _lim(term="viscous@x", symbol="c", value=0.001, standard_error=0.0009)
    text = resolution.detected_text([one, two, null, near])
    readings, apart = text.split("no detection")
    assert "alternative readings of one misfit" in readings and "not 2 terms" in readings
    assert "k = 0.0669" in readings and "c = 0.00267" in readings
    assert null.label in apart and near.label in apart and "0.271" not in text and "0.001 " not in text
    alone = resolution.detected_text([one])
    assert "detected by its own test" in alone and "alternative readings" not in alone
    # the verdict's first clause: passes its adequacy test, not "fits at the noise floor", when one is seen
    verdict = ADEQUATE + "; not excluded below ..."
    said = resolution.adequate_head(verdict, [one]) + resolution.adequate_tail([one], _D([one]), 0.05)
    assert said.startswith(resolution.ADEQUATE_SEEN) and "noise floor" not in said
    assert resolution.adequate_head(verdict, [replace(one, not_named="")]) == verdict


def test_the_printed_status_says_a_candidate_was_seen_but_none_named() -> None:
    """kx_f1a6: status "adequate" while the verdict's body said a spring was detected at p adj 4e-09."""
    assert status_text("adequate", (), True) == f"adequate ({SEEN_NOT_NAMED})"
    assert status_text("adequate", ()) == "adequate"
    assert status_text("unexplained", (), True) == "unexplained"


def test_a_term_the_verdict_names_has_no_not_named_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    """Review 35m F11: viscous on u named at step 2 was reported "not named: its value differs between
    experiments" in the summary and JSON, because the limits read the first step only."""
    from dataclasses import dataclass, field
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import run
    from bouc_wen_id.diagnosis.result import NamedTerm

    @dataclass(frozen=True)
    class _Named:
        status: str = "explained"
        verdict: str = "explained by: viscous damping"
        experiments: tuple[Any, ...] = ()
        named: tuple[NamedTerm, ...] = ()
        limits: tuple[DetectionLimit, ...] = field(default_factory=tuple)

    named = (NamedTerm("viscous", "c", 0.00996, 8e-5, "s"),)
    lims = (_lim(term="viscous", not_named="its value differs between experiments"), _lim())
    monkeypatch.setattr(run, "detection_limits", lambda *a, **k: lims)
    setup = SimpleNamespace(units=("", ""), alpha=0.05)
    out = run._with_limits(_Named(named=named), [], None, [], None, 1, setup)  # type: ignore[arg-type]
    by_term = {lim.term: lim for lim in out.limits}
    assert by_term["viscous"].not_named == ""  # named: no reason why not
    assert by_term["stiffness@x"].not_named  # not named: its reason kept

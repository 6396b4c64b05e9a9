"""The stability rule (diagnosis/stability.py): a term named in the main run and in every completed
preprocessing variant is a finding; one named in k < n is an alternative, moved out of the verdict's named
terms; a term only some variants name is said likewise; a failed variant is left out of the count and said."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import pytest
from bouc_wen_id import Measurement, average_measurement
from bouc_wen_id.diagnosis import run as diag_run
from bouc_wen_id.diagnosis import stability as stab
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.limits import DetectionLimit
from bouc_wen_id.diagnosis.result import Diagnosis, NamedTerm
from bouc_wen_id.errors import InsufficientDataError
from bouc_wen_id.signal import average_segments

VISCOUS = NamedTerm("viscous", "c", 3.3, 0.01, "N s/mm")
ASYM = NamedTerm("asymmetry", "delta", -6e-5, 1e-6, "1/N^mu")
DEG = NamedTerm("degradation", "delta_nu", 1.5e-11, 2e-12, "1/N^2")
OFFSET = NamedTerm("offset", "y0", 4.0, 0.1, "N")


def _diag(
    named: tuple[NamedTerm, ...],
    status: str = "partly explained",
    limits: tuple[DetectionLimit, ...] = (),
    partial: tuple[NamedTerm, ...] = (),
) -> Diagnosis:
    """A diagnosis naming ``named`` (found ``partial`` beside structure left), its verdict built as
    run._verdict builds it, with the detection limits ``limits``."""
    none = cast(Any, None)
    verdict = (
        "explained in part by: " + ", ".join(str(t) for t in named) + " (82 % of the excess); unexplained "
        "structure remains at harmonics 1, 2"
        if status == "partly explained"
        else "explained by: " + ", ".join(str(t) for t in named)
        if status == "explained"
        else f"{status}: the plain Wiener-Bouc-Wen model fits at the noise floor"
        if status == "adequate"
        else "unexplained structure remains at harmonic 2"
    )
    return Diagnosis(
        status=cast(Any, status),
        verdict=verdict,
        named=named,
        partial=partial,
        alternatives=(),
        before=none,
        after=none,
        steps=(),
        held_out=None,
        plain=none,
        final=none,
        experiments=(),
        explained_fraction=0.82,
        settings={},
        seconds=0.0,
        limits=limits,
    )


def test_a_term_in_every_variant_is_a_finding_one_in_k_of_n_an_alternative() -> None:
    main = _diag((VISCOUS, ASYM, DEG))
    runs: dict[str, stab.Outcome] = {
        "early": _diag((VISCOUS, ASYM, DEG)),
        "late": _diag((VISCOUS, ASYM)),
        "half harmonics": _diag((ASYM, VISCOUS)),
    }
    st = stab.stability(main, runs)
    assert st.findings == ("viscous", "asymmetry")
    assert st.alternatives == ("degradation",)
    deg = next(t for t in st.terms if t.term == "degradation")
    assert deg.named_in == ("as recorded", "early") and deg.completed == 4 and not deg.finding
    # The verdict no longer names degradation among the terms that explain; it says it is an alternative.
    head = st.verdict.split(";")[0]
    assert str(DEG) not in head and str(VISCOUS) in head and str(ASYM) in head
    assert "degradation" in st.verdict and "named in 2 of 4 preprocessing variants" in st.verdict
    assert "an alternative, not a finding" in st.verdict
    assert st.status == "partly explained"
    d = st.to_dict()
    assert d["findings"] == ["viscous", "asymmetry"] and d["alternatives"] == ["degradation"]
    assert d["main_verdict"] == main.verdict and d["verdict"] == st.verdict


def test_every_variant_agreeing_leaves_the_verdict_as_it_is() -> None:
    main = _diag((VISCOUS, ASYM))
    st = stab.stability(main, {"early": _diag((ASYM, VISCOUS)), "late": _diag((VISCOUS, ASYM))})
    assert st.verdict == main.verdict and st.status == main.status
    assert st.alternatives == () and set(st.findings) == {"viscous", "asymmetry"}


def test_a_term_only_some_variants_name_is_said_as_an_alternative() -> None:
    main = _diag((VISCOUS,))
    st = stab.stability(main, {"early": _diag((VISCOUS, OFFSET)), "late": _diag((VISCOUS,))})
    assert st.findings == ("viscous",) and st.alternatives == ("offset",)
    assert st.verdict.startswith(main.verdict)
    assert "output offset named in 1 of 3 preprocessing variants (early; not as recorded, late)" in st.verdict


def test_a_failed_variant_is_left_out_of_the_count_and_said() -> None:
    main = _diag((VISCOUS, DEG))
    runs: dict[str, stab.Outcome] = {
        "early": InsufficientDataError("too few periods"),
        "late": _diag((VISCOUS, DEG)),
        "half harmonics": "refused: InsufficientDataError",
    }
    st = stab.stability(main, runs)
    assert st.completed == ("as recorded", "late")
    assert st.findings == ("viscous", "degradation")  # 2 of 2 completed: the failures do not count against
    assert set(st.failed) == {"early", "half harmonics"} and "too few periods" in st.failed["early"]
    # Nothing unstable: the verdict is the main run's.
    assert st.verdict == main.verdict
    # With an unstable term, the count is over the completed runs and the failures are said.
    st2 = stab.stability(main, {**runs, "late": _diag((VISCOUS,))})
    assert "named in 1 of 2 preprocessing variants" in st2.verdict
    assert (
        "variants that failed, not counted: early (InsufficientDataError: too few periods), half harmonics"
        in st2.verdict
    )


def test_no_stable_term_left_is_unexplained_and_explained_becomes_partly() -> None:
    main = _diag((DEG,))
    st = stab.stability(main, {"early": _diag(()), "late": _diag(())})
    assert st.status == "unexplained" and st.findings == () and st.alternatives == ("degradation",)
    assert st.verdict.startswith("no term named in every preprocessing variant")
    full = _diag((VISCOUS, DEG), status="explained")
    st = stab.stability(full, {"early": _diag((VISCOUS,), status="explained")})
    assert st.status == "partly explained" and str(DEG) not in st.verdict.split(";")[0]
    assert st.verdict.startswith(f"explained in part by: {VISCOUS};") and "(the fit counts it)" in st.verdict


def test_no_completed_variant_leaves_the_verdict_and_says_stability_was_not_checked() -> None:
    main = _diag((VISCOUS, DEG))
    st = stab.stability(main, {"early": "refused", "late": ValueError("x")})
    assert not st.checked and st.findings == () and st.status == main.status
    assert st.verdict.startswith(main.verdict) and "not checked" in st.verdict


def test_bad_outcomes_are_named_errors() -> None:
    main = _diag((VISCOUS,))
    with pytest.raises(TypeError, match="variant 'early'"):
        stab.stability(main, {"early": cast(Any, 3)})
    with pytest.raises(ValueError, match="main run"):
        stab.stability(main, {"as recorded": main})
    with pytest.raises(TypeError, match="Diagnosis"):
        stab.stability(cast(Any, "x"), {})


def _measurement(seed: int) -> Measurement:
    rng = np.random.default_rng(seed)
    t = np.arange(0, 20.0, 0.01)
    u = np.sin(2 * np.pi * t)
    return Measurement(t, u, np.tanh(3 * u) + 0.01 * rng.standard_normal(t.size), name=f"m{seed}")


def test_variant_items_cut_without_touching_the_measurements_and_refuse_others() -> None:
    ms = [_measurement(1), _measurement(2)]
    before = [m.y.copy() for m in ms]
    early, late = stab.variant_items(ms, "early"), stab.variant_items(ms, "late")
    for m, e, la, y in zip(ms, early, late, before):
        assert np.array_equal(m.y, y)
        ap = average_measurement(m)[0]
        assert e.periods < ap.periods and la.periods < ap.periods  # two thirds of the steady stretch
        assert e.source.endswith("(early)") and la.source.endswith("(late)")
    assert stab.variant_items(ms, "as recorded") == ms
    with pytest.raises(ValueError, match="unknown preprocessing variant"):
        stab.variant_items(ms, "reversed")
    with pytest.raises(TypeError, match="Measurements"):
        stab.variant_items([object()], "early")


def test_diagnose_stable_runs_each_variant_and_counts_a_refused_one_as_failed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """diagnose_stable passes the variants' items to diagnose and reads them with stability (diagnose
    stubbed: the rule, not the fit, is under test)."""
    seen: list[int] = []

    def fake(items: Any, **kw: Any) -> Diagnosis:
        seen.append(len(items))
        if any("(late)" in getattr(m, "source", "") for m in items):
            raise InsufficientDataError("too short")
        return _diag((VISCOUS, DEG) if len(seen) == 1 else (VISCOUS,))

    monkeypatch.setattr(diag_run, "diagnose", fake)
    st = stab.diagnose_stable([_measurement(3), _measurement(4)], variants=("early", "late"))
    assert len(seen) == 3 and set(st.failed) == {"late"} and st.completed == ("as recorded", "early")
    assert st.alternatives == ("degradation",) and st.findings == ("viscous",)
    main = _diag((VISCOUS, DEG))
    said = main.verdict
    st = stab.diagnose_stable([_measurement(3)], variants=("early",), main=main)
    assert st.main is main and len(seen) == 4  # the main run given is not run again
    assert st.alternatives == ("degradation",) and main.verdict == said  # the main diagnosis untouched
    with pytest.raises(ValueError, match="unknown preprocessing variants"):
        stab.diagnose_stable([_measurement(3)], variants=("as recorded",))


def _limit(term: NamedTerm, limit_90: float) -> DetectionLimit:
    """A variant's detection limit for ``term`` (90 % power at ``limit_90``)."""
    return DetectionLimit(
        term.term, term.symbol, term.unit, 0.7 * limit_90, limit_90, 0.0, 0.2, 0.01, False, 0.0
    )


def test_a_variant_too_small_to_see_a_term_is_not_counted_against_it() -> None:
    """Review 31c (stable_power.py 6 5): a shorter variant with the term below its detection limit is not
    evidence against it; one that could have seen it (limit below the main run's value) is."""
    main = _diag((OFFSET,), status="explained")
    blind = _diag((), status="adequate", limits=(_limit(OFFSET, 2.5 * OFFSET.value),))
    st = stab.stability(main, {"early": blind, "late": main, "half harmonics": main})
    off = st.terms[0]
    assert off.unseen == ("early",) and off.finding and st.findings == ("offset",)
    assert st.status == "explained" and st.verdict.startswith(main.verdict)
    assert "not named in early, which could not have seen it" in st.verdict
    assert st.to_dict()["terms"][0]["unseen"] == ["early"]
    sharp = _diag((), status="adequate", limits=(_limit(OFFSET, 0.4 * OFFSET.value),))
    st = stab.stability(main, {"early": sharp, "late": main, "half harmonics": main})
    assert st.terms[0].unseen == () and st.alternatives == ("offset",)
    assert "named in 3 of 4 preprocessing variants" in st.verdict


def test_nothing_stable_named_but_no_run_left_structure_is_not_unexplained() -> None:
    """Review 31c (stab_text.py): every run fit at its noise floor (adequate, or explained by the term), so
    nothing is shown to remain: partly explained by alternatives, not "unexplained"."""
    main = _diag((OFFSET,), status="explained")
    st = stab.stability(main, {"early": _diag((), status="adequate"), "late": main})
    assert st.alternatives == ("offset",) and st.findings == ()
    assert st.status == "partly explained"
    assert st.verdict.startswith("explained only by alternatives, not findings")
    assert "named in 2 of 3 preprocessing variants" in st.verdict
    # A run that left structure keeps it "unexplained".
    st = stab.stability(main, {"early": _diag((), status="unexplained"), "late": main})
    assert st.status == "unexplained"


def test_a_variant_that_found_the_term_beside_structure_counts_as_naming_it() -> None:
    main = _diag((OFFSET,), status="explained")
    found = _diag((), status="unexplained", partial=(OFFSET,))
    st = stab.stability(main, {"early": found, "late": main})
    assert st.findings == ("offset",) and st.terms[0].named_in == ("as recorded", "early", "late")
    assert st.status == "explained" and st.verdict == main.verdict


def _two_segments() -> Measurement:
    """One Measurement, two steady segments (two amplitudes), each after a settling stretch."""
    f, fs = 2.0, 200.0
    t = np.arange(0, 60, 1 / fs)
    u = np.where(t < 30, 1.0, 2.0) * np.sin(2 * np.pi * f * t)
    y = np.tanh(2 * u) + 0.01 * np.random.default_rng(0).normal(size=t.size)
    return Measurement(t, u, y, nominal_frequency=f, name="two")


def test_early_and_late_cut_every_segment_and_keep_its_lead() -> None:
    """Review 31c (multiseg.py, lead_cut.py): the cuts keep every steady segment, and the periods recorded
    before each stretch (the drift's age) stay its lead: the late cut's lead grows by the third it drops."""
    m = _two_segments()
    main = prepare([m])
    assert len(main) == 2 and main[1].lead_periods > 50  # the second segment follows 30 s at 2 Hz
    for variant in ("early", "late", "half harmonics"):
        cut = stab.variant_items([m], variant)
        assert len(cut) == len(main)
        for e, full, k in zip(cut, main, average_segments(m).report.kept):
            assert e.lead_periods >= full.lead_periods  # never younger than the main run's stretch
            if variant == "late":
                dropped = (k.stop - k.start) // 3 * (m.t[1] - m.t[0]) * 2.0  # the third dropped, in periods
                assert e.lead_periods - full.lead_periods == pytest.approx(dropped, abs=1.0)
                assert e.lead_periods > full.lead_periods
            else:
                assert e.lead_periods == full.lead_periods

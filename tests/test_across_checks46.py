"""diagnose_across runs two more of diagnose's checks through the same functions (session 46, ring46;
diagnosis/across_checks.py): a line not locked to the input taken out (lines.py) and a weak remainder said
"may remain" with its p (borderline.py).

The hum records are test_diagnosis_lines.py's (the diagnosis bench's generator, its own RK4, a 60 Hz-like
line at 2 noise sd added), given as two conditions.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "benches"))


@dataclass(frozen=True)
class _Out:
    """What across_checks reads and replaces of an AcrossDiagnosis."""

    status: str
    verdict: str
    steps: tuple[Any, ...] = ()
    notes: tuple[str, ...] = ()


HEAD = "across 3 conditions: unexplained structure remains (tested terms x remove 10 % of the summed excess)"


@pytest.mark.parametrize(
    ("ps", "moved", "weak"),
    [((0.02, 0.5, 0.3), False, True), ((0.02, 0.001, 0.3), False, False), ((0.02, 0.5, 0.3), True, False)],
    ids=["weak", "one-strong", "drifting"],
)
def test_a_weak_remainder_across_is_said_as_diagnose_says_it(
    monkeypatch: pytest.MonkeyPatch, ps: tuple[float, ...], moved: bool, weak: bool
) -> None:
    """Main said "unexplained structure remains" at any failing p. Here, as diagnose: "may remain (p = the
    smallest failing p; a right model is flagged so in ... % of cases)" when every failing condition's p is
    within borderline.FACTOR of alpha and no loop drifts on its plain model; else the words stand."""
    from bouc_wen_id.diagnosis import across_checks, borderline

    groups = [SimpleNamespace(current=p, moved=moved and i == 0) for i, p in enumerate(ps)]
    monkeypatch.setattr(across_checks, "p_of", lambda g, fit: fit)
    out = across_checks.borderline_said(_Out("unexplained", HEAD + "; nothing named"), groups, 0.05)
    fails = [p for p in ps if p < 0.05]
    if weak:
        rate = 1 - 0.95 ** len(ps)
        assert f"may remain (p = {min(fails):.2g}" in out.verdict, out.verdict
        assert f"flagged so in {100 * rate:.3g} % of cases" in out.verdict, out.verdict
        assert borderline.of_headline(out.verdict), out.verdict  # the reading readings.py finds
    else:
        assert out.verdict == HEAD + "; nothing named"


def test_a_hum_at_both_conditions_is_taken_out_across() -> None:
    """test_diagnosis_lines's hum (2 noise sd, 0.05 cycle off a harmonic a period) on both conditions'
    records: diagnose takes it out and says so; main's diagnose_across fitted it. Here the same clause and
    notes."""
    import bouc_wen_id as bw

    gen: Any = importlib.import_module("generator")
    lines_test: Any = importlib.import_module("test_diagnosis_lines")
    p = gen.make_plant(lines_test.SEED, shape="resonant")
    y = gen.run(p, gen.Effect())[0]
    groups = [lines_test._records(p, y, lines_test.HUM_SD, s) for s in (1, 2)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, [0.0, 1.0], candidates=("sensor_lag", "viscous@x", "stiffness"))
    assert "was taken out before the test" in a.verdict, a.verdict
    assert any(n.startswith("0: ") for n in a.notes) and any(n.startswith("1: ") for n in a.notes), a.notes

"""A loop-shape term named from one amplitude per frequency carries the other-family caveat in its headline
(diagnosis/one_amplitude.py, issue 18): on such a design Iwan loops were named "explained by pinching"
alone (studies/outside_design.py), and only a second amplitude separates the two families."""

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
bench: Any = importlib.import_module("diagnosis")


def _exps(pairs: list[tuple[float, float]]) -> list[SimpleNamespace]:
    return [SimpleNamespace(frequency=w, amplitude=a) for w, a in pairs]


def test_the_clause_needs_a_loop_shape_term_and_one_amplitude_per_frequency() -> None:
    pinch = NamedTerm(T.Pinching.kind, "zeta1", 0.05, 0.01, "")
    one = _exps([(3.0, 2.0), (6.0, 2.0), (12.0, 2.02)])  # within REL_TOL: one amplitude
    said = O.text([pinch], one)
    assert O.ONE_AMPLITUDE_MARK in said and "U = 1.01" in said  # half the largest amplitude
    assert O.text([pinch], _exps([(3.0, 2.0), (3.0, 1.0), (6.0, 2.0)])) == ""  # a second amplitude at 3
    # two amplitudes, each at its own frequency: the amplitude law is confounded with frequency, untested
    assert O.ONE_AMPLITUDE_MARK in O.text([pinch], _exps([(3.0, 2.0), (6.0, 1.0)]))
    assert O.text([NamedTerm(T.Viscous.kind, "c", 0.1, 0.01, "")], one) == ""  # not a loop-shape term
    with pytest.raises(ValueError, match="finite"):
        O.untested(_exps([(float("nan"), 1.0)]))


def test_the_headline_carries_it_and_the_bench_scores_it_a_family_reading() -> None:
    coul = NamedTerm(T.Coulomb.at(T.Place.X).kind, "f", 0.003, 0.0005, "")
    said = "explained by: dry (Coulomb) friction across the hysteretic element (on x) f = 0.003 ± 0.0005"
    said += O.text([coul], _exps([(3.0, 2.0), (6.0, 2.0)]))
    rs = readings.of_verdict(said, [coul.term], [])
    head = headline(readings.headlined(said, rs))
    assert O.ONE_AMPLITUDE_MARK in head and "record a second amplitude, e.g. U = 1" in head
    assert any(r.rival and r.instead_of == (coul.term,) for r in rs)
    d = SimpleNamespace(headline=head)
    assert bench._family(d, ["coulomb"], "iwan") and not bench._family(d, ["coulomb"], "rate_width")
    assert not bench._family(SimpleNamespace(headline=headline(said)), ["coulomb"], "iwan")


@pytest.mark.parametrize(("name", "place", "seed"), [("pinching", "", 3901), ("coulomb", "x", 3902)])
def test_an_in_library_loop_shape_term_stays_named_with_the_caveat(
    name: str, place: str, seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bench's own generator (closed-form G, its integrator) on three frequencies at one amplitude."""
    monkeypatch.setattr(gen, "FREQ_FACTORS", (0.5, 1.0, 2.0))
    monkeypatch.setattr(gen, "X_LEVELS", (3.0,))
    case = gen.make_case("library", name, place, 30.0, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
    kinds = [str(k).split("@")[0] for k in d.named_terms]
    assert name in kinds, d.verdict
    assert d.status in ("explained", "partly explained") and O.ONE_AMPLITUDE_MARK in d.headline, d.verdict
    assert "not the only reading" in d.status_text

"""Play's equivalence caveat (diagnosis/caveats.py, issue 18: a name users can trust blind).

A backlash on the measured output dwells exactly as a play on x when every reversal starts from saturation
(the blind bench, benches/blind.py, named play for its output backlash in 4 of 4 cases; no test of the
dwell's shape separated them: session 28). The verdict must say so whenever play is named, and only then.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import caveats as C
from bouc_wen_id.diagnosis.result import NamedTerm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def test_the_caveat_comes_with_play_and_only_with_play() -> None:
    play = NamedTerm(T.Play.kind, "b", 0.01, 0.001, "")
    text = C.family_text([play])
    assert C.PLAY_MARK in text and "output" in text and "below saturation" in text
    assert C.family_text([NamedTerm(T.Viscous.kind, "c", 0.1, 0.01, "")]) == ""
    dahl = NamedTerm(T.Dahl.at(T.Place.X).kind, "fc", 0.05, 0.01, "")
    both = C.family_text([dahl, play])
    assert C.PLAY_MARK in both and C.FAMILY_MARK in both
    assert C.PLAY_MARK not in C.family_text([dahl])
    # Said only when every experiment reverses from saturation: with one below it (latent level 0.6),
    # the separating experiment has been run and the law test judged the play.
    assert C.PLAY_MARK in C.family_text([play], [1.2, 2.5])
    assert C.PLAY_MARK not in C.family_text([play], [0.6, 2.5])
    assert C.PLAY_MARK not in C.family_text([play], [])  # no saturation level at all


def test_a_named_play_carries_the_caveat_in_the_verdict() -> None:
    """The bench's independent generator (its own closed-form G and integrator), play at 30x."""
    import bouc_wen_id as bw

    case = gen.make_case("library", "play", "", 30.0, 33000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
    assert T.Play.kind in d.named_terms, d.verdict
    assert C.PLAY_MARK in d.verdict

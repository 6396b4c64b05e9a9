"""A verdict read in two layers: the headline (what is named, or that nothing is) and its further clauses."""

from __future__ import annotations

import math
from dataclasses import replace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis.report import html_page
from bouc_wen_id.diagnosis.verdict_text import clauses, details, headline

TWO_PI = 2.0 * math.pi


def test_clauses_split_at_top_level_only() -> None:
    v = (
        "unexplained structure remains at harmonics 1, 2 (tested terms offset remove 46 %); not named: "
        "viscous (p = 3e-06): it stands in for physics outside the library (at step 2 the pair step fitted "
        "25 sets and named none; the best, viscous with dahl: law fails [p = 1e-3; 2e-4]); the input is "
        "not a sine"
    )
    got = clauses(v)
    assert len(got) == 3, got
    assert got[0] == headline(v) and got[0].startswith("unexplained structure remains")
    assert "named none; the best" in got[1] and got[1].endswith("2e-4])")
    assert details(v) == got[1:] and got[2] == "the input is not a sine"
    assert "; ".join(got) == v  # nothing of the verdict is lost
    assert clauses("adequate: the plain model is at the noise floor") == [
        "adequate: the plain model is at the noise floor"
    ]


def _recs(seed: int) -> list[bw.Recording]:
    """A first-order G (not the bench's resonant one), a 0.02 output offset, 1 % noise."""
    lin = bw.TransferFunction([1.0], [0.08, 1.0])
    om = np.repeat(TWO_PI * np.array([0.4, 1.2, 3.0]), 2)
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om, np.tile([0.8, 2.0], 3) / g, settle_periods=8, periods=12, samples_per_period=64, substeps=8,
        noise_sd=0.01, seed=seed,
    )  # fmt: skip
    plant = bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5), terms=(T.Offset(0.02),))
    return bw.simulate(plant, plan)


@pytest.fixture(scope="module")
def offset_diagnosis() -> bw.Diagnosis:
    return bw.diagnose(_recs(7))


def test_the_headline_names_the_term_with_its_value(offset_diagnosis: bw.Diagnosis) -> None:
    d = offset_diagnosis
    assert d.named_terms == ("offset",), d.verdict
    assert d.headline.startswith("explained by: output offset") and "±" in d.headline
    assert d.headline == clauses(d.verdict)[0] and d.details == tuple(clauses(d.verdict)[1:])


def test_summary_and_page_give_the_headline_first_then_one_clause_per_line(
    offset_diagnosis: bw.Diagnosis,
) -> None:
    verdict = (
        f"{offset_diagnosis.headline}; the experiments cannot tell apart: output offset or asymmetry "
        "(alternatives; each with the experiment that would separate them); a note on the data"
    )
    d = replace(offset_diagnosis, verdict=verdict)
    lines = d.summary().splitlines()
    assert lines[0] == f"Diagnosis: {d.headline}"
    assert lines[1] == "  - the experiments cannot tell apart: output offset or asymmetry " + (
        "(alternatives; each with the experiment that would separate them)"
    )
    assert lines[2] == "  - a note on the data" and lines[3] == ""
    page = html_page(d, {})
    head = page.index("class='verdict'")
    assert head < page.index("<li>the experiments cannot tell apart") < page.index("<h1>Diagnosis</h1>")
    assert page.count("<li>a note on the data</li>") == 1

"""What a reader of the diagnosis report meets (issue 19): the identified model and identify's warnings after
the verdict, figures with units and named bars, a "periods" column that counts periods, words that follow
the sign of a trend."""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.locate import trend_phrase
from bouc_wen_id.diagnosis.report import (
    FIGURES,
    figure,
    html_page,
    identify_plain,
    whole_periods,
    write_report,
)


@pytest.fixture(scope="module")
def case() -> tuple[list[Any], bw.Diagnosis]:
    """Three experiments of a first-order G with a delay hiding a dashpot (seeded)."""
    plant = bw.WienerPlant(
        bw.TransferFunction([8.0], [1.0, 8.0], delay=0.02),
        bw.BoucWen(beta=1.0, gamma=0.4, mu=1.4, alpha=1.2),
        terms=(bw.terms.Viscous(0.03),),
    )
    plan = bw.SinePlan(
        frequencies=[1.5, 4.0, 9.0],
        amplitudes=1.0,
        settle_periods=8,
        periods=10,
        samples_per_period=128,
        noise_sd=0.004,
        seed=11,
    )
    recs = bw.simulate(plant, plan)
    return recs, bw.diagnose(recs, y_unit="N", u_unit="mm")


# --------------------------------------------------------------------------------------------------
# Words that follow the sign
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("exponent", [-2.3, -0.7, -0.51, 0.51, 0.7, 1.0, 2.0])
def test_the_trend_phrase_follows_the_sign_of_the_exponent(exponent: float) -> None:
    phrase = trend_phrase(exponent)
    assert f"omega^{exponent:.1f}" in phrase
    if exponent < 0:
        assert "shrinking" in phrase and "growing" not in phrase
    else:
        assert "growing" in phrase and "shrinking" not in phrase


def test_a_misfit_that_falls_with_frequency_is_not_called_growing(
    case: tuple[list[Any], bw.Diagnosis],
) -> None:
    _, d = case
    # 'growing as omega^-0.7' read as the opposite of what it meant (issue 19).
    falling = replace(d.before, frequency_exponent=-0.7).describe()
    rising = replace(d.before, frequency_exponent=0.7).describe()
    assert "shrinking with frequency (as omega^-0.7)" in falling and "growing" not in falling
    assert "growing with frequency (as omega^0.7)" in rising
    flat = replace(d.before, frequency_exponent=0.2).describe()
    assert "omega^" not in flat


# --------------------------------------------------------------------------------------------------
# The identified model and identify's warnings, after the verdict
# --------------------------------------------------------------------------------------------------


def _text(page: str) -> str:
    return re.sub(r"<[^>]+>", " ", page)


def test_the_page_shows_identifys_model_with_intervals_after_the_verdict(
    case: tuple[list[Any], bw.Diagnosis],
) -> None:
    recs, d = case
    identified, notes = identify_plain(recs)
    assert isinstance(identified, bw.IdentificationResult)
    page = html_page(d, {}, identified, notes)
    at_verdict = page.index("class='verdict'")
    at_model = page.index("<h2>Identified model</h2>")
    at_terms = page.index("<h2>Held-out proof</h2>")
    assert at_verdict < at_model < at_terms
    section = page[at_model:at_terms]
    for name in ("beta", "gamma", "mu"):
        lo, hi = identified.interval(name)
        assert f"<td>{name}</td><td>{getattr(identified, name):.5g}</td>" in section
        assert f"[{lo:.4g}, {hi:.4g}]" in section
    # Every experiment's |G| with its interval; the phase lag in degrees, as identify estimated it.
    for e in identified.experiments:
        assert f"<td>{e.source}</td>" in section and f"<td>{e.gain:.5g}</td>" in section
        assert e.gain_se is not None
        lag = float(np.degrees(e.phase))
        shown = [float(v) for v in re.findall(r"<td>(-?[\d.]+(?:e[-+]\d+)?)</td><td>± ", section)]
        assert any(abs(((v - lag + 180) % 360) - 180) < 1e-3 * max(1.0, abs(lag)) for v in shown), (
            lag,
            shown,
        )
    # The warnings identify raised are all there, by name (the plain model misses the dashpot).
    for note in notes:
        assert note.split(": ", 1)[-1][:60] in _text(page).replace("&#x27;", "'").replace("&quot;", '"')


def test_the_warnings_come_from_identify_itself(case: tuple[list[Any], bw.Diagnosis]) -> None:
    recs, _ = case
    # settle_periods=0 keeps the start-up transient: identify warns (TransientWarning), and the page says so.
    raw = [bw.Recording(r.t, r.u, r.y, r.amplitude, r.frequency, settle_periods=0) for r in recs]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bw.identify(raw)
    assert any(issubclass(w.category, bw.errors.TransientWarning) for w in caught)
    identified, notes = identify_plain(raw)
    assert any(n.startswith("TransientWarning: ") for n in notes), notes
    assert len(notes) == len(set(notes))
    page = html_page(bw.diagnose(recs), {}, identified, notes)
    assert "Warnings raised by identify" in page and "TransientWarning" in page


def test_a_refusal_of_identify_is_shown_not_raised(case: tuple[list[Any], bw.Diagnosis]) -> None:
    recs, d = case
    refused, notes = identify_plain(recs, method="no such method")
    assert isinstance(refused, bw.errors.InvalidParameterError)
    page = html_page(d, {}, refused, notes)
    assert "identify refused these data: InvalidParameterError" in page
    assert page.index("class='verdict'") < page.index("identify refused")


def test_without_identify_the_page_has_no_empty_section(case: tuple[list[Any], bw.Diagnosis]) -> None:
    _, d = case
    assert "Identified model" not in html_page(d, {})


# --------------------------------------------------------------------------------------------------
# The experiments table: periods are periods
# --------------------------------------------------------------------------------------------------


def test_the_periods_column_counts_the_periods_of_a_recording(case: tuple[list[Any], bw.Diagnosis]) -> None:
    recs, d = case
    for r, e in zip(recs, d.experiments):
        assert whole_periods(e) == r.whole_periods - r.settle_periods == 10


def test_the_periods_column_counts_the_periods_of_a_lab_record_not_samples_per_point() -> None:
    """A lab record made with NumPy alone (1 kHz, 2.37 Hz: not a whole number of samples per period)."""
    rng = np.random.default_rng(5)
    fs, f, periods = 1000.0, 2.37, 24
    t = np.arange(int(periods / f * fs)) / fs
    u = 3.0 * np.cos(2 * np.pi * f * t)
    y = 40.0 * np.tanh(np.cos(2 * np.pi * f * t - 0.4)) + 0.2 * rng.standard_normal(t.size)
    m = bw.Measurement(t, u, y, nominal_frequency=2 * np.pi * f, units={"u": "mm", "y": "N"})
    (e,) = prepare([m])
    n = whole_periods(e)
    assert periods - 3 <= n <= periods, n
    # What the column showed before: the samples averaged into each point of the averaged period.
    assert e.periods == pytest.approx(fs / f * n / e.samples_per_period, rel=0.15)
    # (the lab path now averages every harmonic below Nyquist, so the weight is near the period count, but
    # not equal: showing it would still put the column outside [periods - 3, periods])
    assert abs(e.periods - n) > 1


# --------------------------------------------------------------------------------------------------
# Figures: units on every axis, legends off the data, bars named
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(FIGURES))
def test_every_figure_labels_its_axes_with_units(case: tuple[list[Any], bw.Diagnosis], name: str) -> None:
    _, d = case
    fig = figure(d, name, u_unit="mm", y_unit="N")
    ax = fig.axes[0]
    x, y = ax.get_xlabel(), ax.get_ylabel()
    assert x and y
    units = {
        "residual_cycle": ("(deg)", "(N)"),
        "loops": ("(mm)", "(N)"),
        "harmonics": ("harmonic", "ratio"),
        "held_out": ("held-out experiment", "ratio"),
    }[name]
    assert units[0] in x and units[1] in y, (x, y)
    # The legend sits right of the axes, not over the data.
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()  # type: ignore[no-untyped-call]
    legend = ax.get_legend()
    assert legend is not None
    r = canvas.get_renderer()  # type: ignore[no-untyped-call]
    assert legend.get_window_extent(r).x0 >= ax.get_window_extent(r).x1


def test_figures_without_units_say_so(case: tuple[list[Any], bw.Diagnosis]) -> None:
    _, d = case
    ax = figure(d, "loops").axes[0]
    assert ax.get_xlabel().endswith("(units of the data)") and ax.get_ylabel().endswith("(units of the data)")


def test_held_out_bars_are_named_by_their_experiment(case: tuple[list[Any], bw.Diagnosis]) -> None:
    recs, d = case
    assert d.held_out is not None
    ax = figure(d, "held_out").axes[0]
    names = [t.get_text() for t in ax.get_xticklabels()]
    assert names == [d.experiments[j].source for j in d.held_out.folds]
    assert names == [r.metadata.get("name", f"recording {i}") for i, r in enumerate(recs)]


def test_the_written_report_holds_everything(case: tuple[list[Any], bw.Diagnosis], tmp_path: Path) -> None:
    recs, d = case
    identified, notes = identify_plain(recs)
    written = write_report(d, tmp_path, identified=identified, identify_warnings=notes, u_unit="mm")
    assert [p.name for p in written][0] == "diagnosis.json" and written[-1].name == "report.html"
    page = written[-1].read_text()
    assert page.count("<img ") == len(FIGURES) and "Identified model" in page
    assert isinstance(identified, bw.IdentificationResult) and math.isfinite(identified.beta)

"""fit_time_domain's sine-path starts and Diagnosis.to_model (reviewer 35, problem 1).

The recordings are made here, apart from the library's simulator: ``solve_ivp`` (DOP853) on a first-order G
with a pure delay (the input's analytic cosine, switched on at t = 0: G sees it from t = tau), Bouc-Wen on
G's output, a viscous term on the measured input with the analytic derivative, white noise from a seed.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.result import NamedTerm
from bouc_wen_id.diagnosis.to_model import diagnosis_model
from bouc_wen_id.errors import NotConvergedError
from bouc_wen_id.terms import Viscous
from bouc_wen_id.timedomain import _fit
from bouc_wen_id.timedomain._records import settling_lead_in
from bouc_wen_id.timedomain._starts import unusable
from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

#: First-order G with a delay (a: pole, b: gain numerator, tau: delay), Bouc-Wen, the viscous term on u.
A, B, TAU = 4.0, 4.0, 0.05
BETA, GAMMA, MU = 1.0, 0.3, 1.5
C_U = 0.01
NOISE = 0.01
P, SETTLE, PERIODS = 64, 8, 8


def _record(omega: float, amp: float, rng: np.random.Generator, cut: int = 0) -> bw.Recording:
    """One sine recording; ``cut`` whole periods of the run dropped before its first sample (a record that
    does not start from rest)."""

    def rhs(t: float, s: np.ndarray) -> list[float]:
        v = amp * math.cos(omega * (t - TAU)) if t >= TAU else 0.0
        xdot = -A * s[0] + B * v
        w = s[1]
        wdot = xdot - BETA * abs(xdot) * abs(w) ** (MU - 1.0) * w - GAMMA * xdot * abs(w) ** MU
        return [xdot, wdot]

    period = 2.0 * math.pi / omega
    t = np.arange((SETTLE + PERIODS + cut) * P) * period / P
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12)
    u = amp * np.cos(omega * t)
    y = sol.y[1] - C_U * amp * omega * np.sin(omega * t) + NOISE * rng.standard_normal(t.size)
    t, u, y = t[: t.size - cut * P], u[cut * P :], y[cut * P :]
    return bw.Recording(t, u, y, amplitude=amp, frequency=omega, settle_periods=SETTLE)


def _records(design: list[tuple[float, float]], seed: int) -> list[bw.Recording]:
    rng = np.random.default_rng(seed)
    return [_record(w, a, rng) for w, a in design]


ONE_AMPLITUDE = [(1.0, 1.0), (2.0, 1.0), (3.5, 1.0), (5.0, 1.0), (7.0, 1.0)]
TWO_AMPLITUDES = [(w, a) for a in (1.0, 0.5) for w in (1.5, 3.0, 6.0)]


def _check_model(fit: bw.TimeDomainFit) -> None:
    """The fitted G's pole, gain and delay and the viscous value near the truth, residuals at the noise."""
    c = next(t.value for t in fit.plant.terms if isinstance(t, Viscous))
    assert abs(c - C_U) < 4.0 * fit.standard_errors["c"] + 0.05 * C_U
    g = fit.plant.linear
    assert abs(g(0.0) - B / A) < 0.05 * B / A  # static gain
    assert abs(g(1j * 3.0) - B / (3j + A) * np.exp(-3j * TAU)) < 0.03 * abs(B / (3j + A))
    assert fit.rmse < 1.1 * NOISE


@pytest.mark.parametrize("design", [ONE_AMPLITUDE, TWO_AMPLITUDES], ids=["one_amplitude", "two_amplitudes"])
def test_fit_time_domain_with_the_diagnosed_term_on_its_recordings(design: list[tuple[float, float]]) -> None:
    """On main: the selected start G was too fast to simulate ("no start could be simulated"), or two
    amplitudes of one frequency were refused as duplicate frequencies."""
    recs = _records(design, 35)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain(recs, terms=["viscous"], lead_in=settling_lead_in(recs))
    _check_model(fit)


def test_a_start_too_fast_for_the_step_or_not_stable_is_named() -> None:
    recs = [bw.TimeRecord(np.arange(100) * 0.05, np.zeros(100), np.zeros(100))]
    fast = bw.TransferFunction([300.0], [1.0, 300.0])
    why = unusable(fast, recs, 2)
    assert why is not None and "too fast" in why
    assert unusable(bw.TransferFunction([4.0], [1.0, 4.0]), recs, 2) is None


def test_a_fit_ending_with_a_pole_at_the_origin_blames_the_fit(monkeypatch: pytest.MonkeyPatch) -> None:
    """On main the result's G with ``a_n`` on its bound 0 raised UnstableSystemError about the user's G."""
    recs = _records(ONE_AMPLITUDE[:3], 1)
    real = _fit._search

    def to_the_origin(problem, starts, *args):  # type: ignore[no-untyped-def]
        (theta, run), tried = real(problem, starts[:1], 1, *args[1:])
        theta = theta.copy()
        theta[problem.structure.m + problem.structure.n] = 0.0  # a_n on its bound
        return (theta, run), tried

    monkeypatch.setattr(_fit, "_search", to_the_origin)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(NotConvergedError, match="not asymptotically stable from every start"):
            bw.fit_time_domain(recs, terms=["viscous"])


def _diagnosis(value: float, se: float) -> SimpleNamespace:
    return SimpleNamespace(named=(NamedTerm(Viscous.kind, "c", value, se, "s"),), structure=None)


def test_to_model_fits_the_named_term_from_its_diagnosed_value(tmp_path: Path) -> None:
    recs = _records(ONE_AMPLITUDE, 7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = diagnosis_model(_diagnosis(1.2 * C_U, 0.1 * C_U), recs)  # type: ignore[arg-type]
    _check_model(fit)
    assert not fit.adequacy.rejects(0.01)
    bw.save_model(fit, tmp_path / "m.json")
    assert bw.load_model(tmp_path / "m.json").to_dict() == fit.plant.to_dict()
    with pytest.raises(bw.errors.InvalidParameterError, match="named terms"):
        diagnosis_model(_diagnosis(C_U, 0.1), recs, terms=["viscous"])  # type: ignore[arg-type]
    with pytest.raises(bw.errors.InvalidParameterError, match="recordings\\[0\\] is a str"):
        diagnosis_model(_diagnosis(C_U, 0.1), ["m.csv"])  # type: ignore[arg-type]


def test_to_model_fits_lab_measurements_as_recorded() -> None:
    """Review 36b: ``diagnose FILES --model`` on lab CSV files refused the Measurements (and lost the
    report). A Measurement is a raw record from its first sample: fitted as such, from the plain model's
    identification as its start (what the CLI passes)."""
    recs = _records(ONE_AMPLITUDE, 7)
    meas = [bw.Measurement(r.t, r.u, r.y, name=f"m{i}") for i, r in enumerate(recs)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = diagnosis_model(_diagnosis(1.2 * C_U, 0.1 * C_U), meas, start=bw.identify(recs))  # type: ignore[arg-type]
    c, se = fit.value("c"), fit.standard_errors["c"]
    assert abs(c - C_U) < 4 * se, (c, se)
    assert fit.lead_in == (0,) * len(meas)  # from the first sample, as recorded


def test_cli_keeps_the_report_when_the_model_cannot_be_fitted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from bouc_wen_id import cli

    recs = _records(ONE_AMPLITUDE, 11)
    bw.save(tmp_path / "csv", recs)

    def refuse(*_: object) -> Path:
        raise bw.errors.NotConvergedError("no start converged")

    monkeypatch.setattr(cli, "_diagnosed_model", refuse)
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = cli.main(
            ["diagnose", str(tmp_path / "csv"), "--out", str(out), "--no-figures", "--no-held-out", "--model"]
        )
    assert rc == 1
    assert (out / "diagnosis.json").exists() and (out / "report.html").exists()
    assert "model.json not written (NotConvergedError: no start converged)" in capsys.readouterr().err


def test_cli_diagnose_model_writes_a_model_export_takes(tmp_path: Path) -> None:
    recs = _records(ONE_AMPLITUDE, 11)
    bw.save(tmp_path / "csv", recs)
    out = tmp_path / "out"
    run = subprocess.run(
        [sys.executable, "-m", "bouc_wen_id", "diagnose", str(tmp_path / "csv"), "--out", str(out)]
        + ["--no-figures", "--no-held-out", "--model"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    doc = json.loads((out / "model.json").read_text(encoding="utf-8"))
    plant = bw.load_model(out / "model.json")
    named = json.loads((out / "diagnosis.json").read_text(encoding="utf-8"))["named"]
    assert [t.kind for t in plant.terms] == [t["term"] for t in named] and doc[
        "format"
    ] == "bouc_wen_id.model"
    exp = subprocess.run(
        [sys.executable, "-m", "bouc_wen_id", "export", str(out / "diagnosis.json"), "--to", "json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert exp.returncode != 0 and "--model" in exp.stderr


def test_a_record_not_starting_from_rest_is_said_and_the_settling_lead_in_fits_it() -> None:
    """Records cut from a running test: fitted from their first sample the residuals are not white and the
    fit says the declared settling is among them (on main: silent); left out, the model is right."""
    rng = np.random.default_rng(5)
    recs = [_record(w, a, rng, cut=3) for w, a in ONE_AMPLITUDE]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = bw.fit_time_domain(recs, terms=["viscous"])
        fit = bw.fit_time_domain(recs, terms=["viscous"], lead_in=settling_lead_in(recs))
    assert plain.adequacy.rejects(0.01) and any("lead_in=" in w for w in plain.warnings)
    _check_model(fit)
    assert not any("lead_in=" in w for w in fit.warnings)

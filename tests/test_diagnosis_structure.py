"""The diagnosis' structural candidate: Bouc-Wen in feedback, not a cascade (diagnosis/structure.py).

The feedback data come from the diagnosis bench's own generator (benches/generator.py: its own RK4 of
``m y'' + c y' + k y + z = u``, its own noise), not from the library's periodic solver; the cascade data from
the library's simulator (test_diagnosis's plant) and from the generator.
"""

from __future__ import annotations

import importlib
import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import bouc_wen_id.diagnosis.structure as S
import numpy as np
import pytest
from bouc_wen_id.diagnosis.data import DiagExperiment

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
#: The bench's generator, a script beside the package (not an installed module).
gen: Any = importlib.import_module("generator")


def _diagnose(recs: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


@pytest.fixture(scope="module")
def feedback_case() -> Any:
    return gen.make_case("structure", "feedback", "", 10.0, 5000)


@pytest.fixture(scope="module")
def feedback_diagnosis(feedback_case: Any) -> Any:
    return _diagnose(feedback_case.recordings)


def test_feedback_data_name_the_structure_in_words(feedback_diagnosis: Any) -> None:
    d = feedback_diagnosis
    st = d.structure
    assert st is not None and st.tested and st.named
    assert d.status == "explained"
    assert "acts back on the dynamics" in d.verdict and "not a cascade" in d.verdict
    # Its evidence: the cascade's gains move with amplitude, the feedback fits where the cascade fails,
    # wins the information criterion and predicts every left-out experiment better in sum.
    assert st.gain_p < 0.05 and st.gain_ratio > 1.05
    assert d.plain.p_value < 0.05 and st.p_value >= 0.05 / S.ADEQUACY_DIVISOR
    assert st.aic < st.aic_rival - S.AIC_MARGIN
    assert st.held_out is not None and st.held_out.improves and len(st.held_out.folds) >= 2
    assert d.final.p_value == st.p_value and d.final.terms == ()
    js = json.loads(d.to_json())
    assert js["structure"]["named"] and js["structure"]["structure"] == "feedback"
    assert "feedback structure:" in d.summary()


def test_feedback_parameters_match_the_generator(feedback_case: Any, feedback_diagnosis: Any) -> None:
    p = gen.make_plant(feedback_case.seed)
    centre = float(np.median(p.omegas))
    m = 2.0 / centre**2  # the generator: k + 1 = m omega_c^2 with k = 1, alpha = 1
    c = 2 * 0.2 * math.sqrt(2.0 * m)
    truth = {"m": m, "c": c, "k": 1.0, "alpha": 1.0, "beta_gamma": p.beta, "beta_delta": p.gamma, "nu": p.mu}
    for name, value, se in feedback_diagnosis.structure.parameters:
        assert abs(value - truth[name]) <= 5.0 * se + 1e-3 * abs(truth[name]), (name, value, se, truth[name])


def test_one_amplitude_per_frequency_cannot_be_tested(feedback_case: Any) -> None:
    recs = feedback_case.recordings[::2]  # the generator's plan: two amplitudes per frequency, in pairs
    d = _diagnose(recs)
    assert d.structure is not None and not d.structure.tested and not d.structure.named
    assert "cannot be tested" in d.structure.reason and d.status != "explained"
    assert any("cannot be tested" in n for n in d.notes)


def test_cascade_data_never_try_it() -> None:
    """A plain cascade, two amplitudes per frequency (so the candidate could be tried): it is not."""
    om = np.repeat(2 * np.pi * np.array([0.5, 1.5, 4.0]), 2)
    lin = bw.TransferFunction([1.0], [0.05, 1.0])
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om,
        np.tile([0.8, 2.0], 3) / g,
        settle_periods=8,
        periods=12,
        samples_per_period=64,
        substeps=8,
        noise_sd=0.01,
        seed=3,
    )
    d = _diagnose(bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.7, 0.3, 1.8)), plan))
    assert d.status == "adequate" and d.structure is None


def test_cascade_with_a_library_term_is_not_called_feedback() -> None:
    case = gen.make_case("library", "coulomb", "u", 30.0, 3)
    d = _diagnose(case.recordings)
    assert not (d.structure is not None and d.structure.named)
    assert "coulomb" in d.named_terms


def _exp(ybar: np.ndarray, phase: float, freq: float = 3.0, amp: float = 1.0) -> DiagExperiment:
    z = np.zeros(1)
    return DiagExperiment(freq, amp, phase, ybar, 8.0, 1.0, 1.0, 10, z, z.astype(complex), "e")


def test_alignment_is_a_fourier_shift_and_its_inverse() -> None:
    p, phase = 64, 0.7
    theta = 2 * np.pi * np.arange(p) / p
    ybar = np.cos(theta + phase) + 0.3 * np.sin(3 * (theta + phase)) + 0.1
    e = _exp(ybar, phase)
    np.testing.assert_allclose(S.aligned(e), np.cos(theta) + 0.3 * np.sin(3 * theta) + 0.1, atol=1e-12)
    np.testing.assert_allclose(S.on_grid(e, S.aligned(e)), ybar, atol=1e-12)


def test_amplitude_groups_and_gain_test() -> None:
    y = np.zeros(8)
    exps = [_exp(y, 0.0, 3.0, 1.0), _exp(y, 0.0, 3.0, 2.0), _exp(y, 0.0, 5.0, 1.0), _exp(y, 0.0, 5.0, 1.0)]
    assert S.amplitude_groups(exps) == [[0, 1]]  # equal amplitudes at 5: no group
    cov = np.eye(4) * 1e-4
    p_same, r_same = S.gain_test([[0, 1]], np.array([2.0, 2.001, 1.0, 1.0]), cov, 1.0)
    p_diff, r_diff = S.gain_test([[0, 1]], np.array([2.0, 2.2, 1.0, 1.0]), cov, 1.0)
    assert p_same > 0.5 and p_diff < 1e-6 and r_diff == pytest.approx(1.1)
    # A misfit inflates the covariance: the same gap is no longer significant at chi2/dof = 1e4.
    assert S.gain_test([[0, 1]], np.array([2.0, 2.2, 1.0, 1.0]), cov, 1e4)[0] > 0.05
    assert math.isnan(S.gain_test([], np.ones(4), cov, 1.0)[0])


def test_report_of_a_named_structure_is_written(feedback_diagnosis: Any, tmp_path: Path) -> None:
    from bouc_wen_id.diagnosis.report import write_report

    write_report(feedback_diagnosis, tmp_path / "diag")
    js = json.loads((tmp_path / "diag" / "diagnosis.json").read_text())
    assert js["status"] == "explained" and js["structure"]["named"]
    assert "acts back on the dynamics" in (tmp_path / "diag" / "report.html").read_text()


def test_one_frequency_cannot_be_tested_and_gives_no_fitter_advice(feedback_case: Any) -> None:
    """Review 45: a one-frequency design read "could not be fitted (...; give theta0)", advice for an
    argument diagnose does not have."""
    recs = feedback_case.recordings[:2]  # the generator's first frequency, at its two amplitudes
    assert len({r.frequency for r in recs}) == 1 and len({r.amplitude for r in recs}) == 2
    d = _diagnose(recs)
    assert d.structure is not None and not d.structure.tested and not d.structure.named
    assert d.structure.reason == S.ONE_FREQUENCY
    assert not any("theta0" in n for n in d.notes) and "theta0" not in d.summary()

"""The distortion term (design.md 9.5): a measured, non-sinusoidal input drives the model.

Pins the path loop along a measured waveform (Rust against the NumPy reference, the Jacobian against
central differences, lambda = 0 against the sine path), the augmented output with a waveform, the extraction
of the input's harmonics, and the selection on small seeded cases.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.diagnosis.data import input_waveform
from bouc_wen_id.errors import InvalidParameterError, ZeroAmplitudeError
from bouc_wen_id.reference import augmented as RA
from bouc_wen_id.reference.path_loop import path_loop_distorted as ref_path_loop_distorted

# [A, beta, gamma, mu, delta, b, phi, lambda] of mildly distorted loops (one maximum per period).
CASES = [
    (1.4, 0.7, 0.25, 1.8, 0.2, 0.15, 0.9, 1.0),
    (-1.1, 0.9, -0.3, 2.5, -0.35, 0.3, 2.0, 0.7),
    (2.0, 0.6, 0.4, 1.5, 0.0, 0.0, -1.0, 1.3),
]


def _harmonics(seed: int, k: int = 3, size: float = 0.05) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return size * rng.uniform(-1.0, 1.0, 2 * k)


@pytest.mark.parametrize("case", range(len(CASES)))
def test_core_matches_reference_and_central_differences(case: int) -> None:
    a, beta, gamma, mu, delta, b, phi, lam = CASES[case]
    h = _harmonics(case)
    p, sub = 32, 3
    w, jac, _ = _core.path_loop_distorted(a, beta, gamma, mu, delta, b, phi, lam, h, p, sub)
    wr, jr, _ = ref_path_loop_distorted(a, beta, gamma, mu, delta, b, phi, lam, h, p, sub)
    # The same discrete map; the two shootings stop within 1e-13 w_b of the same fixed point (divided by
    # 1 - Phi for the sensitivities), so 1e-9 leaves a wide margin while a wrong node or term (O(1e-2)) fails.
    assert np.max(np.abs(w - wr)) < 1e-9
    assert np.max(np.abs(jac - jr)) < 1e-8
    assert jac.shape == (p, 8)
    q = np.array([beta, gamma, mu, a, phi, delta, b, lam])

    def run(v: np.ndarray) -> np.ndarray:
        return _core.path_loop_distorted(v[3], v[0], v[1], v[2], v[5], v[6], v[4], v[7], h, p, sub)[0]

    for k in range(8):
        if k == 6 and b == 0.0:
            continue  # the play cannot go below 0
        step = 1e-5 * max(1.0, abs(q[k]))
        up, dn = q.copy(), q.copy()
        up[k] += step
        dn[k] -= step
        fd = (run(up) - run(dn)) / (2.0 * step)
        # Central differences of the same discrete map: truncation ~1e-10 plus the shooting tolerance over
        # 2 h (~1e-8); a missing chain-rule term is O(1).
        assert np.max(np.abs(fd - jac[:, k]) / (1.0 + np.abs(fd))) < 1e-6, k


def test_lambda_zero_is_the_sine_path() -> None:
    h = _harmonics(7)
    for a in (1.3, -0.8):
        w0, j0, _ = _core.path_loop_distorted(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, 0.0, h, 40, 3)
        ws, js, _ = _core.path_loop(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, 40, 3)
        # Reversals found by Newton to rounding: the same segments up to ~1e-15.
        assert np.max(np.abs(w0 - ws)) < 1e-12
        assert np.max(np.abs(j0[:, :7] - js)) < 1e-11
        # ... while the distortion's own column is not zero (the term is testable at lambda = 0).
        assert np.max(np.abs(j0[:, 7])) > 1e-3


def test_bad_waveforms_are_named_errors() -> None:
    strong = np.array([0.0, 0.0, 0.5, 0.0])  # harmonic 3 at half the fundamental: six reversals
    with pytest.raises(InvalidParameterError, match="reversals"):
        _core.path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 0.0, 0.0, 1.0, strong, 40, 3)
    with pytest.raises(InvalidParameterError, match="reversals"):
        ref_path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 0.0, 0.0, 1.0, strong, 40, 3)
    with pytest.raises(InvalidParameterError, match="pairs"):
        _core.path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 0.0, 0.0, 1.0, np.array([0.1]), 40, 3)
    with pytest.raises(ZeroAmplitudeError):
        _core.path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 1.2, 0.0, 1.0, _harmonics(1), 40, 3)


def test_augmented_output_with_a_waveform_matches_reference() -> None:
    h = _harmonics(3)
    shared = np.array([0.8, 0.1, 1.7, 0.05, 0.9])  # beta, gamma, mu, viscous c, lambda
    args = (48, 1.2, 3.0, 0.3, ["viscous", "distortion"], shared, 0.9, 0.6, 3)
    y, js, jo = _core.augmented_output(*args, h)
    yr, jsr, jor = RA.augmented_output(*args, h)
    # Same discrete model on both sides (see the path-loop test): agreement to the shooting tolerance.
    assert np.max(np.abs(y - yr)) < 1e-9
    assert np.max(np.abs(js - jsr)) < 1e-8 and np.max(np.abs(jo - jor)) < 1e-8
    step = 1e-6
    up, dn = shared.copy(), shared.copy()
    up[4] += step
    dn[4] -= step
    fd = (
        _core.augmented_output(*args[:5], up, *args[6:], h)[0]
        - _core.augmented_output(*args[:5], dn, *args[6:], h)[0]
    ) / (2 * step)
    assert np.max(np.abs(fd - js[:, 4])) < 1e-6
    # Without a waveform the term does nothing: its column is 0.
    _, js0, _ = _core.augmented_output(*args)
    assert np.all(js0[:, 4] == 0.0)


def test_input_waveform_recovers_harmonics_and_ignores_a_pure_sine() -> None:
    p, n = 64, 12
    z = 2 * np.pi * np.arange(p) / p + 0.7
    c = {2: 0.03 * np.exp(1j * 0.4), 3: 0.05 * np.exp(-1j * 1.1)}
    u = 2.0 * (np.cos(z) + sum((ck * np.exp(1j * k * z)).real for k, ck in c.items()))
    rng = np.random.default_rng(0)
    rows = np.tile(u, (n, 1)) + rng.normal(0.0, 1e-3, (n, p))
    wf = input_waveform(rows)
    got = wf[0::2] + 1j * wf[1::2]
    # Averaged noise 1e-3/sqrt(12) per sample: each normalised coefficient within ~1e-4 of the truth.
    assert np.allclose(got[:2], [c[2], c[3]], atol=5e-4)
    assert np.all(np.abs(got[2:]) < 5e-4)
    pure = np.tile(2.0 * np.cos(z), (n, 1)) + rng.normal(0.0, 1e-3, (n, p))
    assert input_waveform(pure).size == 0


def _recordings(distortion: float, seed: int, low_clean: bool = False, only: int = -1) -> list[bw.Recording]:
    """A first-order G and a saturating Bouc-Wen at three frequencies and two amplitudes, driven by an input
    with harmonics 2 and 3 of relative size ``distortion`` (simulated in the time domain, sampled input);
    ``low_clean``: the low amplitude's inputs are pure sines (an actuator that distorts only at its top);
    ``only`` (0..5): that recording's input alone is distorted."""
    lin = bw.TransferFunction([1.0], [0.05, 1.0])
    plant = bw.WienerPlant(lin, bw.BoucWen(beta=0.7, gamma=0.3, mu=1.8))
    rng = np.random.default_rng(seed)
    p, settle, periods = 64, 6, 12
    recs: list[bw.Recording] = []
    for f in (0.5, 1.0, 2.0):
        om = 2 * np.pi * f
        for amp in (0.8, 2.0):
            t = np.arange((settle + periods) * p) * (2 * np.pi / om / p)
            th = om * t
            dist = 0.0 if (low_clean and amp < 1.0) or only not in (-1, len(recs)) else distortion
            u = amp * (np.cos(th) + dist * (0.5 * np.cos(2 * th + 0.3) + np.cos(3 * th - 1.0)))
            _, w = bw.simulate_input(plant, t, u, substeps=8)
            y = w + rng.normal(0.0, 0.01, t.size)
            recs.append(bw.Recording(t, u, y, amp, om, settle_periods=settle))
    return recs


def test_diagnose_names_a_distorted_input_and_skips_pure_sines() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_recordings(0.04, 1), candidates=["offset", "stiffness", "asymmetry", "distortion"])
        assert "distortion" in d.named_terms
        lam = next(t for t in d.named if t.term == "distortion")
        # The true G is carried at the harmonics' own frequencies: lambda near 1.
        assert abs(lam.value - 1.0) < 0.1 + 3 * lam.standard_error
        plain = bw.diagnose(_recordings(0.0, 2), candidates=["offset", "distortion"])
    assert "distortion" not in plain.settings["candidates"]
    assert "pure sine" in plain.settings["skipped"]["distortion"]
    assert not math.isnan(plain.explained_fraction)


def test_simulate_refuses_a_plant_with_the_distortion_term() -> None:
    from bouc_wen_id.terms import Distortion

    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.05, 1.0]), bw.BoucWen(0.7, 0.3, 1.8), terms=(Distortion(1.0),)
    )
    plan = bw.SinePlan([1.0], [1.0], settle_periods=1, periods=2, samples_per_period=16, substeps=2)
    with pytest.raises(InvalidParameterError, match="distorted input itself"):
        bw.simulate(plant, plan)


def test_the_loop_does_not_depend_on_the_sign_convention_of_the_gain() -> None:
    # (A, phi) and (-A, phi + pi) are one latent sine; with a waveform they must stay one x (the even
    # harmonics would flip otherwise), so the loop is the same up to the shooting tolerance.
    h = _harmonics(11)
    w1, j1, _ = _core.path_loop_distorted(1.2, 0.7, 0.25, 1.8, 0.1, 0.05, 0.3, 1.0, h, 40, 3)
    w2, j2, _ = _core.path_loop_distorted(-1.2, 0.7, 0.25, 1.8, 0.1, 0.05, 0.3 + np.pi, 1.0, h, 40, 3)
    assert np.max(np.abs(w1 - w2)) < 1e-9
    assert np.max(np.abs(j1[:, 3] + j2[:, 3])) < 1e-8  # d/dA flips with the sign of A


def test_fopdt_for_the_harmonics_holds_the_dc_lag_at_half_turns() -> None:
    from bouc_wen_id.diagnosis.fitting import _fopdt

    freqs = 2 * np.pi * np.array([0.5, 1.0, 2.0, 4.0])
    tc, delay = 0.0878, 0.0121
    logs = math.log(2.0) - 0.5 * np.log1p((freqs * tc) ** 2)
    lag = np.arctan(freqs * tc) + freqs * delay
    # Exact points: the corner is refined off its grid (400 points over 6 decades, 3.5 % apart).
    got = _fopdt(freqs, logs, lag)
    assert got is not None
    assert got[3] == 0.0 and abs(got[1] / tc - 1) < 1e-6 and abs(got[2] / delay - 1) < 1e-6
    # An inverting path: half a turn at DC, held there.
    inv = _fopdt(freqs, logs, lag + math.pi)
    assert inv is not None and inv[3] == math.pi
    # A common phase error of 0.02 rad is not a lag at DC (it would reach harmonic k times k - 1): held at 0,
    # the corner and delay take what they can and the points are still reproduced within the tolerance.
    biased = _fopdt(freqs, logs, lag + 0.02)
    assert biased is not None and biased[3] == 0.0
    # A constant the held model cannot reproduce (0.3 rad) stays free rather than failing the fit.
    free = _fopdt(freqs, logs, lag + 0.3)
    assert free is not None and abs(free[3] - 0.3) < 0.05


def test_a_strongly_distorted_input_names_the_distortion_alone() -> None:
    # Harmonics of 10 % and 20 % of the fundamental: carried from the plain fit's G (its phases biased by
    # the distortion it leaves out) the waveforms settled on a G that named play and Coulomb friction
    # beside the distortion.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_recordings(0.2, 1))
    assert d.named_terms == ("distortion",), d.summary()
    lam = d.named[0]
    assert abs(lam.value - 1.0) < 4 * lam.standard_error, d.summary()


def test_a_waveform_distorted_in_some_experiments_only_keeps_its_law_test() -> None:
    """Only the high amplitude's inputs are distorted (the blind bench's clipping actuator): the waveform's
    column is zero in the clean experiments, which have no value of lambda of their own. Its law test
    compares the experiments it acts on; it raised LinAlgError (an overflowing 1/scale of a zero column)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_recordings(0.2, 1, low_clean=True), candidates=["offset", "distortion"])
    assert d.named_terms == ("distortion",), d.summary()
    trial = next(tr for st in d.steps for tr in st.trials if tr.term == "distortion")
    assert math.isfinite(trial.law_p_value) and trial.law_p_value >= 0.01


def test_a_failed_waveform_law_names_g_at_the_harmonics_as_a_reading() -> None:
    """The input-waveform term's law fails where G at the input's harmonics is not the G carried from the
    tested band (the blind bench's clipping actuator through a resonance: lam 1.5-2.4): the verdict says
    so, not only "physics outside the library"; other terms' words are unchanged."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis.run import _law_text
    from bouc_wen_id.terms import Distortion, Viscous

    def steps(term: str) -> list[Any]:
        trial = SimpleNamespace(term=term, law_p_value=1e-20)
        return [SimpleNamespace(trials=[trial], law_failed=(term,), alternatives=())]

    text = _law_text(steps(Distortion.kind))
    assert "G at the input's harmonics" in text and "p = 1e-20" in text
    assert "G at the input's harmonics" not in _law_text(steps(Viscous.kind))


def test_a_small_column_does_not_hide_a_law_failure() -> None:
    """The law test's contrasts (select.contrast_statistic) on a known covariance: four experiments, the
    term's value 1.0, 1.5 and 0.6 (se 0.05) in three, the fourth's column 1e-6..1e-9 of the largest (a
    nearly clean input: its value undetermined). Each against the last scaled every row by the small
    column's 1/scale: the informative contrasts fell below the pseudo-inverse's cut while matrix_rank
    counted them (statistic ~0 on 3 dof, p = 1: the failure hidden). Normalised rows against the largest
    column keep them; a zero column is left out (2 dof), and one experiment alone is no test."""
    from bouc_wen_id.diagnosis.select import LAW_ALPHA, contrast_statistic
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    values, se = np.array([1.0, 1.5, 0.6, 0.0]), 0.05
    cols = [np.arange(4)]
    for rel in (1e-6, 1e-7, 1e-9):
        scale = np.array([1.0, 1.0, 1.0, rel])
        got = contrast_statistic(values * scale / se, np.eye(4), scale, cols)
        assert got is not None, rel
        stat, df = got
        assert df == 3 and float(chdtrc(df, stat)) < LAW_ALPHA, (rel, stat, df)
    zero = np.array([1.0, 1.0, 1.0, 1e-300])
    got = contrast_statistic(values * zero / se, np.eye(4), zero, cols)
    assert got is not None and got[1] == 2 and float(chdtrc(2, got[0])) < LAW_ALPHA
    alone = np.array([1.0, 1e-300, 1e-300, 1e-300])
    assert contrast_statistic(values * alone / se, np.eye(4), alone, cols) is None
    same = np.array([1.0, 1.0, 1.0, 1e-7])  # one value for all: no failure
    got = contrast_statistic(np.full(4, 0.8) * same / se, np.eye(4), same, cols)
    assert got is not None and float(chdtrc(got[1], got[0])) > 0.5


def test_a_waveform_carried_by_one_experiment_says_its_law_untested() -> None:
    """The input waveform distorted in one experiment of six (the others pure sines): its column is zero in
    five, the law test has nothing to compare (NaN), and before the verdict named the term as if its law,
    one value for all, had passed. Now it says the law is untested; distorted in every experiment, it does
    not."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one = bw.diagnose(_recordings(0.2, 1, only=5), candidates=["offset", "distortion"])
        every = bw.diagnose(_recordings(0.2, 1), candidates=["offset", "distortion"])
    assert one.named_terms == ("distortion",), one.summary()
    assert "law untested (carried by only 1 of the 6 experiments" in one.verdict, one.verdict
    assert every.named_terms == ("distortion",) and "law untested" not in every.verdict, every.verdict

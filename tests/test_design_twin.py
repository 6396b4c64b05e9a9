"""Design twins (review 34, problem 6): at one frequency inertia is exactly a stiffness of -m omega^2 at the
same place; the verdict that names one says the other with its value, and what would separate them (another
frequency). A design with two frequencies has no such twin. The reviewer's own case (an independent
simulator, a spring on x at one frequency, six amplitudes) named "inertia on u m = 0.0015" and called the
exact twin of the true spring (inertia on x with a negative mass) "not physical, so no alternative".
"""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import design_twin

TWO_PI = 2.0 * math.pi
G = {
    "first": bw.TransferFunction([1.0], [0.05, 1.0]),
    "resonant": bw.TransferFunction([1.0], [1.0 / 400.0, 0.5 / 20.0, 1.0]),
}
STIFF, MASS = T.Stiffness.kind, T.Inertia.kind


def _plan(g: str, freqs: tuple[float, ...], seed: int) -> bw.SinePlan:
    om = np.repeat(TWO_PI * np.array(freqs), 6 // len(freqs))
    amps = np.tile([0.5, 0.9, 1.6, 2.4, 3.2, 4.0], 1)[: om.size] / G[g].gain_phase(om)[0]
    return bw.SinePlan(
        om, amps, settle_periods=8, periods=12, samples_per_period=64, substeps=8, noise_sd=0.005, seed=seed
    )


def _diagnose(g: str, k: float, freqs: tuple[float, ...], seed: int) -> bw.diagnosis.Diagnosis:
    plant = bw.WienerPlant(G[g], bw.BoucWen(0.7, 0.3, 1.8), terms=(T.Stiffness(k),))
    return bw.diagnose(bw.simulate(plant, _plan(g, freqs, seed)))


@pytest.mark.parametrize("g", ["first", "resonant"])
@pytest.mark.parametrize("k", [-0.02, 0.02])
def test_one_frequency_says_the_exact_twin_with_its_value(g: str, k: float) -> None:
    d = _diagnose(g, k, (1.0,), seed=11)
    want, twin = (MASS, STIFF) if k < 0 else (STIFF, MASS)
    assert d.named_terms == (want,), d.summary()
    omega2 = (TWO_PI * 1.0) ** 2
    named = d.named[0]
    # The named one's twin: k = -m omega^2 (a positive mass is a negative stiffness, and back).
    expect = -named.value * omega2 if want == MASS else -named.value / omega2
    label = T.TERMS[twin].place_label()
    assert f"gives the same averaged periods as {label} with" in d.verdict, d.verdict
    clause = d.verdict.split(f"gives the same averaged periods as {label} with ", 1)[1]
    value = float(clause.split(" = ", 1)[1].split(" ", 1)[0])
    assert value == pytest.approx(expect, rel=2e-3), (value, expect)
    assert clause.split("(", 1)[1].startswith("exactly"), clause
    # What separates them is another frequency, not another amplitude.
    assert "its frequency" in clause.split(")", 1)[0] or "its frequency" in clause[:400], clause
    # Still no alternative: the twin's value is not physical (test_diagnosis's rule holds).
    assert not [a for a in d.alternatives if {a.term, a.rival} == {STIFF, MASS}], d.summary()


def test_two_frequencies_have_no_exact_twin() -> None:
    d = _diagnose("first", -0.02, (0.5, 2.0), seed=12)
    assert MASS not in d.named_terms or "(exactly;" not in d.verdict, d.verdict
    assert "(exactly;" not in d.verdict, d.verdict


def test_distance_is_zero_only_for_the_same_outputs() -> None:
    """The chi-square distance of two fits' averaged periods: zero for the same outputs, the weighted sum of
    squares otherwise."""
    from bouc_wen_id.augmented import AugExperiment

    ys = np.linspace(0.0, 1.0, 8)
    e = AugExperiment(ybar=ys, amplitude=1.0, frequency=1.0, grid_phase=0.0, weight=4.0)

    class _F:
        def __init__(self, y: np.ndarray) -> None:
            self.outputs = (y,)

    a, b = _F(ys), _F(ys + 0.5)
    assert design_twin.distance([e], a, a) == 0.0  # type: ignore[arg-type]
    assert design_twin.distance([e], a, b) == pytest.approx(4.0 * 8 * 0.25)  # type: ignore[arg-type]

"""The diagnosis across conditions says what the single-condition diagnosis says of its own honesty
(issue 18, "nothing false said"; diagnosis/across_said.py): a candidate beyond its physical range
(across_bounds.py), a design twin (across_twin.py), values fitted on the clean-input experiments, an input
that is not a sine and a clipped output (across_clean.py). On main the same sets, diagnosed one condition at
a time, said each of these; across, none of them.

Data made three ways: the main bench's generator (benches/generator.py: a negative stiffness), the library's
simulator on a one-frequency design (tests/test_design_twin.py's), and an RK4 simulation written apart with a
clipped drive (tests/test_clean_value.py's).
"""

from __future__ import annotations

import importlib
import math
import re
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "benches"))
sys.path.insert(0, str(HERE))
gen: Any = importlib.import_module("generator")
twin_plan: Any = importlib.import_module("test_design_twin")._plan
twin_g: Any = importlib.import_module("test_design_twin").G
clipped_recordings: Any = importlib.import_module("test_clean_value")._recordings
output_clipped: Any = importlib.import_module("test_clean_value")._output_clipped


def _across(groups: list[Any], cands: Any = None, **kw: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=cands, **kw)


def _numbers(text: str) -> list[float]:
    return [float(v) for v in text.split(", ")]


def test_a_negative_stiffness_at_every_condition_is_said_with_its_values() -> None:
    """The bench's plant with a negative stiffness on u at -10x and -16x at two conditions: diagnosed one
    condition at a time (bounds_said.py) the verdict says the negative stiffness; across, main refused it in
    silence. Now the across verdict says it with its value at each condition (each near the truth, both
    negative) and what such a value suggests, and names no stand-in for it."""
    p = gen.make_plant(1)
    b = gen.base(p)
    truth, groups = [], []
    for size, seed in ((-10.0, 101), (-16.0, 102)):
        value, _, y = gen._calibrate(p, "stiffness", "u", size, b)
        truth.append(value)
        groups.append(gen.recordings(p, y, seed))
    a = _across(groups)
    label = T.TERMS[T.Stiffness.kind].place_label()
    assert "not explained within the terms' physical ranges" in a.verdict, a.verdict
    assert "P-Delta" in a.verdict, a.verdict
    m = re.search(re.escape(label) + r" k = ([-0-9.e]+, [-0-9.e]+) .*?at 0, 1 would remove", a.verdict)
    assert m is not None, a.verdict
    got = _numbers(m.group(1))
    for k, v in zip(got, truth):
        assert k < 0 and abs(k - v) < 0.25 * abs(v), (got, truth)
    assert a.named == () and a.status == "unexplained", a.verdict


@pytest.mark.parametrize("g", ["first", "resonant"])
def test_one_frequency_across_says_the_exact_twin_at_every_condition(g: str) -> None:
    """A spring on u at one frequency (six amplitudes), k moving with the condition: one condition at a time
    the verdict says the exact twin, an inertia of m = -k / omega^2, and the experiment that separates them
    (another frequency); across, main said nothing of it. Now it says the twin with its value at each
    condition and what separates them."""
    groups = []
    for k, seed in ((0.02, 11), (0.035, 12)):
        plant = bw.WienerPlant(twin_g[g], bw.BoucWen(0.7, 0.3, 1.8), terms=(T.Stiffness(k),))
        groups.append(bw.simulate(plant, twin_plan(g, (1.0,), seed)))
    cands = [T.Stiffness.kind, T.Inertia.kind, T.StiffnessX.kind, T.InertiaX.kind]
    a = _across(groups, cands)
    assert a.named == (T.Stiffness.kind,), a.verdict
    label = T.TERMS[T.Inertia.kind].place_label()
    m = re.search(
        r"gives the same averaged periods at every condition as " + re.escape(label) + r" with m = "
        r"([-0-9.e]+, [-0-9.e]+) [^(]*\((exactly|within the noise); ([^;]*); to separate them: ([^)]*)\)",
        a.verdict,
    )
    assert m is not None, a.verdict
    omega2 = (2.0 * math.pi) ** 2
    for m_k, k_k in zip(_numbers(m.group(1)), a.terms[0].values):
        assert m_k == pytest.approx(-k_k / omega2, rel=2e-3), (m_k, k_k)
    assert m.group(2) == "exactly" and "negative" in m.group(3), m.group(0)
    assert "frequency" in m.group(4), m.group(0)


def test_a_clipped_input_at_one_condition_is_said_and_its_values_are_the_clean_experiments() -> None:
    """Viscous damping on u (30x and 20x), two of five inputs clipped at condition 0 only. One condition at a
    time (clean_value.py, input_note.py) the verdict says the input is not a sine and quotes the value fitted
    on the clean experiments; across, main said neither and quoted the pooled value at condition 0. Now
    both are said at condition 0 (and not at 1), and the value there is the clean experiments' (within 3
    standard errors of the truth)."""
    recs0, c0 = clipped_recordings(1, 30.0)
    recs1, _ = clipped_recordings(2, 20.0, np.zeros(5))
    a = _across([recs0, recs1], [T.Viscous.kind, T.Coulomb.kind])
    assert "; the measured input is not a sine at 0 (" in a.verdict, a.verdict
    assert "not a sine at 1" not in a.verdict, a.verdict
    assert "; at 0: the values named are fitted on the 3 experiments whose input is a sine" in a.verdict
    assert "at 1: the values named" not in a.verdict, a.verdict
    t = next(t for t in (*a.terms, *a.partial) if t.term == T.Viscous.kind)
    assert abs(t.values[0] - c0) < 3 * t.standard_errors[0], (t.values, t.standard_errors, c0)


def test_a_clipped_output_at_one_condition_is_said_there() -> None:
    """The clipped-output clause (output_clip.py) at each condition whose recorded output has flat tops."""
    from bouc_wen_id.diagnosis import across_clean

    clean = output_clipped(0.0)
    text = across_clean.outputs_text(["0 A", "1 A"], [clean, output_clipped(0.92)])
    assert text.startswith("; at 1 A, the measured output of recording 3, recording 4 looks clipped"), text
    assert "at 0 A" not in text
    assert across_clean.outputs_text(["0 A"], [clean]) == ""


def test_a_physical_twin_is_added_once_to_its_step_s_alternatives_and_a_non_physical_one_is_said() -> None:
    """across_twin's bookkeeping: a twin with a physical value at every condition becomes its step's
    alternative (once: not when the pair is already there, in either order); one outside its range is no
    alternative but is said with its value at each condition and what separates them."""
    from bouc_wen_id.diagnosis import across_twin
    from bouc_wen_id.diagnosis.across import JointStep
    from bouc_wen_id.diagnosis.select import Alternative

    k, m, mx, kx = T.Stiffness.kind, T.Inertia.kind, T.InertiaX.kind, T.StiffnessX.kind
    have = Alternative(kx, k, math.nan, "another amplitude")
    steps = (JointStep((), k, alternatives=(have,)), JointStep((), None))

    def twin(rival: str, ok: bool) -> Any:
        return across_twin.TwinAcross(k, rival, 0.0, ok, (-0.001, -0.002), ("0 A", "1 A"), "at 0 A: at 2x")

    found = [twin(m, False), twin(mx, True), twin(kx, True)]
    out, added = across_twin.with_alternatives(steps, found)
    assert [(a.term, a.rival) for a in added] == [(k, mx)]
    assert out[0].alternatives == (have, added[0]) and out[1] is steps[1]
    text = across_twin.text(found, ("N", "mm"))
    assert T.TERMS[mx].place_label() + " with" not in text
    assert f"as {T.TERMS[m].place_label()} with m = -0.001, -0.002 " in text, text
    assert "at 0 A, 1 A (exactly;" in text and "to separate them: at 0 A: at 2x" in text, text

"""``diagnose_across`` takes its targeted step by ``diagnose``'s gate (issue 18: the house says the same thing
whichever path the user takes), and says what it did.

``diagnose`` takes the targeted step (its candidates at ``alpha / 2`` when the plain model passes the global
test) only when every noise floor is measured noise, and never when the loop drifts on the plain model
(``gate.plain_passes``' ``moved``); otherwise it notes why (``NO_TARGETED_STEP``). The joint path ran the
targeted step whenever the plain models passed: on quantised output whose floor is the quantisation step
(the bench's first-order G, not the closed form the rules were shaped on) ``diagnose`` said "adequate" at
each condition and ``diagnose_across`` "unexplained ... not named: viscous damping (p = 1e-9)". Both paths
now call ``gate.plain_gate``. Also: "passes its adequacy test at X of N conditions" at the caller's alpha,
the notes in the printed summary, a step's level and targeted flag and a trial's presence in the record.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across, gate
from bouc_wen_id.diagnosis.run import NO_TARGETED_STEP

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")
tests = str(Path(__file__).resolve().parent)
sys.path.insert(0, tests)
rules: Any = importlib.import_module("test_diagnosis_across_rules")

CANDS = [T.Viscous.kind, T.Offset.kind, T.Stiffness.kind]


def _quantised(seed: int, size: float = 1.0, dither: float = 0.05) -> list[Any]:
    """Viscous damping on u at ``size`` (below the global test's reach) through the bench's first-order G,
    the output quantised at the averaged noise sd with a dither of ``dither`` steps: the noise floor is the
    quantisation step's, not measured noise."""
    p = gen.make_plant(4101, shape="first")
    b = gen.base(p)
    q = math.sqrt(12.0) * gen.NOISE_SD / math.sqrt(gen.PERIODS)
    _, _, y = gen._calibrate(p, "viscous", "u", size, b)
    rng = np.random.default_rng(seed)
    recs = []
    for i in range(p.omegas.size):
        n = y.shape[-1]
        t = np.arange(n) * (2.0 * math.pi / float(p.omegas[i]) / gen.P)
        u = float(p.amplitudes[i]) * np.cos(float(p.omegas[i]) * t)
        yy = np.round((y[i] + dither * q * rng.standard_normal(n)) / q) * q
        recs.append(
            bw.Recording(t, u, yy, float(p.amplitudes[i]), float(p.omegas[i]), settle_periods=gen.SETTLE)
        )
    return recs


def test_no_targeted_step_across_where_a_noise_floor_is_set_as_diagnose() -> None:
    groups = [_quantised(77), _quantised(78)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=CANDS) for g in groups]
        alone = bw.diagnose_across(groups, [0.0, 1.0], candidates=CANDS)
        given = bw.diagnose_across(groups, [0.0, 1.0], candidates=CANDS, per_condition=own)
    for d in own:  # the case: diagnose's gate passes on a floored noise, and it says so
        assert d.status == "adequate" and not d.steps, d.verdict
        assert NO_TARGETED_STEP in d.notes
    for a in (alone, given):
        assert a.status == "adequate" and not a.steps, a.verdict  # before: a targeted step, "unexplained"
        assert gate.ADEQUATE in a.verdict
        assert any(n.endswith(NO_TARGETED_STEP) for n in a.notes), a.notes
        assert NO_TARGETED_STEP in a.summary()  # the CLI prints the notes now
    assert all(d.settings["measured_noise"] is False for d in own)  # what the joint path reads of them


def _groups(p: float, moved: bool, measured: bool) -> list[Any]:
    cost = rules._plain_at(p)
    return [
        SimpleNamespace(**vars(g), moved=moved, measured_noise=measured)
        for g in rules._groups(cost, cost, ())
    ]


def test_the_first_step_follows_diagnose_s_gate() -> None:
    """across._go_on at the function level: (go, level, targeted) as diagnose's gate gives them
    (gate.plain_gate): a loop that drifts on its plain model (``moved``, diagnose's before.drift_detected)
    keeps the plain model from passing, so the first step runs at alpha, not as the targeted one."""
    alpha = 0.05
    assert across._go_on(_groups(0.3, False, True), [], alpha) == (True, 0.5 * alpha, True)
    assert across._go_on(_groups(0.3, True, True), [], alpha) == (True, alpha, False)  # moved: no pass
    assert across._go_on(_groups(0.3, False, False), [], alpha) == (False, alpha, False)  # floored: none
    assert across._go_on(_groups(0.01, False, False), [], alpha) == (True, alpha, False)  # fails: a step
    # diagnose's rule, the same function:
    assert gate.plain_gate([0.3], alpha, [True], [True]) == (False, False)
    assert gate.plain_gate([0.3], alpha, [False], [False]) == (True, False)


def test_the_verdict_counts_adequate_conditions_at_the_callers_alpha() -> None:
    """The reviewer's case: final p 0.03 and 0.02 pass at alpha = 0.01 (the stop rule's and the status's
    level) but were counted at a hard-coded 0.05 ("passes ... at 0 of 2 conditions")."""
    conds = [
        across.ConditionResult("0 A", 0.0, 4, 3.0, 1.1, 0.03, 0.1, 0.09),
        across.ConditionResult("1 A", 1.0, 4, 3.0, 1.1, 0.02, 0.1, 0.09),
    ]
    t = rules._term(T.Viscous.kind, (0.5, 0.5))
    assert "passes its adequacy test at 2 of 2 conditions" in across._verdict([t], conds, [], 0.01)
    assert "passes its adequacy test at 0 of 2 conditions" in across._verdict([t], conds, [], 0.05)


def test_a_step_records_its_level_and_whether_targeted_and_a_trial_its_presence() -> None:
    tr = across.JointTrial(
        T.Viscous.kind, 9.0, 1e-3, 2e-3, 0.9, (5.0, 4.0), (1e-3, 0.2), True, present=(True, False)
    )
    st = across.JointStep((tr,), T.Viscous.kind, level=0.025, targeted=True)
    d = st.to_dict()
    assert d["level"] == 0.025 and d["targeted"] is True
    assert d["trials"][0]["present"] == [True, False]
    assert across.JointStep((), None).to_dict()["targeted"] is False

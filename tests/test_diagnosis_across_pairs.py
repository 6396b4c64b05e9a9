"""``diagnose_across`` runs ``diagnose``'s pair step (diagnosis/across_pairs.py, the same pairs.pair_step
through pairs.Rules): where every candidate of a joint step fails its law alone, a set fitted at every
condition at once may hold its laws, and is named together as each level's own diagnosis names it (issue
18: before, each level said "play with sensor lag, named together" and the joint structure "unexplained",
both law-failed, with no word on why).

The plant is not the across tests' generator: the library's simulator with a resonant G with a delay (the
pair tests' plant), play and a sensor lag whose values move with the condition, seeded noise per condition.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import across_pairs, pairs
from bouc_wen_id.terms import Offset, Play, SensorLag, Stiffness, Viscous, ViscousX

CANDS = [Play.kind, SensorLag.kind, Viscous.kind, ViscousX.kind, Offset.kind, Stiffness.kind]


def _recordings(play: float, lag: float, seed: int, rate_damping: float = 0.0) -> list[Any]:
    """Play and a sensor lag (``rate_damping`` > 0: play and a damping ``rate_damping * f`` that grows with
    the frequency f instead, one plant per experiment: physics outside the library, 20 periods of 256)."""
    g = bw.TransferFunction([36.0], [1.0, 3.0, 36.0], delay=0.03)
    hyst = bw.BoucWen(beta=1.6, gamma=0.4, mu=1.6, alpha=2.0)
    out: list[Any] = []
    periods, samples = (20, 256) if rate_damping else (40, 512)
    for k, f in enumerate((0.5, 1, 2, 3, 4, 5)):
        terms: tuple[Any, ...] = (Play(play), SensorLag(lag))
        if rate_damping:
            terms = (Viscous(rate_damping * f), Play(play))
        plan = bw.SinePlan(frequencies=[f], amplitudes=1.0, settle_periods=30, periods=periods,
                           samples_per_period=samples, noise_sd=0.01, seed=seed + k)  # fmt: skip
        out += bw.simulate(bw.WienerPlant(g, hyst, terms=terms), plan)
    return out


def test_across_names_the_pair_each_level_names() -> None:
    """Play (0.10, 0.12) and a sensor lag (15, 20 ms) at two conditions: each level's diagnose names play with
    sensor lag together (each fails its law alone); so does the joint structure, with each member present at
    both conditions and its values the levels' own within their se (on main: nothing named across)."""
    groups = [_recordings(0.10, 0.015, 3), _recordings(0.12, 0.020, 50)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=CANDS) for g in groups]
        a = bw.diagnose_across(groups, [0.0, 1.0], candidates=CANDS, per_condition=own)
    pair = {Play.kind, SensorLag.kind}
    assert all(any(set(st.pair) == pair for st in d.steps) for d in own), [d.verdict for d in own]
    assert pair <= set(a.named) and a.status == "explained", a.verdict
    assert any(set(st.pair) == pair for st in a.steps), a.verdict
    assert "named together: play (backlash) with sensor lag" in a.verdict
    for t in a.terms:
        if t.term not in pair:
            continue
        assert t.everywhere
        mine = [next(n for n in d.named if n.term == t.term) for d in own]
        z = [
            (v - m.value) / math.hypot(se, m.standard_error)
            for v, se, m in zip(t.values, t.standard_errors, mine)
        ]
        assert np.all(np.abs(z) < 3.0), (t.term, z)
    step = next(st for st in a.steps if st.pair)
    assert step.to_dict()["pair"] == list(step.pair) and step.to_dict()["pairs"]


def test_outside_physics_reaches_the_joint_pair_step_and_no_set_is_named() -> None:
    """A damping that grows with the rate beside play (0.02 f and 0.025 f at two conditions): the joint pair
    step is reached (a step whose candidates' laws all fail) and every set it fits is refused (each
    stand-in's law still fails beside the others): no set named, and the verdict says what the step did
    (on main the clause said it "did not run")."""
    groups = [_recordings(0.1, 0.0, 3, 0.02), _recordings(0.1, 0.0, 60, 0.025)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, [0.0, 1.0])
    # The pair step's sets (a revisit's record, revisit.Revisit, may sit on a named step: across_revisit.py)
    tried = [st for st in a.steps if any(isinstance(p, pairs.PairTrial) for p in st.pairs)]
    assert tried, a.verdict
    assert not any(st.pair for st in a.steps) and "named together" not in a.verdict
    assert all(p.refused for st in tried for p in st.pairs)
    assert a.status != "explained"
    k = a.steps.index(tried[0]) + 1
    n = sum(isinstance(p, pairs.PairTrial) and math.isfinite(p.cost) for p in tried[0].pairs)
    assert f"at step {k} the pair step fitted {n} sets" in a.verdict, a.verdict


class _Group:
    """A condition as JointRules reads it (its experiments' dof stubbed)."""

    def __init__(self, label: str) -> None:
        self.label, self.substeps, self.cache = label, 1, None
        self.sx: list[Any] = []


def _joint(*flags: tuple[bool, bool]) -> Any:
    """A JointFit of stub fits of cost 120, each (admissible, at its null)."""
    from types import SimpleNamespace

    fits: Any = tuple(SimpleNamespace(cost=120.0, ok=ok, null=null) for ok, null in flags)
    return across_pairs.JointFit(fits)


def test_joint_rules_pool_the_conditions(monkeypatch: Any) -> None:
    """JointRules: a set's dof summed over the conditions, its F tests on ``q K`` parameters (per_set = K),
    physical at every condition and not at its null at all of them."""
    monkeypatch.setattr(across_pairs, "dof_of", lambda sx, f: 100)
    monkeypatch.setattr(across_pairs, "_admissible", lambda f, t: f.ok)
    monkeypatch.setattr(across_pairs, "at_null", lambda f, t: f.null)
    r = across_pairs.JointRules([_Group("a"), _Group("b"), _Group("c")])
    good = (True, False)
    jf = _joint(good, good, good)
    assert isinstance(r, pairs.Rules) and r.per_set == 3 and r.dof(jf) == 300 and jf.cost == 360.0
    assert r.physical(jf, "x")
    assert not r.physical(_joint(good, (False, False), good), "x")  # outside its range at one condition
    assert r.physical(_joint((True, True), good, good), "x")  # at its null at one only: absent there
    assert not r.physical(_joint((True, True), (True, True), (True, True)), "x")  # at its null everywhere

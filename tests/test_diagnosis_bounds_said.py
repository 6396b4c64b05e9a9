"""Values held at an admissible bound are said, not replaced by stand-ins (issue 18; review 34 problems 1-2).

A negative parallel stiffness on u (a P-Delta-like softening) removed most of the excess at the first step but
was refused in silence (k >= 0): the verdict named sensor lag and Dahl friction on x instead, and the
detection limits said "|k| < 0.013". A final fit held at the lower end of mu's bracket (Bouc-Wen with
mu = 0.5) named viscous + Coulomb + Dahl on x on a null and never mentioned mu.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import bounds_said
from bouc_wen_id.diagnosis.result import NamedTerm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

K_U = T.Stiffness.kind


@pytest.mark.parametrize("place", ["u", "x"])
def test_a_negative_stiffness_is_said_with_its_value_and_not_hidden_by_its_limit(place: str) -> None:
    """The bench's plant (written apart from the library's simulator), a negative stiffness on u or on x at
    the bench's 10x size: the verdict says the negative stiffness, its value and what it suggests, names no
    stand-in for it, and its detection limit does not claim |k| < limit."""
    term = K_U if place == "u" else T.StiffnessX.kind
    p = gen.make_plant(1)
    value, _, y = gen._calibrate(p, "stiffness", place, -10.0, gen.base(p))
    assert value < 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(gen.recordings(p, y, 101))
    assert "negative stiffness" in d.verdict and "P-Delta" in d.verdict, d.summary()
    assert term not in d.named_terms
    said = d.verdict.split(f"{T.TERMS[term].place_label()} k = ")[1]
    k = float(said.split(" ")[0])
    assert k < 0 and abs(k - value) < 0.2 * abs(value), (k, value)
    lim = next(lim for lim in d.limits if lim.term == term)
    assert not math.isfinite(lim.limit) and "|k| <" not in str(lim), str(lim)
    assert "outside its physical range" in str(lim)


def _named(term: str) -> NamedTerm:
    return NamedTerm(term, "c", 0.01, 0.001, "")


def test_a_final_fit_held_at_the_mu_bracket_qualifies_the_verdict() -> None:
    """The terms kept beside mu held at its bracket's end are stand-ins, not findings (review 36 problem 3):
    the status is not "explained in part", nothing is named, and the clause says their values without the
    standard errors that assume the hysteresis is right."""
    held = bounds_said.Beyond(mu_face="lower", mu=1.0)
    kept = (_named(T.ViscousX.kind), _named(T.CoulombX.kind))
    status, named, head, tail = bounds_said.apply(held, "partly explained", kept, kept, 0.6)
    assert status == "unexplained" and named == () and head == ""
    assert tail.startswith("; the hysteresis exponent is held at the lower end of its bracket (mu = 1;")
    assert "conditional" in tail
    said = tail.split(bounds_said.HELD_MARK)[1]
    assert all(f"{t.label} c = 0.01" in said for t in kept), said
    assert (
        "±" not in tail
        and "0.001" not in said
        and "softer than mu = 1 allows" in said
        and "sharper" not in said
    )
    # Nothing named, nothing to demote: the mu clause alone.
    bare = bounds_said.apply(held, "unexplained", (), kept, 0.3)[3]
    assert bare.startswith("; the hysteresis exponent") and bounds_said.HELD_MARK not in bare
    # An adequate verdict and a final model that passes within the bracket stand as they were.
    assert bounds_said.apply(held, "adequate", (), (), 0.0) == ("adequate", (), "", "")
    assert bounds_said.apply(held, "explained", kept, kept, 1.0) == ("explained", kept, "", "")
    # Inside the bracket nothing changes.
    inside = bounds_said.Beyond(mu=2.0)
    assert bounds_said.apply(inside, "partly explained", kept, kept, 0.6) == (
        "partly explained",
        kept,
        "",
        "",
    )


def test_a_candidate_beyond_its_range_that_only_ties_is_not_said() -> None:
    """Review of the merge: a negative stiffness removing 56 % beside an inertia on x that explains 100 %
    was said, with P-Delta "suggested"; only one that beats the final model is said (an exact tie is a
    design twin's, said by design_twin.py)."""
    kept = (_named(T.InertiaX.kind),)
    tie = bounds_said.Beyond(found=((_named(T.StiffnessX.kind), None),), beats_final=False)  # type: ignore[arg-type]
    assert bounds_said.apply(tie, "explained", kept, kept, 1.0) == ("explained", kept, "", "")
    assert bounds_said.apply(tie, "partly explained", kept, kept, 0.6) == ("partly explained", kept, "", "")


def test_the_mu_clause_does_not_claim_the_loops_ask_for_a_smaller_mu() -> None:
    """A true mu = 1 (the classic Bouc-Wen) sits at the bracket's end whenever something else is missing."""
    tail = bounds_said.apply(bounds_said.Beyond(mu_face="lower", mu=1.0), "unexplained", (), (), 0.3)[3]
    assert "ask for" not in tail and "either the true exponent is there" in tail


def test_a_soft_loop_leads_with_its_shape_not_with_a_negative_mass() -> None:
    """Review 40 item 2 (mu41): a mu = 0.7 loop through a resonant G and a delay led the verdict with "inertia
    ... m = -5.8e-05 ... a negative mass ... or an input recorded with the wrong sign or scale" (48 se). With
    mu held at the lower end of its bracket the loop's shape leads; the out-of-range value follows as what
    may stand in for it. Data: the tests' own simulator (wiener_sim.py), white noise 1 %, two amplitudes."""
    import numpy as np
    from wiener_sim import SETTLE, simulate

    freqs, amps = np.array([1.0, 2.0, 4.0, 1.0, 2.0, 4.0]), np.array([0.6, 0.6, 0.6, 1.5, 1.5, 1.5])
    h, u, w = simulate(freqs, amps, mu=0.7)
    rng = np.random.default_rng(21)
    recs = []
    for i, f in enumerate(freqs):
        t = np.arange(w[i].size) * h[i]
        y = w[i] + rng.normal(0.0, 0.01 * float(np.sqrt(np.mean(w[i] ** 2))), t.size)
        recs.append(
            bw.Recording(
                t, u[i], y, amplitude=float(amps[i]), frequency=2 * math.pi * float(f), settle_periods=SETTLE
            )
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recs)
    assert d.status != "explained" and not d.named, d.verdict
    head = d.verdict.split("; ")[0]
    assert "negative" not in head and "wrong sign" not in head, d.verdict
    assert head.startswith(bounds_said.SOFT_HEAD), d.verdict  # before: the negative mass led
    assert "a negative mass" in d.verdict.split(bounds_said.MU_MARK)[1], d.verdict  # said after, as stand-in
    assert "softer than mu = 1 allows" in d.verdict and "sharper" not in d.verdict, d.verdict


def test_the_soft_head_puts_an_out_of_range_candidate_after_the_mu_clause() -> None:
    """The rule: mu held at its lower end and a candidate beyond its range that beats the final model."""

    class _Trial:
        share, p_adjusted = 0.3, 1e-20

    found = ((NamedTerm(T.InertiaX.kind, "m", -5.8e-5, 1.2e-6, "s^2"), _Trial()),)
    b = bounds_said.Beyond(found=found, beats_final=True, mu_face="lower", mu=1.0)  # type: ignore[arg-type]
    status, named, head, tail = bounds_said.apply(b, "partly explained", (), (), 0.2)
    assert status == "unexplained" and named == ()
    assert head.startswith(bounds_said.SOFT_HEAD) and "negative" not in head
    assert tail.index(bounds_said.MU_MARK) < tail.index("a negative mass"), tail
    # Inside the bracket the out-of-range candidate leads, as before.
    inside = bounds_said.Beyond(found=found, beats_final=True, mu=1.4)  # type: ignore[arg-type]
    head2 = bounds_said.apply(inside, "partly explained", (), (), 0.2)[2]
    assert head2.startswith("not explained within the terms' physical ranges") and "a negative mass" in head2


def test_nothing_named_with_mu_at_its_lower_end_leads_with_the_soft_loop() -> None:
    """Review 43 d5 (a plain mu = 0.8 device, resonant G, 8 ms delay, six frequencies): nothing named, the
    headline read "unexplained structure remains ..." and the reason (mu held at 1) only in a later clause."""
    status, named, head, tail = bounds_said.apply(
        bounds_said.Beyond(mu_face="lower", mu=1.0), "unexplained", (), (), 0.3
    )
    assert status == "unexplained" and named == () and head.startswith(bounds_said.SOFT_HEAD), head
    assert bounds_said.MU_MARK in tail  # the clause with both readings stays
    inside = bounds_said.apply(bounds_said.Beyond(mu_face="", mu=1.3), "unexplained", (), (), 0.3)
    assert inside[2] == ""  # mu inside its bracket: no such lead
    upper = bounds_said.apply(bounds_said.Beyond(mu_face="upper", mu=5.0), "unexplained", (), (), 0.3)
    assert upper[2] == ""  # the upper end is not a softer loop

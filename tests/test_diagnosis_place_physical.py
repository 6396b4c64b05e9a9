"""A place alternative must be a physical reading (issue 18: honest verdicts).

Where x lags u by about pi (the bench's resonant G with a delay, every experiment at the frequency where the
lag is pi - 0.03 rad), viscous damping on x fits the data of viscous damping on u as well as the truth, with
the opposite sign: a negative damping. ``diagnose`` and ``diagnose_across`` both listed it as an alternative
("the experiments cannot tell apart: viscous damping on u or ... on x"). Now a sibling at another place is an
alternative only with a physical value that is not its null wherever the chosen term is present
(``select.place_admissible``), and the verdict says the non-physical one is no alternative.
"""

from __future__ import annotations

import importlib
import json
import math
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_rules
from bouc_wen_id.diagnosis.result import clean

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

X = T.ViscousX.kind


def _lagging_pi(delta: float = 0.03, size: float = 5.0) -> list[Any]:
    """Two conditions of viscous damping on u (the bench's calibrated size), the resonant G with a delay,
    three levels at the one frequency where x lags u by ``pi - delta``."""
    p0 = gen.make_plant(7, shape="resonant")
    om = np.linspace(p0.omegas[0] * 0.5, p0.omegas[-1] * 3, 4000)
    ph = np.unwrap(np.angle(p0.freqresp(om)))
    w = float(om[np.argmin(np.abs(ph + (math.pi - delta)))])
    levels = np.array([1.2, 2.0, 3.0])
    omegas = np.full(3, w)
    g = np.abs(p0.freqresp(omegas))
    p = replace(p0, omegas=omegas, amplitudes=levels / g, levels=levels, w0=np.zeros(3))
    b = gen.base(p)
    groups = []
    for k in range(2):
        _, _, y = gen._calibrate(p, "viscous", "u", size, b)
        groups.append(gen.recordings(p, y, 900 + k))
    return groups


def _value(fit: Any, term: str) -> float:
    return float(fit.params.values[fit.params.terms.index(term)])


def test_a_negative_damping_at_the_other_place_is_no_alternative() -> None:
    groups = _lagging_pi()
    cands = [T.Viscous.kind, X]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across(groups, [0.0, 1.0], candidates=cands)
        d = bw.diagnose(groups[0], candidates=cands)
    runs: list[tuple[str, Any, Any, str]] = [
        ("across", a.named, a.steps, a.verdict),
        ("diagnose", d.named_terms, d.steps, d.verdict),
    ]
    for what, named, steps, verdict in runs:
        assert named == (T.Viscous.kind,), (what, verdict)
        first = steps[0]
        # The sibling on x fits about as well, with a negative value: the case the rule is about.
        on_x: Any = next(t for t in first.trials if t.term == X)
        fits = on_x.fits if what == "across" else (on_x.fit,)
        assert all(_value(f, X) < 0 for f in fits), what
        assert not any(alt.rival == X for st in steps for alt in st.alternatives), (what, verdict)
        assert first.unphysical_places == (X,), what
        assert "cannot tell apart" not in verdict, (what, verdict)
        assert f"{T.ViscousX.place_label()} fits about as well" in verdict and "not physical" in verdict
    json.dumps(clean(a.to_dict()), allow_nan=False)
    assert a.to_dict()["steps"][0]["unphysical_places"] == [X]
    assert d.to_dict()["steps"][0]["unphysical_places"] == [X]


def test_the_siblings_law_is_tested_where_the_sibling_is_present(monkeypatch: pytest.MonkeyPatch) -> None:
    """``across_rules._places`` tested a sibling's law at the conditions where the CHOSEN term is present;
    the sibling's own law is its claim where IT is present (its own ``present``)."""
    seen: list[tuple[bool, ...]] = []

    def law_p(groups: Any, tr: Any, present: Any) -> float:
        seen.append(tuple(present))
        return 0.5

    monkeypatch.setattr(across_rules, "law_p", law_p)
    monkeypatch.setattr(across_rules, "_s2", lambda groups, chosen: 1.0)
    monkeypatch.setattr(across_rules, "_rho", lambda groups, chosen, rival, present: 0.0)
    monkeypatch.setattr(across_rules, "_place_separation", lambda sx, fit, term: "elsewhere")
    monkeypatch.setattr(across_rules, "place_admissible", lambda fits, term: True, raising=False)
    groups = [SimpleNamespace(label=f"{k} A", sx=[]) for k in range(3)]
    fit = SimpleNamespace(cost=10.0)
    chosen = SimpleNamespace(term=T.Viscous.kind, fits=(fit,) * 3, present=(True, True, False))
    sib = SimpleNamespace(term=X, fits=(fit,) * 3, present=(False, True, True), law_p_value=math.nan)
    out = across_rules._places(groups, chosen, {X: sib}, [], {})
    assert [a.rival for a in out] == [X]
    assert seen == [sib.present]


def test_place_admissible_refuses_a_value_outside_the_range_or_at_null() -> None:
    """The rule at the function level, for each term with places and a physical range."""
    from bouc_wen_id.diagnosis.select import place_admissible, siblings

    for cls in (T.Viscous, T.Coulomb):
        for term in (cls.kind, *siblings(cls.kind)):
            lo, hi = T.TERMS[term].bounds

            def fit(v: float, term: str = term) -> Any:
                return SimpleNamespace(params=SimpleNamespace(terms=(term,), values=np.array([v])))

            good = 0.5 * (max(lo, 0.0) + min(hi, 1.0)) or 0.5
            assert place_admissible([fit(good), fit(good)], term), term
            assert not place_admissible([fit(good), fit(0.0)], term), term  # its null at one condition
            assert not place_admissible([fit(good), fit(-good)], term), term  # non-physical at one
            assert not place_admissible([fit(good), None], term), term

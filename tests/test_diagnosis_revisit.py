"""The revisit of a named single term (diagnosis/revisit.py), the law-failed clause's account of the pair
step (run._law_text, pairs.refusal_text), and the separating experiment of a set's rival (pairs._rivals).

The selection tests build its inputs directly (fits with set costs per set of terms, a law p per term and
set), so that the rule, not a noise draw, decides; select.rebase and select.wide_fit are stubbed. The plant
the revisit was built for (stiffness and viscous damping on u through a two-pole G without delay, named
viscous damping on x on main) is reproduced by studies/several_terms.py.
"""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace
from typing import Any, cast

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output
from bouc_wen_id.diagnosis import pairs, revisit, run, select, speed

M, N = 4, 100  # experiments, samples per averaged period
S, A, B = T.ViscousX.kind, T.Stiffness.kind, T.Viscous.kind  # the wrong single, the true pair


def _fit(terms: tuple[str, ...], cost: float) -> Any:
    par = SimpleNamespace(terms=terms, values=np.full(len(terms), 0.01), gains=np.ones(M), phases=np.zeros(M))
    return SimpleNamespace(params=par, cost=cost)


Law = Callable[[frozenset[str], str], float]


def _costs(ab: float = 395.0) -> dict[frozenset[str], float]:
    """A alone 425 (its law fails), S 430 (its law holds: named), B alone 470; beside S, B removes most of
    what is left (400) but its law fails; jointly A and B reach ``ab``."""
    return {
        frozenset({A}): 425.0,
        frozenset({S}): 430.0,
        frozenset({B}): 470.0,
        frozenset({S, B}): 400.0,
        frozenset({A, B}): ab,
    }


def _law(holds: tuple[frozenset[str], ...]) -> Law:
    """S's law holds alone; in each set of ``holds`` every law holds; every other law fails."""
    return lambda terms, t: 0.4 if terms in (frozenset({S}), *holds) else 1e-6


def _select(
    monkeypatch: pytest.MonkeyPatch,
    costs: dict[frozenset[str], float],
    law: Law,
    limit: float = 420.0,
) -> tuple[Any, list[select.Step]]:
    """revisit.select from a plain fit of cost 500 over S, A, B; a model's cost from ``costs`` (1000 when
    absent); adequate below ``limit``."""
    monkeypatch.setattr(speed, "MEMO_FITS", False)

    def fit_with(exps: Any, base: Any, t: str, sub: int) -> Any:
        terms = (*base.params.terms, t)
        return _fit(terms, costs.get(frozenset(terms), 1000.0))

    def law_test(exps: Any, fit: Any, t: str, sub: int) -> float:
        return law(frozenset(fit.params.terms), t)

    monkeypatch.setattr(select, "fit_with", fit_with)
    for mod in (select, pairs):
        monkeypatch.setattr(mod, "element_law_test", law_test)
        monkeypatch.setattr(mod, "_separating", lambda exps, fa, fb, sub: "a separating design")
    monkeypatch.setattr(select, "_correlation", lambda fit, a, b: 0.3)
    monkeypatch.setattr(select, "rebase", lambda *a, **k: None)
    monkeypatch.setattr(select, "wide_fit", lambda exps, base, t, sub, first: first)
    exps = [SimpleNamespace(ybar=np.zeros(N), grid_phase=0.0, source=f"e{i}") for i in range(M)]
    return revisit.select(
        cast(Any, exps),
        _fit((), 500.0),
        [S, A, B],
        lambda f: f.cost < limit,
        2,
        use_held_out=False,
        pair_step=pairs.pair_step,
    )


def test_a_single_that_leaves_a_lawless_remainder_is_replaced_by_the_set_whose_laws_hold(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """S is named at step 1; at step 2 B removes most of what is left but fails its law beside S; A with B
    hold their laws jointly and pass adequacy: named in S's place, S reported as the rival."""
    final, steps = _select(monkeypatch, _costs(), _law((frozenset({A, B}),)))
    assert set(final.params.terms) == {A, B}
    assert len(steps) == 1 and set(steps[0].pair) == {A, B}
    (rec,) = revisit.records(steps)
    assert rec.outcome == "named" and rec.replaced == S and set(rec.terms) == {A, B}
    assert "revisited" in revisit.text(steps) and "a separating design" in revisit.text(steps)
    assert steps[0].to_dict()["pairs"][-1]["revisit_of"] == S


def test_without_the_revisit_the_single_stays_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """The selection as on the pairs branch (and main): S named, step 2 ends on B's failed law."""
    monkeypatch.setattr(revisit, "ENABLED", False)
    final, steps = _select(monkeypatch, _costs(), _law((frozenset({A, B}),)))
    assert final.params.terms == (S,) and steps[1].chosen is None and B in steps[1].law_failed


def test_outside_physics_keeps_the_single_and_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every law but S's fails, also in the set: nothing changes; the revisit's refusal is recorded."""
    final, steps = _select(monkeypatch, _costs(), _law(()))
    assert final.params.terms == (S,) and steps[0].chosen == S and steps[1].chosen is None
    (rec,) = revisit.records(steps)
    assert rec.terms == () and "law fails" in rec.outcome
    assert "revisited from the model before it" in revisit.text(steps) and rec.outcome in revisit.text(steps)


def test_the_revisits_refusal_names_the_set_and_its_terms_in_words(monkeypatch: pytest.MonkeyPatch) -> None:
    """Review 33 (clip_cu): "best refused for coulomb: share 0.048 of the excess given distortion" named no
    set and spoke in code names. The refusal names the best-fitting set by its terms' labels, says it was
    refused, and the law's failure in words (which value differs between experiments)."""
    final, steps = _select(monkeypatch, _costs(), _law(()))
    (rec,) = revisit.records(steps)
    said = revisit.text(steps)
    assert "best refused for" not in said and "was refused: law fails (its value differs" in said
    assert f"the best-fitting, {T.Stiffness.place_label()} with {T.Viscous.place_label()}" in said or (
        f"the best-fitting, {T.Viscous.place_label()} with {T.Stiffness.place_label()}" in said
    )
    labels = (T.Stiffness.place_label(), T.Viscous.place_label())
    assert any(f"{lab} (p = " in rec.outcome for lab in labels)


def test_a_set_whose_model_fails_adequacy_is_an_alternative_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """The set's laws hold but its model is not adequate (the limit below its cost): S stays named; the set
    is said as an alternative with the separating experiment."""
    final, steps = _select(monkeypatch, _costs(), _law((frozenset({A, B}),)), limit=390.0)
    assert final.params.terms == (S,)
    (rec,) = revisit.records(steps)
    assert rec.outcome.startswith("alternative") and "adequacy" in rec.outcome
    assert "alternative to" in revisit.text(steps) and "a separating design" in revisit.text(steps)


def test_the_law_failed_clause_says_several_terms_and_what_the_pair_step_did(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A law-failed candidate is not called a stand-in for outside physics only: the clause says "or
    several library terms at once" with what the pair step did (here: ran at step 2, named none, with the
    best set's refusal; not run at step 1, which named S). Main said "it stands in for physics outside the
    library" and nothing more."""
    monkeypatch.setattr(revisit, "ENABLED", False)
    _, steps = _select(monkeypatch, _costs(), _law(()))
    text = run._law_text(steps)
    assert "several library terms at once" in text
    assert "at step 1 the pair step did not run" in text
    assert "at step 2 the pair step fitted" in text and "named none; the best" in text


def _exps() -> list[AugExperiment]:
    out = []
    for k, (u, om) in enumerate([(1.0, 1.0), (1.5, 3.0), (1.0, 6.0)]):
        out.append(AugExperiment(np.zeros(64), u, om, 0.1 * k, 1e4, source=f"run {k}"))
    return out


def _params(terms: tuple[str, ...], values: tuple[float, ...]) -> AugParams:
    return AugParams(1.0, 0.3, 1.5, terms, np.array(values), np.ones(3), np.full(3, 0.2))


def test_a_rival_set_gets_the_experiment_that_separates_it() -> None:
    """pairs._rivals on real models: a rival set passed over for its law only (fits as well, law p above
    the floor) is an alternative of the member it replaces, with the design where the two models' outputs
    differ most (a tested experiment at another amplitude or frequency), its correlation undefined (NaN,
    None in to_dict); two identical models are separated by none of the designs."""
    exps = _exps()
    for i, e in enumerate(exps):  # data from the chosen set, so that the costs mean something
        exps[i] = AugExperiment(
            augmented_output(e, _params((A, B), (0.1, 0.02)), i, substeps=2), e.amplitude, e.frequency,
            e.grid_phase, e.weight, source=e.source,
        )  # fmt: skip
    chosen_fit = SimpleNamespace(params=_params((A, B), (0.1, 0.02)), cost=150.0)
    rival_fit = SimpleNamespace(params=_params((A, S), (0.1, 0.09)), cost=150.0)
    chosen = pairs.PairTrial((A, B), 150.0, 50.0, (1e-4, 1e-4), (0.4, 0.4), fit=cast(Any, chosen_fit))
    floor = select.PREFERRED_LAW_FLOOR
    rival = pairs.PairTrial((A, S), 150.0, 50.0, (1e-4, 1e-4), (0.4, 2 * floor), fit=cast(Any, rival_fit))
    (alt,) = pairs._rivals(exps, chosen, [rival], [], 2)
    assert (alt.term, alt.rival) == (B, S)
    assert (
        alt.separating_experiment.startswith("run ") and "predicted difference" in alt.separating_experiment
    )
    assert np.isnan(alt.correlation) and alt.to_dict()["correlation"] is None
    same = select._separating(exps, cast(Any, chosen_fit), cast(Any, chosen_fit), 2)
    assert same.startswith("none of the designs")

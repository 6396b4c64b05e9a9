"""The library's terms in the time-domain Wiener fit (issue #20, item 1: "the Wiener cascade ... and the
library's terms").

Claims tested on data made another way than the library's simulator (benches/timedomain.py
``clean_with_term``: solve_ivp on ``tf2ss`` of G with the terms' states and the analytic input; play by the
exact operator on a 64x finer grid with Bouc-Wen integrated along the played path), on a resonant G and a
first-order G with a delay, multisine and random inputs.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.errors import InsufficientDataError, InvalidParameterError, NonFiniteError, TimeAxisError
from bouc_wen_id.terms import (
    TERMS,
    Asymmetry,
    Coulomb,
    Dahl,
    DahlSigma,
    Degradation,
    Distortion,
    Inertia,
    Offset,
    Place,
    Play,
    SensorLag,
    Stiffness,
    Term,
    Viscous,
    core_terms,
)
from bouc_wen_id.timedomain import Structure
from bouc_wen_id.timedomain._records import as_time_records
from bouc_wen_id.timedomain._terms import FD_STEP, REGRESSOR_TERMS, term_bounds, time_domain_terms
from bouc_wen_id.timedomain._wiener import Problem

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("timedomain")

DIFFERENCED = tuple(cls for cls in time_domain_terms() if cls not in REGRESSOR_TERMS)


def _make(kind: type[Term], value: float) -> Term:
    return kind(value)  # type: ignore[call-arg]


def _short(ci: int, duration: float = 3.0, **kw: Any) -> Any:
    return replace(bench.CASES[ci], duration=duration, **kw)


def _structure(case: Any, *terms: type[Term]) -> Structure:
    return Structure(len(case.num) - 1, len(case.den) - 1, delay=case.delay > 0, terms=terms)


def test_every_registry_term_with_a_simulation_form_is_fittable_and_distortion_is_refused() -> None:
    expected = []
    for cls in TERMS.values():
        if cls.companion or cls.part_of:  # Dahl friction: simulated, refused by the fit (its own test)
            continue
        try:
            core_terms([cls(0.0)])  # type: ignore[call-arg]
            expected.append(cls)
        except (InvalidParameterError, TypeError):
            pass
    assert time_domain_terms() == tuple(expected) and Distortion not in expected
    # Both places of the mechanical terms.
    for cls in (Viscous, Coulomb, Stiffness, Inertia):
        assert cls in time_domain_terms() and cls.at(Place.X) in time_domain_terms()
    case = _short(0, 2.0)
    t, u, y = bench.clean_with_term(case, Offset, 0.0)
    with pytest.raises(InvalidParameterError, match=Distortion.kind):
        bw.fit_time_domain((t, u, y), start=case.plant(), terms=(Distortion.kind,))
    with pytest.raises(InvalidParameterError, match="no_such_term"):
        bw.fit_time_domain((t, u, y), start=case.plant(), terms=("no_such_term",))
    # Dahl friction is simulated but its two parameters are one element: refused by name, with the reason.
    for dahl in (Dahl, DahlSigma, Dahl.at(Place.X)):
        with pytest.raises(InvalidParameterError, match=f"{dahl.kind!r}.*two-parameter element"):
            bw.fit_time_domain((t, u, y), start=case.plant(), terms=(dahl.kind,))


def test_the_search_box_is_each_terms_admissible_and_physical_range() -> None:
    s = Structure(0, 2, terms=time_domain_terms())
    lo, hi = s.bounds(
        s.pack(bw.WienerPlant(bw.TransferFunction([1.0], [1.0, 2.0, 1.0]), bw.BoucWen(1, 0, 2))), 1.0
    )
    for j, cls in enumerate(s.terms):
        a, b = term_bounds(cls)
        assert (lo[s.core_size + j], hi[s.core_size + j]) == (a, b)
        assert a >= cls.physical[0] and a >= cls.bounds[0] and b <= cls.physical[1]
    assert lo[s.names.index("k")] == 0.0  # a passive spring (issue 18's physical range)


def test_differenced_jacobian_matches_the_exact_dual_number_one() -> None:
    """Where both exist (the cascade with the regressor terms), the central differences of the simulator with
    terms equal the dual-number kernel's exact Jacobian."""
    case = _short(1, 2.0)
    t, u, y = bench.clean_with_term(case, Offset, 0.0)
    s = _structure(case, Offset, Stiffness, Viscous)
    plant = bw.WienerPlant(
        case.plant().linear, case.plant().hysteresis, (Offset(0.1), Stiffness(0.3), Viscous(0.01))
    )
    theta = s.pack(plant)
    recs = as_time_records((t, u, y))
    exact = Problem(s, recs, [0], 2, "rust")
    diff = Problem(s, recs, [0], 2, "rust", jacobian="difference")
    y1, j1 = exact.simulate(theta, 0)
    y2, j2 = diff.simulate(theta, 0)
    np.testing.assert_allclose(y2, y1, atol=1e-11 * np.max(np.abs(y1)))
    for i in np.flatnonzero(s.free):
        size = np.max(np.abs(j1[:, i]))
        assert size > 0 and np.max(np.abs(j2[:, i] - j1[:, i])) < 1e-6 * size, s.names[i]


@pytest.mark.parametrize("cls", DIFFERENCED, ids=lambda c: c.kind)
def test_each_terms_jacobian_against_differences_at_another_step(cls: type[Term]) -> None:
    """Per term: the search's Jacobian (steps FD_STEP x scale) against central differences 30x wider. Smooth
    terms agree everywhere; play's map is non-smooth (the mode switches), so it is held to the same bound
    away from them: at 99 % of the samples."""
    case = _short(0 if cls.acts_on is Place.X else 1, 2.0)
    t, u, _ = bench.clean_with_term(case, Offset, 0.0)
    s = _structure(case, cls)
    value = bench.TERM_VALUES.get(
        cls, 0.05 * cls.scale_factor(1.0, 1.0, case.mu)
    )  # a new term: a small value
    theta = s.pack(bench.term_plant(case, cls, value))
    p = Problem(s, as_time_records((t, u, u)), [0], 2, "rust", scale=1.0)
    _, jac = p.simulate(theta, 0)
    scales = s.scales(theta, 1.0, float(np.std(u)), t[1] - t[0])
    share = 0.99 if cls is Play else 1.0
    for i in np.flatnonzero(s.free):
        h = 30 * FD_STEP * max(abs(theta[i]), scales[i])
        hi, lo = theta.copy(), theta.copy()
        hi[i] += h
        lo[i] -= h
        fd = (p.output(hi, 0) - p.output(lo, 0)) / (2 * h)
        size = np.max(np.abs(jac[:, i]))
        assert size > 0, s.names[i]
        err = np.abs(fd - jac[:, i]) / size
        assert np.quantile(err, share) < 1e-5, (s.names[i], float(np.quantile(err, share)))


def test_the_differenced_path_runs_alike_on_rust_and_on_the_numpy_oracle() -> None:
    rng = np.random.default_rng(7)
    n = 160
    t = np.arange(n) / 200.0
    u = np.convolve(rng.standard_normal(n + 8), np.ones(8) / 8, "valid")[:n]
    case = _short(0)
    kinds = (SensorLag, Asymmetry, Play, Degradation, Viscous.at(Place.X), Coulomb)
    s = _structure(case, *kinds)
    plant = bw.WienerPlant(
        case.plant().linear, case.plant().hysteresis, tuple(_make(k, rng.uniform(0.005, 0.05)) for k in kinds)
    )
    theta = s.pack(plant)
    rec = as_time_records((t, u, u))
    r1, j1 = Problem(s, rec, [0], 2, "rust").residuals(theta)
    r2, j2 = Problem(s, rec, [0], 2, "numpy").residuals(theta)
    np.testing.assert_allclose(r2, r1, atol=1e-9 * np.max(np.abs(r1)))
    np.testing.assert_allclose(j2, j1, atol=1e-5 * np.max(np.abs(j1)))


@pytest.mark.parametrize("row", bench.TERM_ROWS, ids=lambda r: r[1].kind)
def test_terms_are_recovered_on_independent_data(row: tuple[int, type[Term]]) -> None:
    """Two noise seeds per term: the term's estimate and every other parameter within 3.5 SE of the truth,
    the residual RMS at the noise (10 %), the whiteness test passing at 1 %."""
    ci, kind = row
    case = _short(ci)
    value = bench.TERM_VALUES[kind]
    t, u, y = bench.clean_with_term(case, kind, value)
    s = _structure(case, kind)
    truth = s.pack(bench.term_plant(case, kind, value))[s.free]
    p0 = bench.perturbed_start(case)
    start = bw.WienerPlant(p0.linear, p0.hysteresis, (_make(kind, 0.5 * value),))
    sd = case.noise * float(np.std(y))
    for seed in range(2):
        yn = y + sd * np.random.default_rng(30_000 + seed).standard_normal(y.size)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = bw.fit_time_domain((t, u, yn), start=start, delay=case.delay > 0, multistart=False)
        assert fit.converged
        se = np.array([fit.standard_errors[n] for n in fit.parameter_names])
        assert np.all(np.abs(fit.parameters - truth) < 3.5 * se), dict(
            zip(fit.parameter_names, (fit.parameters - truth) / se)
        )
        assert fit.rmse == pytest.approx(sd, rel=0.1)
        assert not fit.adequacy.rejects(0.01)
        assert [type(x) for x in fit.plant.terms] == [kind]
        assert kind.kind in fit.summary() and "central differences" in fit.summary()


@pytest.mark.parametrize("kind", [SensorLag, Play, Viscous.at(Place.X)], ids=lambda c: c.kind)
def test_terms_are_recovered_from_a_random_input(kind: type[Term]) -> None:
    ci = 0 if kind.acts_on is Place.X else 1
    case = _short(ci, random=True)
    value = bench.TERM_VALUES[kind]
    t, u, y = bench.clean_with_term(case, kind, value, 3)
    sd = case.noise * float(np.std(y))
    yn = y + sd * np.random.default_rng(31).standard_normal(y.size)
    p0 = bench.perturbed_start(case)
    start = bw.WienerPlant(p0.linear, p0.hysteresis, (_make(kind, 0.5 * value),))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain((t, u, yn), start=start, delay=case.delay > 0, multistart=False)
    lo, hi = fit.interval(kind.symbol)
    assert lo < value < hi
    assert fit.rmse == pytest.approx(sd, rel=0.1)
    # validate simulates the fitted model with its term (its own substeps): the same residuals to 1e-3.
    assert bw.validate(fit, t, u, yn).rmse == pytest.approx(fit.rmse, rel=1e-3)


@pytest.mark.parametrize("kind", [Degradation, Inertia.at(Place.X)], ids=lambda c: c.kind)
def test_terms_on_a_resonant_plant_with_a_delay(kind: type[Term]) -> None:
    """The resonant G with a delay of 17 ms (fitted), a state term and a term on x."""
    case = replace(_short(0), delay=0.017)
    value = bench.TERM_VALUES[kind]
    t, u, y = bench.clean_with_term(case, kind, value)
    sd = case.noise * float(np.std(y))
    yn = y + sd * np.random.default_rng(32).standard_normal(y.size)
    p0 = bench.perturbed_start(case)
    start = bw.WienerPlant(p0.linear, p0.hysteresis, (_make(kind, 0.5 * value),))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain((t, u, yn), start=start, delay=True, multistart=False)
    s = _structure(case, kind)
    truth = s.pack(bench.term_plant(case, kind, value))[s.free]
    se = np.array([fit.standard_errors[n] for n in fit.parameter_names])
    assert "delay" in fit.parameter_names
    assert np.all(np.abs(fit.parameters - truth) < 3.5 * se), dict(
        zip(fit.parameter_names, (fit.parameters - truth) / se)
    )
    assert fit.rmse == pytest.approx(sd, rel=0.1)


def test_several_terms_at_once_on_independent_data() -> None:
    """A sensor lag, asymmetry, strength degradation and viscous damping on x together on the resonant G."""
    case = _short(0, 4.0)
    kinds = (SensorLag, Asymmetry, Degradation, Viscous.at(Place.X))
    pairs = tuple((k, bench.TERM_VALUES[k]) for k in kinds)
    t, u, y = bench.clean_with_terms(case, pairs)
    sd = case.noise * float(np.std(y))
    yn = y + sd * np.random.default_rng(33).standard_normal(y.size)
    p0 = bench.perturbed_start(case)
    start = bw.WienerPlant(p0.linear, p0.hysteresis, tuple(_make(k, 0.5 * v) for k, v in pairs))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain((t, u, yn), start=start, multistart=False)
    s = _structure(case, *kinds)
    truth_plant = bw.WienerPlant(
        case.plant().linear, case.plant().hysteresis, tuple(_make(k, v) for k, v in pairs)
    )
    truth = s.pack(truth_plant)[s.free]
    se = np.array([fit.standard_errors[n] for n in fit.parameter_names])
    assert fit.converged and fit.parameter_names[-4:] == tuple(k.symbol for k in kinds)
    assert np.all(np.abs(fit.parameters - truth) < 3.5 * se), dict(
        zip(fit.parameter_names, (fit.parameters - truth) / se)
    )
    assert fit.rmse == pytest.approx(sd, rel=0.1) and not fit.adequacy.rejects(0.01)


def test_bad_records_with_terms_are_named() -> None:
    case = _short(1, 2.0)
    t, u, y = bench.clean_with_term(case, SensorLag, 0.01)
    lagged = bw.WienerPlant(case.plant().linear, case.plant().hysteresis, (_make(SensorLag, 0.2),))
    # A record shorter than the model's memory: 3 time constants of G (0.15 s) + the delay + 3 of the lag.
    n = int(0.5 * case.fs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bw.fit_time_domain((t[:n], u[:n], y[:n]), start=case.plant(), terms=(SensorLag.kind,), max_iter=1)
    with pytest.raises(InsufficientDataError, match="memory"):
        bw.fit_time_domain((t[:n], u[:n], y[:n]), start=lagged, max_iter=1)
    bad = y.copy()
    bad[5] = np.nan
    with pytest.raises(NonFiniteError):
        bw.fit_time_domain((t, u, bad), start=lagged)
    back = t.copy()
    back[10], back[11] = back[11], back[10]
    with pytest.raises(TimeAxisError):
        bw.fit_time_domain((back, u, y), start=lagged)

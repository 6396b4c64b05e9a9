"""Honest verdicts on data the library did not make (issue 18): a term's law, physical ranges, whole blocks.

The records here come from an independent NumPy integrator (this file's own: G first order or resonant with
a delay solved by RK4 in time, the Bouc-Wen element by RK4 on the same grid, its own seeded noise), not
from the library's simulator.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.data import DiagExperiment, prepare
from bouc_wen_id.diagnosis.drift import whole_blocks
from bouc_wen_id.terms import TERMS, Place, Stiffness, physical_value

TWO_PI = 2.0 * math.pi
P = 96


BETA, GAMMA, MU = 0.7, 0.3, 1.8


def _plant(shape: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """(A, B, C, delay, centre frequency) of G: first order, or resonant (zeta 0.3) with a delay."""
    if shape == "first":
        wc = TWO_PI * 2.0
        return np.array([[-wc]]), np.array([1.0]), np.array([wc]), 0.0, wc
    wn, zeta = TWO_PI * 2.0, 0.3
    a_mat = np.array([[0.0, 1.0], [-wn * wn, -2 * zeta * wn]])
    return a_mat, np.array([0.0, 1.0]), np.array([wn * wn, 0.0]), 0.02, wn


def _integrate(shape: str, amp: float, om: float, n: int, extra: str, size: float) -> np.ndarray:
    """w at n samples (P per period) of G's states and the Bouc-Wen element by RK4 together, from rest."""
    a_mat, b_vec, c_vec, delay, centre = _plant(shape)
    dt = TWO_PI / om / P
    sub = 4
    h = dt / sub
    vref = 1.5 * centre

    def rhs(t: float, st: np.ndarray, w: float) -> tuple[np.ndarray, float]:
        u = amp * math.cos(om * (t - delay)) if t >= delay else 0.0
        dst = a_mat @ st + b_vec * u
        xd = float(c_vec @ dst)
        bt = BETA * (math.exp(size * math.tanh(abs(xd) / vref - 1.0)) if extra == "rate_width" else 1.0)
        aw = abs(w) ** (MU - 1.0)
        return dst, xd - bt * abs(xd) * aw * w - GAMMA * xd * aw * abs(w)

    st = np.zeros(len(b_vec))
    w = 0.0
    y = np.zeros(n)
    for j in range(n):
        y[j] = w
        for q in range(sub):
            tt = j * dt + q * h
            k1 = rhs(tt, st, w)
            k2 = rhs(tt + h / 2, st + h / 2 * k1[0], w + h / 2 * k1[1])
            k3 = rhs(tt + h / 2, st + h / 2 * k2[0], w + h / 2 * k2[1])
            k4 = rhs(tt + h, st + h * k3[0], w + h * k3[1])
            st = st + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            w = w + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return y


def _records(
    seed: int,
    shape: str,
    extra: str = "",
    size: float = 0.0,
    periods: int = 12,
    settle: int = 8,
) -> list[bw.Recording]:
    """Sine records of a Wiener-Bouc-Wen plant integrated here (:func:`_integrate`), 1 % noise.

    ``extra``: "viscous_u" (c du/dt added to the output), "rate_width" (beta grows with |dx/dt|: outside
    the library), "" (plain). ``size`` scales it."""
    rng = np.random.default_rng([seed, 5])
    a_mat, b_vec, c_vec, delay, centre = _plant(shape)
    out = []
    for om in centre * np.array([0.6, 1.0, 1.5]):
        for level in (1.3, 3.0):
            s = 1j * om
            g = complex(c_vec @ np.linalg.solve(s * np.eye(len(b_vec)) - a_mat, b_vec)) * np.exp(-s * delay)
            amp = level / abs(g)
            n = (settle + periods) * P
            y = _integrate(shape, amp, float(om), n, extra, size)
            t = np.arange(n) * (TWO_PI / om / P)
            u = amp * np.cos(om * t)
            if extra == "viscous_u":
                y = y - size * amp * om * np.sin(om * t)
            y = y + rng.normal(0.0, 0.01, n)
            out.append(bw.Recording(t, u, y, amp, float(om), settle_periods=settle))
    return out


def test_stiffness_has_a_physical_range_at_both_places() -> None:
    """A passive spring's force follows its displacement: k >= 0 on u and on x; a negative k is said."""
    for place in Stiffness.places:
        cls = Stiffness.at(place)
        assert physical_value(cls.kind, 0.3) and not physical_value(cls.kind, -0.3)
        assert "negative stiffness" in cls.unphysical
    assert Stiffness.at(Place.X).kind in TERMS


@pytest.mark.parametrize("shape", ["first", "resonant"])
def test_a_rate_dependent_loop_width_is_not_named_as_library_physics(shape: str) -> None:
    """A loop whose width grows with rate (outside the library) drew "explained in part by viscous damping"
    (59 % of the excess): the viscous value that fits it differs between experiments, so its law fails."""
    d = bw.diagnose(_records(3, shape, "rate_width", 0.4))
    assert d.status == "unexplained", d.summary()
    assert d.named == ()
    assert any(st.law_failed for st in d.steps), d.summary()
    assert "differs between experiments" in d.verdict


def test_a_library_term_keeps_its_law() -> None:
    """Viscous damping on u (library physics): its value is the same in every experiment, it is named."""
    recs = _records(4, "resonant", "viscous_u", 0.004)
    d = bw.diagnose(recs)
    assert [t.term for t in d.named] == ["viscous"], d.summary()
    step = next(st for st in d.steps if st.chosen == "viscous")
    tr = next(t for t in step.trials if t.term == "viscous")
    assert math.isfinite(tr.law_p_value) and tr.law_p_value >= 0.05


def test_law_test_rejects_a_value_that_differs_between_experiments() -> None:
    """The score test itself: an effect c_i du/dt whose c doubles from experiment to experiment is
    rejected; one shared c is not."""
    from bouc_wen_id.diagnosis.fitting import fit_plain, fit_with, scale_of, scaled, substeps_for
    from bouc_wen_id.diagnosis.select import law_test

    recs = _records(6, "first")
    ps = []
    for vary in (False, True):
        rr = []
        for i, r in enumerate(recs):
            c = 0.004 * (2.0 ** (i % 3) if vary else 1.0)
            rr.append(replace(r, y=r.y - c * r.amplitude * r.frequency * np.sin(r.frequency * r.t)))
        exps = prepare(rr)
        s = scale_of(exps)
        sx = scaled(exps, s)
        sub = substeps_for([e.ybar.size for e in sx])
        f = fit_with(sx, fit_plain(exps, sx, s, sub), "viscous", sub)
        assert f is not None
        ps.append(law_test(sx, f, "viscous", sub))
    assert ps[0] >= 0.01 and ps[1] < 1e-6, ps


def _law_p_values(shape: str, distortion: float) -> tuple[list[float], list[float]]:
    """(law p-values, chi2/dof) of viscous damping on u fitted to records with an unmodelled distortion:
    each experiment's output gets its own waveform at harmonics 2-5 (seeded phases, ``distortion`` per
    harmonic: a fixture's response no library term models), with c shared, then with c doubling from
    experiment to experiment."""
    from bouc_wen_id.diagnosis.fitting import fit_plain, fit_with, scale_of, scaled, substeps_for
    from bouc_wen_id.diagnosis.select import dof_of, law_test

    recs = _records(6, shape)
    ps, chi = [], []
    for vary in (False, True):
        rr = []
        for i, r in enumerate(recs):
            rng = np.random.default_rng([i, 9])
            th = r.frequency * r.t
            extra = sum(np.cos(h * th + rng.uniform(0.0, TWO_PI)) for h in range(2, 6))
            c = 0.004 * (2.0 ** (i % 3) if vary else 1.0)
            rr.append(replace(r, y=r.y + distortion * extra - c * r.amplitude * r.frequency * np.sin(th)))
        exps = prepare(rr)
        s = scale_of(exps)
        sx = scaled(exps, s)
        sub = substeps_for([e.ybar.size for e in sx])
        f = fit_with(sx, fit_plain(exps, sx, s, sub), "viscous", sub)
        assert f is not None
        ps.append(law_test(sx, f, "viscous", sub))
        chi.append(f.cost / dof_of(sx, f))
    return ps, chi


@pytest.mark.parametrize(("shape", "distortion"), [("resonant", 0.02), ("first", 0.02), ("resonant", 0.005)])
def test_a_law_holds_under_an_unmodelled_misfit(shape: str, distortion: float) -> None:
    """A misfit sits in a few harmonics, correlated over each experiment's samples, and leaks into the
    per-experiment values; against the residual variance per sample that leak was "significant" (p = 6e-7 to
    0.015 on the shared c here; the MR damper's terms at 1e-58..0.007). Against each experiment's own
    residual spectrum the shared c keeps its law while the model misfits at chi2/dof > 5, and a c that
    differs between experiments is still rejected under the same misfit."""
    ps, chi = _law_p_values(shape, distortion)
    assert chi[0] > 5.0, chi
    assert ps[0] >= 0.05 and ps[1] < 1e-6, (ps, chi)


def test_outside_physics_of_the_bench_generator_stays_unnamed() -> None:
    """A rate-dependent loop width made by the bench's own generator (benches/generator.py: G in closed
    form, its own RK4 and noise; a resonant or first-order plant per seed): no library name under the
    misfit-robust law test."""
    import importlib
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
    gen = importlib.import_module("generator")
    case = gen.make_case("outside", "rate_width", "", 10.0, 31000)
    d = bw.diagnose(case.recordings)
    assert d.named == (), d.summary()
    assert d.status == "unexplained", d.summary()


def _exp(blocks: int, samples: np.ndarray, periods: np.ndarray) -> DiagExperiment:
    rng = np.random.default_rng(1)
    coef = rng.normal(0.0, 1.0, (blocks, 8)) + 1j * rng.normal(0.0, 1.0, (blocks, 8))
    return DiagExperiment(
        frequency=TWO_PI,
        amplitude=1.0,
        grid_phase=0.0,
        ybar=np.zeros(64),
        periods=float(periods.sum()),
        noise_var=1e-4,
        spread_var=1e-4,
        noise_dof=640,
        dc=np.zeros(4),
        h1=np.ones(4, dtype=complex),
        source="e",
        block_coef=coef.astype(np.complex128),
        block_samples=samples,
        block_center=np.arange(float(blocks)),
        block_periods=periods,
    )


def test_blocks_of_fewer_whole_periods_are_kept() -> None:
    """12 periods in 8 runs: blocks of 2 and of 1 whole period. Raw sizes against their median dropped the
    four single-period blocks of every experiment as "not whole periods"; per period spanned they are whole.
    A block cut mid-period (166 of 401 samples per period) is still left out."""
    per = np.array([2.0, 2, 2, 2, 1, 1, 1, 1])
    assert whole_blocks(_exp(8, 64.0 * per, per)).tolist() == list(range(8))
    lab = np.array([1.0, 1, 1, 1, 1])
    assert whole_blocks(_exp(5, np.array([166.0, 401, 401, 400, 401]), lab)).tolist() == [1, 2, 3, 4]


def test_a_recording_of_twelve_periods_keeps_every_block() -> None:
    """Through ``prepare``: a Recording whose 12 averaged periods split unevenly keeps all its blocks."""
    rng = np.random.default_rng(0)
    n = 20
    t = np.arange(n * P) / P
    u = np.cos(TWO_PI * t)
    y = np.tanh(2 * u) + rng.normal(0.0, 0.01, t.size)
    (e,) = prepare([bw.Recording(t, u, y, 1.0, TWO_PI, settle_periods=8)])
    assert e.blocks == 8 and sorted(set(e.block_periods.tolist())) == [1.0, 2.0]
    assert whole_blocks(e).size == 8


def test_places_within_the_misfit_are_alternatives(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two places whose costs differ by less than chi2(1)'s 5 % point times the chosen model's chi2/dof are
    alternatives: with a misfit of chi2/dof 100 (the MR damper's), a difference of 50 is within it; on a
    model at the noise floor the same 50 separates the places."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import select

    monkeypatch.setattr(select, "fit_with", lambda *a, **k: None)
    exps = [SimpleNamespace(ybar=np.zeros(100), grid_phase=0.0) for _ in range(4)]
    par = SimpleNamespace(terms=("viscous",), gains=np.ones(4), phases=np.zeros(4))
    fit = SimpleNamespace(params=par)
    dof = 400 - (3 + 1 + 8)

    def trial(term: str, cost: float) -> select.Trial:
        return select.Trial(term, cost, 0.0, 0.0, 0.0, 0.0, 1.0, True, fit=fit)  # type: ignore[arg-type]

    for chi2dof, expect in ((100.0, ["viscous@x"]), (1.0, [])):
        chosen = trial("viscous", chi2dof * dof)
        rivals = [chosen, trial("viscous@x", chi2dof * dof + 50.0)]
        alts = select.place_alternatives(exps, chosen, rivals, 2)  # type: ignore[arg-type]
        assert [a.rival for a in alts] == expect


def test_a_term_at_its_null_value_is_not_a_candidate() -> None:
    """A term fitted at 0 (a sensor lag of 0 +- 0.0013 s beside a 30x stiffness degradation) is the model
    without it: its "improvement" is the other parameters' refit, so it cannot pass."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis.select import at_null

    def fit(term: str, v: float) -> object:
        return SimpleNamespace(params=SimpleNamespace(terms=(term,), values=np.array([v])))

    assert at_null(fit("sensor_lag", 0.0), "sensor_lag")  # type: ignore[arg-type]
    assert not at_null(fit("sensor_lag", 1e-3), "sensor_lag")  # type: ignore[arg-type]
    assert at_null(fit("offset", 0.0), "offset") and not at_null(fit("offset", -0.2), "offset")  # type: ignore[arg-type]
    assert not at_null(fit("offset", 0.0), "viscous")  # type: ignore[arg-type]


def test_a_budget_error_inside_the_law_test_or_the_separating_design_is_raised(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A budget the user set is theirs: the law test and the separating-design search used to swallow every
    exception (reading a budget stop as "the law is not tested" / "separates nothing"). Other failures of
    the core there still mean exactly that."""
    from types import SimpleNamespace

    from bouc_wen_id.diagnosis import law, select
    from bouc_wen_id.errors import BudgetExceededError, NonFiniteError

    exps = [SimpleNamespace(ybar=np.zeros(10), amplitude=1.0, frequency=1.0, weight=1.0, source="e")] * 2
    par = SimpleNamespace(terms=("viscous",))
    fit = SimpleNamespace(params=par)

    def raiser(exc: Exception) -> Callable[..., None]:
        def f(*a: object, **k: object) -> None:
            raise exc

        return f

    monkeypatch.setattr(select, "replace", lambda e, **k: e)
    for mod in (select, law):  # the law test lives in law.py (re-exported by select)
        monkeypatch.setattr(mod, "augmented_output", raiser(NonFiniteError("x")))
    assert math.isnan(select.law_test(exps, fit, "viscous", 2))  # type: ignore[arg-type]
    assert select._separating(exps, fit, fit, 2).startswith("none of the designs")  # type: ignore[arg-type]
    for mod in (select, law):
        monkeypatch.setattr(mod, "augmented_output", raiser(BudgetExceededError("BOUC_WEN_ID_MAX_STEPS")))
    with pytest.raises(BudgetExceededError):
        select.law_test(exps, fit, "viscous", 2)  # type: ignore[arg-type]
    with pytest.raises(BudgetExceededError):
        select._separating(exps, fit, fit, 2)  # type: ignore[arg-type]

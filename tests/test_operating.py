"""Issue #21 item 3: parameters that follow an operating variable, one joint fit over the levels.

The data are made another way than the fit's model: the time-domain simulator (RK4 from rest, the terms of
design.md 9.4) run to steady state, its last period taken as the averaged period; the fit evaluates the
steady-loop model of design.md 9.2. The truth: a saturation level linear in the variable, the terms linear
in it, the rest constant.
"""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import operating as op
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugExperiment, AugParams, fit_augmented
from bouc_wen_id.errors import InsufficientDataError, InvalidParameterError

TERMS = (T.Offset.kind, T.Viscous.kind, T.Stiffness.kind)
MU, RHO = 1.8, 0.4
#: Per experiment: amplitude U, frequency omega (rad/s).
TESTS = ((1.0, 2.0), (2.0, 5.0))
P = 64
G = bw.TransferFunction([1.0], [0.05, 1.0])


def truth(v: float) -> tuple[bw.WienerPlant, float]:
    """The plant at level v, and its saturation level w_u (linear in v)."""
    w_u = 1.0 + 0.8 * v
    s = w_u ** (-MU)
    h = bw.BoucWen(0.5 * s * (1 + RHO), 0.5 * s * (1 - RHO), MU)
    terms = (T.Offset(0.1 + 0.2 * v), T.Viscous(0.05 + 0.1 * v), T.Stiffness(0.3 - 0.2 * v))
    return bw.WienerPlant(G, h, terms), w_u


def level(v: float, noise: float = 0.0, seed: int = 0) -> list[AugExperiment]:
    plant, _ = truth(v)
    plan = bw.SinePlan(
        [w for _, w in TESTS], [u for u, _ in TESTS], settle_periods=30, periods=1, samples_per_period=P
    )
    rng = np.random.default_rng(seed)
    out = []
    for rec in bw.simulate(plant, plan):
        ybar = np.asarray(rec.y[-P:]) + noise * rng.standard_normal(P)
        out.append(
            AugExperiment(
                ybar=ybar, amplitude=rec.amplitude, frequency=rec.frequency, grid_phase=0.0, weight=1.0
            )
        )
    return out


def level_start(v: float, exps: list[AugExperiment]) -> AugParams:
    """A per-level fit from a start 20 % off the truth (what a user's per-level fits give)."""
    plant, _ = truth(v)
    h = plant.hysteresis
    vals = np.array([t.value for t in plant.terms])
    resp = [complex(G.freqresp(w)) for _, w in TESTS]
    g = np.array([abs(r) for r in resp])
    phi = np.array([-np.angle(r) for r in resp])
    start = AugParams(h.beta * 1.2, h.gamma * 0.8, MU * 1.1, TERMS, vals * 1.2 + 0.01, g * 0.9, phi)
    return fit_augmented(exps, start).params


@pytest.fixture(scope="module")
def data() -> tuple[list[float], list[list[AugExperiment]], list[AugParams]]:
    levels = [0.0, 0.5, 1.0, 1.5]
    exps = [level(v) for v in levels]
    return levels, exps, [level_start(v, e) for v, e in zip(levels, exps)]


def test_coordinates_round_trip_and_their_jacobian() -> None:
    p = AugParams(
        0.7, 0.2, 1.9, TERMS, np.array([0.1, 0.2, 0.3]), np.array([1.5, -2.0]), np.array([0.1, 0.4])
    )
    shared, log_g, phi = op.coordinates_of(p)
    signs = np.sign(p.gains)
    back, jac = op._params_from(shared, log_g, phi, signs, TERMS)
    assert back.beta == pytest.approx(0.7, rel=1e-12) and back.gamma == pytest.approx(0.2, rel=1e-12)
    assert back.mu == pytest.approx(1.9, rel=1e-12) and np.allclose(back.gains, p.gains, rtol=1e-12)
    eps = 1e-6
    for k in range(3):
        step = np.zeros_like(shared)
        step[k] = eps
        hi = op._params_from(shared + step, log_g, phi, signs, TERMS)[0]
        lo = op._params_from(shared - step, log_g, phi, signs, TERMS)[0]
        fd = np.array([hi.beta - lo.beta, hi.gamma - lo.gamma, hi.mu - lo.mu]) / (2 * eps)
        assert np.allclose(jac[:, k], fd, rtol=1e-6, atol=1e-9), (k, jac[:, k], fd)


def test_a_held_out_level_is_predicted_by_the_joint_fit(data: tuple) -> None:  # type: ignore[type-arg]
    """Fit on three levels, predict the fourth (an extrapolation): degree 1 (the truth's) predicts it to the
    integration error, degree 0 (constant parameters) cannot."""
    levels, exps, starts = data
    fit1 = op.fit_operating(levels[:3], exps[:3], starts[:3], 1)
    fit0 = op.fit_operating(levels[:3], exps[:3], starts[:3], 0)
    held1 = max(op.nrmse(e, fit1.params_at(levels[3]), i) for i, e in enumerate(exps[3]))
    held0 = max(op.nrmse(e, fit0.params_at(levels[3]), i) for i, e in enumerate(exps[3]))
    assert held1 < 5e-3 and held0 > 20 * held1, (held1, held0)
    _, w_u = truth(levels[3])
    assert fit1.coordinate("w_u", levels[3]) == pytest.approx(w_u, rel=5e-3)
    assert fit1.coordinate(T.Viscous.kind, 1.2) == pytest.approx(0.05 + 0.1 * 1.2, abs=5e-3)
    assert 1.0 + math.exp(fit1.coordinate("log_mu_minus_1", 0.7)) == pytest.approx(MU, rel=1e-2)


def test_select_degree_rejects_constant_parameters(data: tuple) -> None:  # type: ignore[type-arg]
    levels, exps, starts = data
    choice = op.select_degree(levels, exps, starts, degrees=(0, 1))
    assert choice.degree == 1 and choice.total(0) > 100 * choice.total(1), choice.scores
    assert len(choice.scores[1]) == len(levels)


def test_intervals_cover_the_truth_under_noise() -> None:
    """With white noise on the periods the 95 % interval of w_u and of the viscous damping at every level
    holds the truth, and its width shrinks when the noise does."""
    levels = [0.0, 0.5, 1.0]
    widths = []
    for noise in (0.02, 0.005):
        exps = [level(v, noise, seed=k) for k, v in enumerate(levels)]
        starts = [level_start(v, e) for v, e in zip(levels, exps)]
        fit = op.fit_operating(levels, exps, starts, 1)
        for v in levels:
            value, lo, hi = fit.interval("w_u", v)
            assert lo <= truth(v)[1] <= hi, (noise, v, lo, hi)
            _, clo, chi = fit.interval(T.Viscous.kind, v)
            assert clo <= 0.05 + 0.1 * v <= chi
        widths.append(hi - lo)
    assert widths[1] < 0.5 * widths[0], widths


def test_refit_own_recovers_a_perturbed_gain(data: tuple) -> None:  # type: ignore[type-arg]
    levels, exps, starts = data
    p = starts[1]
    bad = AugParams(
        p.beta,
        p.gamma,
        p.mu,
        p.terms,
        p.values,
        p.gains * np.array([1.3, 1.0]),
        p.phases + np.array([0.2, 0.0]),
    )
    assert op.nrmse(exps[1][0], bad, 0) > 10 * op.nrmse(exps[1][0], op.refit_own(exps[1][0], bad, 0), 0)


def test_named_errors(data: tuple) -> None:  # type: ignore[type-arg]
    levels, exps, starts = data
    with pytest.raises(InvalidParameterError, match="degree"):
        op.fit_operating(levels, exps, starts, 3)
    with pytest.raises(InsufficientDataError, match="needs 3 levels"):
        op.fit_operating(levels[:2], exps[:2], starts[:2], 2)
    with pytest.raises(InvalidParameterError, match="one each"):
        op.fit_operating(levels, exps[:3], starts, 1)
    with pytest.raises(InvalidParameterError, match="distinct"):
        op.fit_operating([0.0, 0.0, 1.0], exps[:3], starts[:3], 1)
    with pytest.raises(InvalidParameterError, match="same experiments"):
        op.fit_operating(levels[:2], [exps[0], exps[1][:1]], starts[:2], 0)
    other = starts[1].only(TERMS[:2])
    with pytest.raises(InvalidParameterError, match="same terms"):
        op.fit_operating(levels[:2], exps[:2], [starts[0], other], 0)
    with pytest.raises(InsufficientDataError, match="two levels"):
        op.select_degree(levels[:1], exps[:1], starts[:1])
    fit = op.fit_operating(levels[:2], exps[:2], starts[:2], 0)
    with pytest.raises(InvalidParameterError, match="unknown coordinate"):
        fit.coordinate("beta", 0.0)


@pytest.mark.parametrize("relative", [False, True])
def test_the_joint_jacobian_is_the_residuals_derivative(data: tuple, relative: bool) -> None:  # type: ignore[type-arg]
    """The chain rule through the coordinates, the polynomial basis and (relative gains) w_u, against
    central differences of the stacked residual."""
    levels, exps, starts = data
    lv = np.asarray(levels[:3])
    signs = np.sign(starts[0].gains)
    prob = op._Problem(lv, exps[:3], TERMS, signs, 1, 0.75, 0.5, relative)
    theta = op._start(prob, starts[:3]) * (
        1 + 0.01 * np.random.default_rng(3).standard_normal(prob.n_coord * 2)
    )
    r, jac = prob.evaluate(theta)
    rng = np.random.default_rng(4)
    for k in rng.choice(theta.size, 8, replace=False):
        h = 1e-6 * max(1.0, abs(theta[k]))
        up, dn = theta.copy(), theta.copy()
        up[k] += h
        dn[k] -= h
        fd = (prob.evaluate(up)[0] - prob.evaluate(dn)[0]) / (2 * h)
        assert np.allclose(jac[:, k], fd, rtol=1e-4, atol=1e-6 * np.max(np.abs(fd)) + 1e-9), (k, relative)


def test_relative_gains_predict_a_level_where_the_gain_follows_the_yield_level() -> None:
    """When the linear part's gain grows with the saturation level (the knee at a fixed travel), the
    relative-gain coordinates are constant in the variable (exact at degree 1, w_u being linear) while log g
    is not: fitted on two levels, they predict the third (an extrapolation) far better."""
    levels = [0.0, 0.5, 1.0]
    exps, starts = [], []
    for v in levels:
        plant, w_u = truth(v)
        scaled = bw.WienerPlant(bw.TransferFunction(G.num * w_u, G.den), plant.hysteresis, plant.terms)
        plan = bw.SinePlan(
            [w for _, w in TESTS], [u for u, _ in TESTS], settle_periods=30, periods=1, samples_per_period=P
        )
        row = [
            AugExperiment(
                ybar=np.asarray(r.y[-P:]),
                amplitude=r.amplitude,
                frequency=r.frequency,
                grid_phase=0.0,
                weight=1.0,
            )
            for r in bw.simulate(scaled, plan)
        ]
        exps.append(row)
        resp = [complex(G.freqresp(w)) * w_u for _, w in TESTS]
        h = plant.hysteresis
        start = AugParams(
            h.beta,
            h.gamma,
            MU,
            TERMS,
            np.array([t.value for t in plant.terms]),
            np.abs(resp),
            -np.angle(resp),
        )
        starts.append(fit_augmented(row, start).params)
    rel = op.fit_operating(levels[:2], exps[:2], starts[:2], 1, relative_gains=True)
    plain = op.fit_operating(levels[:2], exps[:2], starts[:2], 1)
    score_rel = op.held_out_score(rel, levels[2], exps[2])
    score_plain = op.held_out_score(plain, levels[2], exps[2])
    assert score_rel < 1e-5 and score_plain > 10 * score_rel, (score_rel, score_plain)
    assert rel.relative_gains and not plain.relative_gains


def test_the_mr_damper_page_is_what_its_run_wrote() -> None:
    """docs/real-data-operating.md is the study's page of docs/real-data/operating.json (a run of
    studies/operating_point.py), its figure exists, and the chosen degree is the one with the lowest held-out
    score of the run."""
    import importlib.util
    import json
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location(
        "operating_point_study", root / "studies" / "operating_point.py"
    )
    assert spec is not None and spec.loader is not None
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    doc = json.loads((root / "docs" / "real-data" / "operating.json").read_text(encoding="utf-8"))
    page = (root / "docs" / "real-data-operating.md").read_text(encoding="utf-8")
    assert study.page(doc) == page, "run: python studies/operating_point.py --from-json"
    assert (root / "docs" / "real-data" / "operating-parameters.png").stat().st_size > 10_000
    scores = {(k if k == op.MONOTONE else int(k)): v for k, v in doc["score"].items()}
    assert op.MONOTONE in scores and {0, 1, 2} <= set(scores)
    assert doc["degree"] == min(scores, key=lambda d: (scores[d], op.n_basis(d), d == op.MONOTONE))
    assert len(doc["per_level"]) == len(doc["levels_A"]) == 5


# ------------------------------------------------------------------------------ the monotone spline form


def test_the_i_splines_are_monotone_continuous_flat_beyond_and_span_a_line() -> None:
    """Each basis function rises from 0 at z = -1 to 1 at z = 1, never falls, is continuous with a
    continuous slope inside, holds its end value beyond, and c = (-a, a, a) is the line a z over [-1, 1]."""
    z = np.linspace(-2.0, 2.0, 4001)
    basis = np.array([op._ispline(float(v)) for v in z])
    assert np.allclose(op._ispline(-1.0), 0.0) and np.allclose(op._ispline(1.0), 1.0)
    assert np.all(np.diff(basis, axis=0) >= -1e-15)
    assert np.max(np.abs(np.diff(basis, axis=0))) < 2e-3  # continuous
    inside = np.abs(z) <= 1.0
    slope = np.diff(basis[inside], axis=0) / np.diff(z[inside])[:, None]
    assert np.max(np.abs(np.diff(slope, axis=0))) < 5e-3
    assert np.allclose(basis[z < -1.0], 0.0) and np.allclose(basis[z > 1.0], 1.0)
    line = basis[inside] @ np.array([1.0, 1.0]) - 1.0
    assert np.allclose(line, z[inside], atol=1e-12)
    assert op.n_basis(op.MONOTONE) == 3 and op.n_basis(2) == 3


def test_the_monotone_spline_predicts_a_held_out_level_and_stays_monotone(data: tuple) -> None:  # type: ignore[type-arg]
    """Fitted on the outer three levels it predicts the inner fourth as the true degree 1 does (the truth is
    linear, which the spline spans between the levels); beyond the levels it holds the end values; every
    coordinate is monotone in the variable, in the direction of the joint line (w_u rising, the stiffness
    falling)."""
    levels, exps, starts = data
    keep = [0, 1, 3]
    fit = op.fit_operating(
        [levels[k] for k in keep], [exps[k] for k in keep], [starts[k] for k in keep], op.MONOTONE
    )
    assert fit.degree == op.MONOTONE and fit.coef.shape[1] == 3
    held = max(op.nrmse(e, fit.params_at(levels[2]), i) for i, e in enumerate(exps[2]))
    assert held < 5e-3, held
    assert fit.coordinate("w_u", levels[2]) == pytest.approx(truth(levels[2])[1], rel=5e-3)
    assert fit.coordinate("w_u", 3.0) == fit.coordinate("w_u", levels[3])
    assert fit.coordinate("w_u", -1.0) == fit.coordinate("w_u", levels[0])
    grid = np.linspace(-0.5, 2.0, 101)
    for k, name in enumerate(fit.names):
        values = np.array([fit.coordinate(name, v) for v in grid])
        assert np.all(fit.directions[k] * np.diff(values) >= -1e-12), name
    names = list(fit.names)
    assert fit.directions[names.index("w_u")] == 1.0
    assert fit.directions[names.index(T.Stiffness.kind)] == -1.0
    assert np.all(fit.directions[:, None] * fit.coef[:, 1:] >= 0.0)


def test_the_monotone_spline_holds_a_non_monotone_trend_to_its_direction() -> None:
    """Per-level values that rise then fall: a quadratic follows them, the spline cannot (its coefficients
    sit on their bounds): the constraint is real."""
    levels = [0.0, 0.5, 1.0, 1.5]
    exps = [level(v) for v in levels]
    starts = [level_start(v, e) for v, e in zip(levels, exps)]
    bump = [0.0, 0.3, 0.3, 0.0]  # offset added to the data and the starts: up, flat, down
    exps = [
        [AugExperiment(e.ybar + b, e.amplitude, e.frequency, e.grid_phase, e.weight) for e in row]
        for row, b in zip(exps, bump)
    ]
    starts = [
        AugParams(s.beta, s.gamma, s.mu, s.terms, s.values + np.array([b, 0.0, 0.0]), s.gains, s.phases)
        for s, b in zip(starts, bump)
    ]
    quad = op.fit_operating(levels, exps, starts, 2)
    mono = op.fit_operating(levels, exps, starts, op.MONOTONE)
    offs = [mono.coordinate(T.Offset.kind, v) for v in np.linspace(0.0, 1.5, 31)]
    k = list(mono.names).index(T.Offset.kind)
    assert np.all(mono.directions[k] * np.diff(offs) >= -1e-12)
    assert quad.cost < 0.5 * mono.cost, (quad.cost, mono.cost)


def test_monotone_intervals_cover_the_truth_under_noise() -> None:
    """The spline's 95 % band of w_u holds the truth at every level, about as wide as the quadratic's (the
    same number of coefficients), and it narrows with the noise."""
    levels = [0.0, 0.5, 1.0, 1.5]
    widths = []
    for noise in (0.02, 0.005):
        exps = [level(v, noise, seed=10 + k) for k, v in enumerate(levels)]
        starts = [level_start(v, e) for v, e in zip(levels, exps)]
        fit = op.fit_operating(levels, exps, starts, op.MONOTONE)
        quad = op.fit_operating(levels, exps, starts, 2)
        for v in levels:
            _, lo, hi = fit.interval("w_u", v)
            _, qlo, qhi = quad.interval("w_u", v)
            assert lo <= truth(v)[1] <= hi and hi - lo < 2.0 * (qhi - qlo), (noise, v, lo, hi, qlo, qhi)
        widths.append(hi - lo)
    assert widths[1] < 0.5 * widths[0], widths


def test_select_degree_tries_the_spline_and_names_its_errors(data: tuple) -> None:  # type: ignore[type-arg]
    levels, exps, starts = data
    choice = op.select_degree(levels, exps, starts, degrees=(0, op.MONOTONE))
    assert set(choice.scores) == {0, op.MONOTONE}
    # Interior levels predicted to the integration error, the end ones held at the nearest level (no
    # extrapolation): still 3x better than constant parameters.
    assert choice.degree == op.MONOTONE and choice.total(0) > 3 * choice.total(op.MONOTONE), choice.scores
    assert max(choice.scores[op.MONOTONE][1:3]) < 1e-8 < min(choice.scores[0])
    assert op.MONOTONE in op.FORMS
    with pytest.raises(InsufficientDataError, match="monotone spline needs 3 levels"):
        op.fit_operating(levels[:2], exps[:2], starts[:2], op.MONOTONE)
    with pytest.raises(InvalidParameterError, match="monotone"):
        op.fit_operating(levels, exps, starts, "spline")
    far = op.fit_operating(levels, exps, starts, 1)
    with pytest.raises(InvalidParameterError):  # extrapolated out of the model: named, never an OverflowError
        far.params_at(1e12)
    assert (
        op.fit_operating(levels, exps, starts, op.MONOTONE).params_at(1e12).mu > 1.0
    )  # held, not extrapolated

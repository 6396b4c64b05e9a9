"""The estimators beyond the paper: steady-state loop, profile-phase SLS, joint refinement, uncertainty.

Tolerances:
- The steady-loop solver and a long RK4 time-domain run are two discretisations of the same ODE; with
  >= 16 RK4 steps per sample both are accurate to ~1e-8, so they must agree to 1e-6.
- Sensitivities against central differences with h = 1e-6: truncation O(h^2 |w'''|) ~ 1e-12 plus
  rounding O(eps/h) ~ 1e-10, plus the lattice re-discretisation when phi moves (O(h_theta^3) ~ 1e-6 at
  P = 256, 8 substeps), hence 1e-5 relative to the column's scale.
- Parity Rust vs NumPy reference: the same operations in the same order, so the steady loop agrees to
  ~1e-12; the searches agree to their tolerances (the profile's golden search over phi to 1e-9).
"""

from __future__ import annotations

import math
import warnings

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id import reference as ref
from bouc_wen_id.identification import Method
from bouc_wen_id.reference import profile as ref_profile
from bouc_wen_id.result import phase_error
from numpy.testing import assert_allclose

BETA, GAMMA, MU = 0.8, 0.2, 1.6


def single_plant(gain: float = 0.9, phi: float = 1.1, omega: float = 3.0) -> bw.WienerPlant:
    """|G(j omega)| = gain and phase phi at omega: a static gain behind a delay phi/omega."""
    return bw.WienerPlant(bw.TransferFunction([gain], [1.0], delay=phi / omega), bw.BoucWen(BETA, GAMMA, MU))


def plan1(noise: float, periods: int, seed: int = 0, p: int = 256, amplitude: float = 2.0) -> bw.SinePlan:
    return bw.SinePlan(
        [3.0],
        amplitude,
        settle_periods=20,
        periods=periods,
        samples_per_period=p,
        substeps=2,
        noise_sd=noise,
        seed=seed,
    )


# --------------------------------------------------------------------------------------------------
# Steady-state loop solver
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("p", [128, 255, 256])
@pytest.mark.parametrize("amp, phi", [(1.7, 1.1), (0.6, 4.0), (-2.5, 0.3)])
def test_steady_loop_matches_long_time_domain_simulation(p: int, amp: float, phi: float) -> None:
    omega = 3.0
    dt = 2 * math.pi / omega / p
    periods = 40
    _, w = _core.simulate_sine(
        [amp], [1.0], phi / omega, 1.0, BETA, GAMMA, MU, 0.0, 1.0, omega, dt, periods * p, 16
    )
    loop, _, _, _ = _core.steady_loop(amp, BETA, GAMMA, MU, phi, p, 16)
    assert_allclose(loop, w[-p:], atol=1e-6)


def test_steady_loop_is_odd_symmetric_and_bounded() -> None:
    w, _, top, _ = _core.steady_loop(1.5, BETA, GAMMA, MU, 0.7, 256, 8)
    assert_allclose(w[:128], -w[128:], atol=1e-12)
    bound = (1.0 / (BETA + GAMMA)) ** (1.0 / MU)
    assert np.max(np.abs(w)) <= bound
    assert 0 < top <= bound


@pytest.mark.parametrize("p", [64, 101])
def test_steady_loop_sensitivities_match_finite_differences(p: int) -> None:
    params = np.array([0.7, 0.25, 1.8, 1.4, 0.9])  # beta, gamma, mu, A, phi

    def loop(v: np.ndarray) -> np.ndarray:
        return _core.steady_loop(v[3], v[0], v[1], v[2], v[4], p, 16)[0]

    _, jac, _, _ = _core.steady_loop(params[3], params[0], params[1], params[2], params[4], p, 16)
    h = 1e-6
    for k in range(5):
        step = np.zeros(5)
        step[k] = h
        fd = (loop(params + step) - loop(params - step)) / (2 * h)
        assert_allclose(jac[:, k], fd, atol=1e-5 * max(1.0, np.max(np.abs(fd))), err_msg=f"column {k}")


# --------------------------------------------------------------------------------------------------
# Profile-phase SLS and gain profiling
# --------------------------------------------------------------------------------------------------


def clean_loop(amp: float, phi: float, p: int, omega: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    w = _core.steady_loop(amp, BETA, GAMMA, MU, phi, p, 8)[0]
    return w, _core.spectral_derivative(w, omega, (p - 1) // 2)


@pytest.mark.parametrize("phi", [0.2, 1.1, 2.9, 4.4])
def test_profile_phase_sls_parity_and_recovery(phi: float) -> None:
    w, wd = clean_loop(2 * 0.9, phi, 96)
    got = _core.profile_phase_sls(w, wd, 2.0, 3.0, 1.0, 10.0, 1e-8, 24)
    want = ref.profile_phase_sls(w, wd, 2.0, 3.0, 1.0, 10.0, 1e-8, 24)
    # Nested golden searches: phi to 1e-9, mu to 1e-8; a flip of one comparison moves mu by ~tol.
    assert_allclose(got[:5], want[:5], rtol=1e-6, atol=1e-6)
    assert got[6] == want[6]
    est_phi, est_mu, est_g, est_beta, est_gamma = got[:5]
    assert est_g > 0
    assert abs(phase_error(est_phi, phi)) < 0.01
    assert est_g == pytest.approx(0.9, rel=0.02)
    assert est_beta == pytest.approx(BETA, abs=0.05)
    assert est_gamma == pytest.approx(GAMMA, abs=0.05)
    assert est_mu == pytest.approx(MU, abs=0.05)


def test_profile_phase_gain_parity_and_recovery() -> None:
    w, wd = clean_loop(1.3, 2.4, 128, omega=5.0)
    got = _core.profile_phase_gain(w, wd, 1.0, 5.0, BETA, GAMMA, MU, 32)
    want = ref.profile_phase_gain(w, wd, 1.0, 5.0, BETA, GAMMA, MU, 32)
    assert_allclose(got, want, rtol=1e-8, atol=1e-9)
    assert got[0] == pytest.approx(1.3, rel=0.01)
    assert got[1] == pytest.approx(2.4, abs=0.01)


def test_symmetry_canonicalisation() -> None:
    """(G, phi, beta, gamma) ~ (-G, phi + pi, -beta, gamma): the profile must report |G| > 0."""
    w, wd = clean_loop(1.8, 1.1, 128)
    # The cost is pi-periodic in phi: the same fit at phi and phi + pi, with the mirrored parameters.
    yb, yd, s, sgn, dt = ref_profile._phase_sign_inputs(w, wd, 2.0, 3.0, 1.1)
    th1, c1 = ref_profile._sls_cost_signed(yb, yd, s, sgn, dt, MU)
    yb, yd, s, sgn, dt = ref_profile._phase_sign_inputs(w, wd, 2.0, 3.0, 1.1 + np.pi)
    th2, c2 = ref_profile._sls_cost_signed(yb, yd, s, sgn, dt, MU)
    assert c1 == pytest.approx(c2, rel=1e-9, abs=1e-15)
    assert th2[0] == pytest.approx(-th1[0], rel=1e-9)
    assert th2[1] / th2[0] == pytest.approx(-th1[1] / th1[0], rel=1e-9)  # beta -> -beta
    assert th2[2] / th2[0] == pytest.approx(th1[2] / th1[0], rel=1e-9)  # gamma unchanged
    fit = _core.profile_phase_sls(w, wd, 2.0, 3.0, 1.0, 10.0, 1e-8, 24)
    assert fit[2] > 0 and fit[3] > 0


def test_negative_amplitude_gives_the_same_model() -> None:
    plant = single_plant()
    pos = bw.identify(bw.simulate(plant, plan1(0.0, 4)))
    neg = bw.identify(bw.simulate(plant, plan1(0.0, 4, amplitude=-2.0)))
    for name in ("beta", "gamma", "mu"):
        assert getattr(neg, name) == pytest.approx(getattr(pos, name), abs=1e-6)
    assert neg.gains[0] == pytest.approx(pos.gains[0], rel=1e-6)
    assert neg.gains[0] > 0
    # The phase is that of G(j omega) itself, whatever the sign of U.
    assert abs(phase_error(neg.phases[0], pos.phases[0])) < 1e-6
    assert abs(phase_error(pos.phases[0], 1.1)) < 1e-4


# --------------------------------------------------------------------------------------------------
# Joint refinement
# --------------------------------------------------------------------------------------------------


def test_refined_reports_whether_the_lm_converged() -> None:
    recs = bw.simulate(bw.demo_plant(), bw.demo_plan(samples_per_period=128, periods=4, noise_sd=0.01))
    res = bw.identify(recs)
    assert res.converged is True and res.to_dict()["converged"] is True
    with pytest.warns(bw.ConvergenceWarning, match="cap of 2 iterations"):
        capped = bw.identify(recs, max_iter=2)
    assert capped.converged is False and capped.iterations == 2
    assert "before converging" in capped.summary()
    assert bw.identify(recs, method="profile").converged is None


def test_refined_noise_free_recovery_is_tight() -> None:
    plant = bw.demo_plant()
    recs = bw.simulate(
        plant, bw.demo_plan(samples_per_period=512, periods=4, settle_periods=40, noise_sd=0.0)
    )
    res = bw.identify(recs)
    err = res.errors()
    assert res.truth is not None
    # Left: the time-domain RK4 of the simulation (step T/1024) and the transient after 40 periods.
    assert abs(err["beta"]) < 1e-5 and abs(err["gamma"]) < 1e-5 and abs(err["mu"]) < 1e-5
    assert np.max(np.abs(err["gain"]) / res.truth.gain) < 1e-5
    assert np.max(np.abs(err["phase"])) < 1e-5
    assert max(e.nrmse for e in res.experiments) < 1e-5


def test_refined_beats_paper_on_noisy_data() -> None:
    plant = single_plant()
    errs: dict[Method, list[list[float]]] = {"paper": [], "refined": []}
    for seed in range(6):
        recs = bw.simulate(plant, plan1(0.05, 50, seed))
        for method in errs:
            with warnings.catch_warnings():
                # The paper's estimates often violate beta >= |gamma| on noisy data, and say so.
                warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
                e = bw.identify(recs, method=method).errors()
            errs[method].append([e["beta"], e["gamma"]])
    rmse = {m: np.sqrt(np.mean(np.square(v), axis=0)) for m, v in errs.items()}
    assert np.all(rmse["refined"] * 5 < rmse["paper"]), rmse


def test_refined_needs_two_periods() -> None:
    recs = bw.simulate(single_plant(), plan1(0.01, 1))
    with pytest.raises(bw.InsufficientDataError, match="2 averaged periods"):
        bw.identify(recs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
        assert bw.identify(recs, method="paper").mu > 1  # the paper method has no such need


# --------------------------------------------------------------------------------------------------
# Uncertainty and adequacy, checked statistically over fixed seeds
# --------------------------------------------------------------------------------------------------

SEEDS = range(30)


@pytest.fixture(scope="module")
def monte_carlo() -> list[bw.IdentificationResult]:
    plant = single_plant()
    out = []
    for seed in SEEDS:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            out.append(bw.identify(bw.simulate(plant, plan1(0.05, 20, seed, p=128))))
    return out


def test_intervals_cover_the_truth(monte_carlo: list[bw.IdentificationResult]) -> None:
    hits = {name: 0 for name in ("beta", "gamma", "mu")}
    for r in monte_carlo:
        for name, true in (("beta", BETA), ("gamma", GAMMA), ("mu", MU)):
            lo, hi = r.interval(name)
            hits[name] += lo <= true <= hi
    # 30 draws of a 95 % interval: P(<= 24 hits) = 0.016 under Binomial(30, 0.95).
    assert all(h >= 25 for h in hits.values()), hits


def test_adequacy_does_not_flag_model_data_too_often(monte_carlo: list[bw.IdentificationResult]) -> None:
    adequacies = [r.adequacy for r in monte_carlo if r.adequacy is not None]
    assert len(adequacies) == len(monte_carlo)
    rejections = sum(a.rejects(0.05) for a in adequacies)
    # Binomial(30, 0.05): P(>= 6 rejections) = 0.016; a broken statistic rejects far more (or never).
    assert rejections <= 5
    pvals = np.array([a.p_value for a in adequacies])
    # Uniform p-values under the null: the mean of 30 is 0.5 +- 0.053 (1 sd).
    assert 0.3 < pvals.mean() < 0.7


def test_adequacy_flags_a_model_that_is_wrong() -> None:
    # A linear spring in parallel with the hysteresis (y = w + 0.1 x): not a Wiener-Bouc-Wen system.
    plant = single_plant()
    rec = bw.simulate(plant, plan1(0.01, 40))[0]
    assert rec.x is not None
    y = rec.y + 0.1 * rec.x
    bad = bw.Recording(rec.t, rec.u, y, rec.amplitude, rec.frequency, settle_periods=rec.settle_periods)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
        res = bw.identify(bad)
    assert res.adequacy is not None and res.adequacy.rejects(0.01)
    e = res.experiments[0]
    noise_only = e.noise_sd / math.sqrt(e.periods) / float(np.std(e.ybar))  # NRMSE of a perfect model
    assert e.nrmse > 2 * noise_only


def test_standard_errors_match_the_cramer_rao_bound() -> None:
    plant = single_plant()
    plan = plan1(0.05, 50, 0)
    crb = bw.cramer_rao(plant, plan)
    res = bw.identify(bw.simulate(plant, plan))
    assert res.standard_errors is not None
    # The estimated noise variance and the Fisher matrix at the estimate differ from the truth's by
    # O(1/sqrt(P (N-1))) and O(error) respectively: a few percent.
    assert res.standard_errors["beta"] == pytest.approx(crb.beta, rel=0.1)
    assert res.standard_errors["mu"] == pytest.approx(crb.mu, rel=0.1)
    assert res.experiments[0].gain_se == pytest.approx(crb.gain[0], rel=0.1)
    # The table: CRB (|G|, phi, beta, gamma, mu) = .0029 .0051 .020 .018 .018.
    assert_allclose(
        [crb.gain[0], crb.phase[0], crb.beta, crb.gamma, crb.mu],
        [0.0029, 0.0050, 0.0196, 0.0181, 0.0183],
        rtol=0.03,
    )


def test_cramer_rao_rejects_a_noise_free_design() -> None:
    with pytest.raises(bw.InvalidParameterError, match="noise-free"):
        bw.cramer_rao(single_plant(), plan1(0.0, 10))


def test_poorly_identifiable_design_warns() -> None:
    # x stays far below the Bouc-Wen bound: the loop is nearly linear and beta, gamma, mu are not
    # determined by it.
    plant = single_plant()
    recs = bw.simulate(plant, plan1(0.02, 10, amplitude=0.05))
    with pytest.warns(bw.IdentifiabilityWarning):
        res = bw.identify(recs)
    assert res.warnings
    assert "warning:" in res.summary()


@pytest.mark.parametrize("method", ["paper", "profile", "refined"])
def test_units_do_not_matter(method: Method) -> None:
    """Forces of 1500 N and strokes of 5 mm identify as well as unit-scale data, reported in user units."""
    recs = bw.simulate(single_plant(), plan1(0.02, 30, seed=3))
    s_u, s_y = 0.005, 1500.0
    scaled = [
        bw.Recording(r.t, r.u * s_u, r.y * s_y, r.amplitude * s_u, r.frequency, r.settle_periods)
        for r in recs
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
        a = bw.identify(recs, method=method)
        b = bw.identify(scaled, method=method)
    # w = s_y w', x = s_y x': |G| -> |G| s_y / s_u, beta -> beta / s_y^mu, gamma likewise.
    assert b.mu == pytest.approx(a.mu, rel=1e-6)
    assert b.beta == pytest.approx(a.beta / s_y**a.mu, rel=1e-5)
    assert b.gamma == pytest.approx(a.gamma / s_y**a.mu, rel=1e-5)
    assert_allclose(b.gains, a.gains * s_y / s_u, rtol=1e-6)
    assert_allclose(b.phases, a.phases, atol=1e-6)
    assert b.experiments[0].nrmse == pytest.approx(a.experiments[0].nrmse, rel=1e-5)
    if method == "refined":
        assert a.standard_errors is not None and b.standard_errors is not None
        assert a.covariance is not None and b.covariance is not None
        assert a.adequacy is not None and b.adequacy is not None
        assert a.experiments[0].gain_se is not None
        assert b.standard_errors["mu"] == pytest.approx(a.standard_errors["mu"], rel=1e-4)
        assert b.experiments[0].gain_se == pytest.approx(a.experiments[0].gain_se * s_y / s_u, rel=1e-4)
        # The covariance maps through (beta, gamma) -> (beta, gamma) / s_y^mu (delta method): beta's
        # interval in N^-mu carries mu's uncertainty times beta ln(s_y).
        jac = np.diag([s_y**-a.mu, s_y**-a.mu, 1.0])
        jac[0, 2] = -b.beta * math.log(s_y)
        jac[1, 2] = -b.gamma * math.log(s_y)
        assert_allclose(b.covariance[:3, :3], jac @ a.covariance[:3, :3] @ jac.T, rtol=1e-3)
        assert b.adequacy.p_value == pytest.approx(a.adequacy.p_value, rel=1e-4, abs=1e-9)

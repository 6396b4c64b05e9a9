"""The diagnosis's view of the augmented fit: scaled units, starts, and the held-out refit.

All fits of a diagnosis run on data scaled to unit size (``y / s_y``, ``u / s_u``, with ``s_y`` the largest
``|ybar|`` and ``s_u`` the largest ``U``), so that the Levenberg-Marquardt sees parameters of order one
whatever the units; :func:`physical` maps a term's value back (design.md 10.1).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit, AugParams, augmented_output, fit_augmented
from ..errors import BoucWenIdError, BudgetExceededError, SearchAtBoundError
from ..terms import TERMS, Distortion, Place, StartContext
from . import coulomb_width, fit_share, free_dc, g_second, input_dc, speed
from .data import DiagExperiment

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Output terms whose contribution is linear in the parameter: their start is the residual's projection.
LINEAR_TERMS = tuple(k for k, cls in TERMS.items() if cls.linear)
#: Iterations of the held-out refit of one experiment's (g, phi) with the physics frozen.
OWN_MAX_ITER = 50


@dataclass(frozen=True)
class Scale:
    """Data scales: ``y -> y / y``, ``u -> u / u``."""

    y: float
    u: float

    def factor(self, term: str, mu: float) -> float:
        """Physical value of a term's parameter per unit of its scaled value."""
        return TERMS[term].scale_factor(self.y, self.u, mu)


def scale_of(exps: Sequence[DiagExperiment]) -> Scale:
    sy = max(float(np.max(np.abs(e.ybar))) for e in exps)
    su = max(abs(e.amplitude) for e in exps)
    return Scale(sy if sy > 0 else 1.0, su if su > 0 else 1.0)


def scaled(exps: Sequence[DiagExperiment], s: Scale) -> list[AugExperiment]:
    """The experiments in scaled units, each with its own RK4 substep count (:func:`experiment_substeps`)."""
    sizes = [e.ybar.size for e in exps]
    return [
        AugExperiment(
            ybar=np.ascontiguousarray(e.ybar / s.y),
            amplitude=e.amplitude / s.u,
            frequency=e.frequency,
            grid_phase=e.grid_phase,
            weight=e.weight * s.y**2,
            source=e.source,
            waveform=e.waveform,
            substeps=experiment_substeps(e.ybar.size, sizes),
            input_shape=input_shape(e),
        )
        for e in exps
    ]


def input_shape(e: DiagExperiment) -> FloatArray:
    """The measured input as the terms on u see it (``AugExperiment.input_shape``): its mean relative to
    U when measured (``input_dc.measured``), then its own harmonics; empty for a centred pure sine, so such
    fits are the plain sine's. Review 35: the terms saw ``U cos`` alone, so a dashpot on u missed its
    ``3 omega c_3`` at a distorted drive's third harmonic and a spring its share of a preloaded drive's
    mean (which the offset took)."""
    dc = float(e.input_dc) / float(e.amplitude) if input_dc.measured(e) else 0.0
    if not e.waveform.size and dc == 0.0:
        return np.zeros(0)
    return np.concatenate([[dc], np.asarray(e.waveform, dtype=np.float64).ravel()])


#: The gain extrapolated beyond the tested frequencies stays below e^this times the largest tested gain.
EXTRAPOLATED_LOG_GAIN_MAX = math.log(1e3)


def _g_of(freqs: FloatArray, logs: FloatArray, phases: FloatArray, omega: float) -> complex:
    """``G(j omega)`` up to a common scale from ``log|G|`` and the unwrapped phase lag at the sorted, distinct
    ``freqs``: linear in ``log omega`` between them, extended linearly from the two nearest beyond them
    (a first-order roll-off, a delay); flat gain and a lag proportional to omega with one frequency."""
    if freqs.size == 1:
        return complex(np.exp(logs[0]) * np.exp(-1j * phases[0] * omega / freqs[0]))
    lw = np.log(freqs)
    x = math.log(omega)
    if x <= lw[-1]:
        lg = float(np.interp(x, lw, logs))
        ph = float(np.interp(x, lw, phases))
        if x < lw[0]:
            ph = float(phases[0] * omega / freqs[0])
    else:
        slope = (logs[-1] - logs[-2]) / (lw[-1] - lw[-2])
        lg = float(logs[-1] + slope * (x - lw[-1]))
        dph = (phases[-1] - phases[-2]) / (freqs[-1] - freqs[-2])
        ph = float(phases[-1] + dph * (omega - freqs[-1]))
    # A steep slope between two close tested frequencies extrapolates to any gain (math.exp overflowed on
    # the wire-rope files): beyond the band G is not known, so its gain stays within a bound of the tested.
    lg = min(lg, float(np.max(logs)) + EXTRAPOLATED_LOG_GAIN_MAX)
    return complex(math.exp(lg) * np.exp(-1j * ph))


#: A first-order lag with a delay, ``K e^{-s T} / (1 + s tc)``, stands for G between and beyond the tested
#: frequencies when it reproduces every tested ``G(j w_i)`` to this complex-log error (5 % in gain, 0.05
#: rad)...
FOPDT_TOL = 0.05
#: ... and at least this many distinct frequencies pin its three parameters (else the interpolation).
FOPDT_MIN_FREQS = 3
#: Points of the corner-time grid, and golden-section steps refining the best between its neighbours
#: (0.618^30 of a 2.7 % bracket).
FOPDT_GRID = 400
FOPDT_REFINE = 30


def _fopdt(
    freqs: FloatArray, logs: FloatArray, lag: FloatArray
) -> Optional[tuple[float, float, float, float]]:
    """``(log K, tc, T, theta0)`` of the first-order-plus-delay G (lag ``theta0 + atan(w tc) + w T``) closest
    in complex log to the tested points, or None when it misses one by more than :data:`FOPDT_TOL`.

    ``theta0``, the lag at zero frequency, is a whole number of half turns (G is real there: 0, or pi for an
    inverting path): the multiple of pi nearest the free least-squares constant, when the model with it held
    there still reproduces the points; else the free constant. A free constant takes up the points' common
    phase error and passes it to harmonic k multiplied by ``k - 1`` (design.md 9.5).
    For each ``tc`` on a log grid the rest is linear least squares (``log K`` on the log-gains, ``T >= 0`` on
    the lags), and the best ``tc`` is refined between its grid neighbours (golden section); the grid spans two
    decades beyond the tested band either side.
    """
    if freqs.size < FOPDT_MIN_FREQS:
        return None
    basis = np.column_stack([np.ones(freqs.size), freqs])
    grid = np.concatenate([[0.0], np.geomspace(1e-2 / freqs[-1], 1e2 / freqs[0], FOPDT_GRID)])

    def solve(tc: float, th0: Optional[float]) -> tuple[float, float, float, float]:
        roll = 0.5 * np.log1p((freqs * tc) ** 2)
        lk = float(np.mean(logs + roll))
        rest = lag - np.arctan(freqs * tc)
        t0, delay = g_second.phase_line(freqs, rest, th0, basis)
        err = np.hypot(logs - (lk - roll), rest - t0 - freqs * delay)
        return float(err @ err), lk, float(delay), float(t0)

    def fit(th0: Optional[float]) -> Optional[tuple[float, float, float, float]]:
        costs = [solve(float(tc), th0)[0] for tc in grid]
        i = int(np.argmin(costs))
        tc = float(grid[i])
        if 0 < i < grid.size - 1:
            lo, hi = float(grid[i - 1]), float(grid[i + 1])
            g = 0.5 * (math.sqrt(5.0) - 1.0)
            for _ in range(FOPDT_REFINE):  # golden section on the unimodal cost between the neighbours
                a, b = hi - g * (hi - lo), lo + g * (hi - lo)
                if solve(a, th0)[0] < solve(b, th0)[0]:
                    hi = b
                else:
                    lo = a
            tc = 0.5 * (lo + hi)
        _, lk, delay, t0 = solve(tc, th0)
        roll = 0.5 * np.log1p((freqs * tc) ** 2)
        err = np.hypot(logs - (lk - roll), lag - np.arctan(freqs * tc) - t0 - freqs * delay)
        return (lk, tc, delay, t0) if float(np.max(err)) <= FOPDT_TOL else None

    free = fit(None)
    if free is None:
        return None
    # theta0 held at its whole half turns when that still reproduces the points (a plain fit biased by the
    # distortion it leaves out may need the free constant; the fits that include the term do not).
    held = fit(math.pi * round(free[3] / math.pi))
    return held if held is not None else free


def carry_waveforms(exps: Sequence[AugExperiment], fit: AugFit) -> list[AugExperiment]:
    """The inputs' waveforms carried through G at their own frequencies (design.md 9.5).

    The latent x of experiment i has harmonic k ``c'_k = c_k G(j k w_i) / (|G(j w_i)| e^{-i k phi_G})``
    relative to its fundamental, where ``c_k`` is the input's: 1 under the quasi-static G the term assumes
    when nothing else is known. G is known (up to the Bouc-Wen scale, which cancels) at the experiments'
    frequencies from ``fit``'s gains and phases, ``G(j w_i) ~ g_i e^{-i (phi_i + psi_i)}``; between them it is
    taken from a first-order lag with a delay when that reproduces the tested points (:func:`_fopdt`), else
    from a second-order one with a delay when that does (:mod:`.g_second`: a resonance between two tested
    frequencies), else interpolated between them and extended beyond (:func:`_g_of`). Experiments without
    a waveform are returned as given.
    """
    if not any(e.waveform.size for e in exps):
        return list(exps)
    par = fit.params
    # A signed g with its phase is the complex G itself (g < 0 is a half turn).
    gs = np.array([g * np.exp(-1j * (ph + e.grid_phase)) for e, g, ph in zip(exps, par.gains, par.phases)])
    om = np.array([e.frequency for e in exps])
    freqs = np.unique(om)
    # The mean G per frequency (the amplitudes of one frequency share G in a Wiener system).
    gf = np.array([np.mean(gs[om == f]) for f in freqs])
    logs = np.log(np.abs(gf))
    lag = -np.unwrap(np.angle(gf))
    # The phase lag of a causal G starts near 0 at low frequency: remove whole turns from the lowest one.
    lag = lag - 2.0 * math.pi * np.round(lag[0] / (2.0 * math.pi))
    model = _fopdt(freqs, logs, lag)
    # A resonance between tested frequencies: the next model up before the interpolation (g_second.py).
    second = (
        None if model is not None else g_second.second_order(freqs, logs, lag, g_second.TOL, FOPDT_MIN_FREQS)
    )

    def g_at(omega: float) -> complex:
        if second is not None:
            return g_second.at(second, omega)
        if model is None:
            return _g_of(freqs, logs, lag, omega)
        lk, tc, delay, th0 = model
        mag = math.exp(lk - 0.5 * math.log1p((omega * tc) ** 2))
        return complex(mag * np.exp(-1j * (th0 + math.atan(omega * tc) + omega * delay)))

    out = []
    for e in exps:
        if not e.waveform.size:
            out.append(e)
            continue
        g1 = g_at(e.frequency)
        c = e.waveform.reshape(-1, 2)
        carried = np.zeros_like(c)
        for idx, (re, im) in enumerate(c):
            k = idx + 2
            gk = g_at(k * e.frequency)
            # Relative to the quasi-static |G1| e^{-i k phi1}.
            ratio = gk / (abs(g1) * (g1 / abs(g1)) ** k)
            v = complex(re, im) * ratio
            carried[idx] = (v.real, v.imag)
        out.append(replace(e, waveform=carried.ravel()))
    return out


#: Refits of the distortion term whose G re-carries the waveforms, at most (the plain fit's G is biased by
#: the very distortion it leaves out; each refit moves G towards the fixed point, linearly: on the bench's
#: 30x cases two refits left the carried harmonics 2-5 % off and a spurious play term named beside the
#: distortion in 40 % of them, converged ones are within 0.3 %)...
CARRY_REFITS = 8
#: ... stopping once the carried waveforms move by less than this fraction of their size.
CARRY_RTOL = 1e-3


def carry_through_g(exps: Sequence[AugExperiment], plain: AugFit, substeps: int) -> list[AugExperiment]:
    """The waveforms carried through the G of the plain model plus the distortion term fitted on them,
    refitted until they settle (:data:`CARRY_RTOL`, at most :data:`CARRY_REFITS` refits; ``exps`` keep the
    inputs' own waveforms).

    The first fit takes the waveforms as measured (the quasi-static rule, ``c'_k = c_k``), not carried
    through the plain fit's G: the plain fit's phases are biased by the very distortion it leaves out (by
    0.04-0.35 rad on a bench case with harmonics of 5 and 11 % of the fundamental), too far for the
    lag-plus-delay model of G, and the interpolation they fall back on settled on a G whose harmonics named
    play and Coulomb friction beside the distortion (2 of 3 seeds of ``tests/test_distortion.py``'s
    generator at 20 %; none from the quasi-static start, and the same bench rates)."""
    out = list(exps)
    if not any(e.waveform.size for e in exps):
        return out
    for _ in range(CARRY_REFITS):
        f = fit_with(out, plain, Distortion.kind, substeps)
        if f is None:
            break
        new = carry_waveforms(exps, f)
        a = np.concatenate([e.waveform for e in out])
        b = np.concatenate([e.waveform for e in new])
        out = new
        if float(np.linalg.norm(b - a)) <= CARRY_RTOL * float(np.linalg.norm(b)):
            break
    return out


def regressor(term: str, e: AugExperiment, par: AugParams, i: int, substeps: int) -> FloatArray:
    """The contribution per unit parameter of a linear output term on experiment i's grid.

    It is the term's Jacobian column in the core's model output (design.md 9.1), through any sensor lag
    the current model already has, so the formulas live in one place.
    """
    out = augmented_output(e, par.with_term(term, 0.0), i, substeps=substeps, jacobian=True)
    return out.jacobian[:, 3 + len(par.terms)]


def substeps_for(sizes: Sequence[int]) -> int:
    """RK4 steps per sample that serve every experiment's grid: the largest :func:`experiment_substeps`.

    The fits and outputs use each experiment's own count (:attr:`AugExperiment.substeps`, set by
    :func:`scaled`); this one is for what has no experiment of its own (the drift test's simulations).
    """
    return max(experiment_substeps(p, sizes) for p in sizes)


def experiment_substeps(p: int, sizes: Sequence[int]) -> int:
    """RK4 steps per sample of one experiment of ``p`` samples per period among grids of ``sizes``.

    At least 128 steps per period on this grid, and a step of at most 2 pi/512 rad on the finest grid of
    the set (so equal grids get exactly the count they had when one count served all). Coarser than
    identify's 2 pi/2048: every reversal is a node of the loop solvers (design.md 9.2), so the steps stay
    fourth order, and at these counts the error of the MR damper's loops is at most 5.4e-3 of the averaged
    noise's standard deviation at every current (docs/diagnosis-speed.md). One count for all would make
    every fine grid pay for the coarsest (the MR damper's six files: P = 401 ... 37, 4 steps per sample
    for all instead of 2 for five and 4 for one: 3670 RK4 steps per evaluation instead of 7192).
    """
    return max(2, math.ceil(512 / max(sizes)), math.ceil(128 / p))


#: The diagnosis's fits are judged in windows of this many LM iterations...
FIT_CHUNK = 25
#: ... and stop once a window lowers the cost by less than this many reduced chi-squares (``cost / dof``): a
#: change of the F statistic of any test by less than this, of a share of the excess by less than this over
#: the excess in reduced chi-squares. The core's own rule (a relative decrease of 1e-12 per step) never ends
#: a fit that crawls along a bound (mu at 1 with gamma = beta on the MR damper: 200 iterations, every fit);
#: at 0.1 the MR damper's verdicts at 0-0.75 A are those of the full 200 iterations (values within 0.1 %),
#: at 1 A the fourth term (inertia) is no longer named: a term that hangs on where a fit stops.
STALL_CHI2 = 0.1
#: A fit also stops after an accepted step that lowered the cost by at most this many reduced chi-squares when
#: the Gauss-Newton step from its end predicts no more (the quadratic model's whole remaining decrease): an F
#: statistic ``(delta cost / k) / (cost / dof)`` moves by at most this, 0.001, which moves no test's p visibly
#: (docs/diagnosis-speed.md, session 46). 0: no such rule.
STEP_CHI2 = 0.001
#: The rule runs inside the core's one refinement (``fit_augmented``'s ``stall``), its damping carried
#: across the windows; until session 46 each window was a refinement of its own, restarting the damping at
#: 1e-3 (docs/diagnosis-speed.md, session 46). False: those separate refinements.
STALL_IN_CORE = True
#: The per-step stop (:data:`STEP_CHI2`'s rule) of a wide restart's screen (:func:`screen`,
#: ``restarts.wide_fit``): a fit of ``SCREEN_ITER`` iterations whose cost only says whether a wide start
#: beats the term's own fit, the best then finished under :data:`STEP_CHI2`. At :data:`STALL_CHI2`: a step
#: that lowered the cost by at most what ends a whole window, with the quadratic model predicting no more.
#: Not for the candidates' own screens: there it moved MR 0.5 A's partial viscous value by 0.06 se (0.11 se
#: at 0.01; docs/diagnosis-speed.md, session 48). STEP_CHI2: the wide screens as before.
SCREEN_STEP_CHI2 = 0.1


def fit_from(
    exps: Sequence[AugExperiment],
    start: AugParams,
    substeps: int,
    max_iter: int = 200,
    step_chi2: Optional[float] = None,
) -> Optional[AugFit]:
    """One augmented fit of at most ``max_iter`` iterations, ended early once it stalls (:data:`STALL_CHI2`,
    and the per-step rule at ``step_chi2`` reduced chi-squares, :data:`STEP_CHI2` when None); None when the
    start leads nowhere (no steady loop, a rejected constraint). An experiment whose period means were taken
    out (a :class:`.free_dc.FreeDC`) has its DC free (``free_dc.py``)."""
    rule = STEP_CHI2 if step_chi2 is None else float(step_chi2)

    def inner(xs: Sequence[AugExperiment], st: AugParams, sub: int, n: int) -> Optional[AugFit]:
        return _fit_from(xs, st, sub, n, rule)

    return fit_share.refit(
        exps,
        start,
        substeps,
        max_iter,
        lambda: free_dc.fit(exps, start, substeps, max_iter, inner),
        (free_dc.fit, _fit_from, fit_augmented),
        rule,
    )


def screen(exps: Sequence[AugExperiment], start: AugParams, substeps: int) -> Optional[AugFit]:
    """A wide restart's screen of ``start``: :data:`SCREEN_ITER` iterations under the per-step stop at
    :data:`SCREEN_STEP_CHI2` (its cost only ranks the starts; the best is finished by :func:`fit_from`)."""
    return fit_from(exps, start, substeps, max_iter=SCREEN_ITER, step_chi2=SCREEN_STEP_CHI2)


def fit_dof(exps: Sequence[AugExperiment], start: AugParams) -> int:
    """The degrees of freedom of a fit of ``start`` on ``exps`` (the steady parameters, the terms, each
    experiment's gain and phase), at least 1."""
    return max(sum(e.ybar.size for e in exps) - (3 + len(start.terms) + 2 * len(exps)), 1)


def stall_rules(
    exps: Sequence[AugExperiment], start: AugParams, step_chi2: Optional[float] = None
) -> tuple[int, float, float]:
    """The core's stall rules of a fit of ``start`` on ``exps``: its window, the stall over a window
    (:data:`STALL_CHI2`) and the per-step stop (``step_chi2``, :data:`STEP_CHI2` when None), per dof."""
    dof = fit_dof(exps, start)
    return FIT_CHUNK, STALL_CHI2 / dof, (STEP_CHI2 if step_chi2 is None else step_chi2) / dof


def _fit_from(
    exps: Sequence[AugExperiment],
    start: AugParams,
    substeps: int,
    max_iter: int,
    step_chi2: Optional[float] = None,
) -> Optional[AugFit]:
    """:func:`fit_from` without free DCs."""
    dof = fit_dof(exps, start)
    fit: Optional[AugFit] = None
    done = 0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if STALL_IN_CORE:
                stall = stall_rules(exps, start, step_chi2)
                return fit_augmented(exps, start, max_iter=max_iter, substeps=substeps, stall=stall)
            while done < max_iter:
                n = min(FIT_CHUNK, max_iter - done)
                new = fit_augmented(exps, start if fit is None else fit.params, max_iter=n, substeps=substeps)
                done += n
                stalled = fit is not None and fit.cost - new.cost <= STALL_CHI2 * new.cost / dof
                fit = new if fit is None or new.cost <= fit.cost else fit
                if new.converged or stalled:
                    break
    except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
        raise
    except BoucWenIdError:
        return fit
    return fit


def best_of(fits: Sequence[Optional[AugFit]]) -> Optional[AugFit]:
    ok = [f for f in fits if f is not None and math.isfinite(f.cost)]
    return min(ok, key=lambda f: f.cost) if ok else None


#: The separable (profile) start's settings: identify's defaults (mu bracket, tolerance, phase grid).
PROFILE_MU_BRACKET = (1.0, 10.0)
PROFILE_TOL = 1e-8
PROFILE_PHASE_GRID = 48


def _prepared(e: DiagExperiment, a: AugExperiment, s: Scale, core: Any) -> Any:
    """The estimators' view of one experiment, from the diagnosis's own averaged period in its own units
    (the output's DC taken off: the plain loop has none)."""
    from ..prepare import Prepared, auto_harmonics

    dc = float(np.mean(a.ybar))
    ybar = np.ascontiguousarray(a.ybar - dc)
    noise_var = e.spread_var / s.y**2
    k = auto_harmonics(ybar, noise_var, e.periods)
    return Prepared(
        amplitude=a.amplitude,
        frequency=a.frequency,
        phase_shift=0.0,
        p=ybar.size,
        s=0,
        n=e.periods,
        k=k,
        ybar=ybar,
        ydot=np.asarray(core.paper.spectral_derivative(ybar, a.frequency, k)),
        noise_var=noise_var,
        noise_dof=e.noise_dof,
        plant=None,
        source=e.source,
        offset=dc * s.y,
    )


def plain_start(exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], s: Scale) -> list[AugParams]:
    """Starts for the plain model: the separable (profile) estimate, then generic ones (scaled units).

    The profile estimator runs on the diagnosis's own averaged periods (the experiments the fits use, in
    their units: one segmentation, one scale); it is the cheap, data-driven start, and the joint refinement
    that follows is the diagnosis's own (with generic restarts when the start is suspicious,
    :func:`fit_plain`), so the library's refined identification with its restarts is not run.
    """
    from .._backend import get_backend
    from ..estimators import fit as estimate

    starts: list[AugParams] = []
    core = get_backend("rust")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            prepared = [_prepared(e, a, s, core) for e, a in zip(exps, sx)]
            lo, hi = PROFILE_MU_BRACKET
            # (reference 0; the iteration cap is the refinement's, which the profile estimator does not run)
            res = estimate(prepared, core, "profile", 0, lo, hi, PROFILE_TOL, PROFILE_PHASE_GRID, 1)
        # (g, phi) and (-g, phi + pi) draw the same x: start on the branch g > 0.
        flip = np.where(res.gains < 0, math.pi, 0.0)
        starts.append(
            AugParams(
                beta=res.beta,
                gamma=res.gamma,
                mu=res.mu,
                terms=(),
                values=np.zeros(0),
                gains=np.abs(res.gains),
                phases=np.mod(res.phis + flip, TWO_PI),
            )
        )
    except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
        raise
    except (BoucWenIdError, SearchAtBoundError):
        pass
    starts.extend(_generic_starts(sx))
    return starts


def _generic_starts(exps: Sequence[AugExperiment]) -> list[AugParams]:
    """A small lattice in the spirit of design.md 7.4: mu, gamma/beta, saturation just above the data."""
    peak = max(float(np.max(np.abs(e.ybar - e.ybar.mean()))) for e in exps)
    h1 = [complex(2.0 * np.fft.rfft(e.ybar)[1] / e.ybar.size) for e in exps]
    out = []
    for mu in (1.5, 3.0):
        for ratio in (0.0, 0.5):
            for stretch in (1.5, 4.0):
                bg = (1.1 * peak) ** (-mu)  # beta + gamma for a saturation at 1.1 peak
                beta = bg / (1.0 + ratio)
                out.append(
                    AugParams(
                        beta=beta,
                        gamma=ratio * beta,
                        mu=mu,
                        terms=(),
                        values=np.zeros(0),
                        gains=np.array([stretch * abs(c) / e.amplitude for c, e in zip(h1, exps)]),
                        # x leads the loop's fundamental: its phase is the fundamental's less 0.3 rad.
                        phases=np.array([float(np.mod(-np.angle(c) - 0.3, TWO_PI)) for c in h1]),
                    )
                )
    return out


#: A plain fit that ends within this relative gap of ``|gamma| = beta`` is suspicious and the generic starts
#: are tried too. On the closed face ``gamma = beta`` the fit sits exactly (gap 0); towards the open face
#: ``gamma = -beta`` (``beta + gamma -> 0``, not a constraint the active set holds) it crawls and stalls short
#: of it: the MR damper at 0 A stalled at a gap of 3.5e-6 with a cost 6.8 times that of the plain fit a
#: generic start reaches (beta = gamma, mu = 1.18), so 1e-6 let a local minimum be the null of every test.
PLAIN_FACE_GAP = 1e-3


def fit_plain(exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], s: Scale, substeps: int) -> AugFit:
    """The plain Wiener-Bouc-Wen model on the data with their DC (the null of every test): ``sx`` are
    ``exps`` scaled by ``s`` (:func:`scaled`)."""
    starts = plain_start(exps, sx, s)
    first = fit_from(sx, starts[0], substeps) if starts else None
    fits: list[Optional[AugFit]] = [first]
    if (
        first is None
        or first.params.beta - abs(first.params.gamma) < PLAIN_FACE_GAP * first.params.beta
        or (
            first.active
            or first.params.mu > PROFILE_MU_BRACKET[1]  # on a face, or a two-line loop (restarts.py)
        )
    ):
        fits += [fit_from(sx, st, substeps, max_iter=25) for st in starts[1:]]
        screened = best_of(fits)
        if screened is not None and screened is not first:
            fits.append(fit_from(sx, screened.params, substeps))
    best = best_of(fits)
    if best is None:
        raise SearchAtBoundError(
            "no start of the plain model gave a valid steady loop on these data; the diagnosis needs the "
            "plain fit as its null"
        )
    return best


def candidate_starts(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> list[AugParams]:
    """Starts for ``fit``'s model plus ``term``: the term's own guesses (:meth:`Term.start`)."""
    par = fit.params

    def projection() -> float:
        """The least-squares value of a linear term on the current residual."""
        num = den = 0.0
        for i, (e, y) in enumerate(zip(exps, fit.outputs)):
            g = regressor(term, e, par, i, substeps)
            num += e.weight * float(np.dot(g, e.ybar - y))
            den += e.weight * float(np.dot(g, g))
        return num / den if den > 0 else 0.0

    context = StartContext(
        latent_amplitudes=tuple(abs(e.amplitude * g) for e, g in zip(exps, par.gains)),
        max_frequency=max(e.frequency for e in exps),
        beta=par.beta,
        gamma=par.gamma,
        projection=projection,
        residual_rms=math.sqrt(
            sum(float(np.sum((e.ybar - y) ** 2)) for e, y in zip(exps, fit.outputs))
            / max(sum(e.ybar.size for e in exps), 1)
        ),
        input_amplitudes=tuple(abs(e.amplitude) for e in exps),
    )
    cls = TERMS[term]
    if cls.companion:  # a two-term element (Dahl friction): both parameters are added, from paired starts
        return [par.with_term(term, a).with_term(cls.companion, b) for a, b in cls.start_pairs(context)]
    return [par.with_term(term, v) for v in cls.start(context)]


#: LM iterations of the screening of several starts (the best is then run to convergence).
SCREEN_ITER = 20


#: Phase offsets (rad) screened per experiment for a term whose output steps with the phase (friction on
#: x): 0.025 rad apart over +-0.4 rad, several per sample spacing of a 64-point grid (the Levenberg-Marquardt
#: steps finish within a stair).
PHASE_SCREEN = np.linspace(-0.4, 0.4, 33)


def screen_phases(exps: Sequence[AugExperiment], par: AugParams, substeps: int) -> tuple[AugParams, float]:
    """Each experiment's phase moved to the best of :data:`PHASE_SCREEN` offsets, the rest held; and the cost.

    A step at the reversals of x (dry friction on x) crosses a sample of the grid as phi moves: each crossing
    is a cost barrier of about ``(2 f)^2`` times the weight, which the Levenberg-Marquardt steps cannot climb;
    the experiments' costs are separate given the shared parameters, so each phase is screened on its own.
    """
    phases = np.array(par.phases, dtype=np.float64)
    total = 0.0
    for i, e in enumerate(exps):
        best = (math.inf, float(phases[i]))
        for d in PHASE_SCREEN:
            trial = phases.copy()
            trial[i] += d
            try:
                y = augmented_output(e, replace(par, phases=trial), i, substeps=substeps)
            except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
                raise
            except BoucWenIdError:
                continue
            c = e.weight * float(np.sum((e.ybar - y) ** 2))
            if c < best[0]:
                best = (c, float(trial[i]))
        phases[i] = best[1]
        total += best[0]
    return replace(par, phases=phases), total


def screen_phases_linear(
    exps: Sequence[AugExperiment], pars: Sequence[AugParams], substeps: int
) -> list[tuple[AugParams, float]]:
    """:func:`screen_phases` of each of ``pars``, which differ only in the value of their last term, a term
    whose output is linear in its value (:attr:`Term.linear`; the phase-screened dry friction on x).

    The output at each experiment's phase offset is then ``y(v) = y(v0) + (v - v0) r`` with ``r`` the
    term's column: each offset's loop is solved once (at ``pars[0]``) instead of once per level (five
    levels: five times fewer loops; docs/diagnosis-speed.md). A level the core refuses (its value outside
    the term's range: an error wherever the loop itself is fine) keeps its phases at cost inf, as
    :func:`screen_phases` leaves it.
    """
    base = pars[0]
    v0 = float(base.values[-1])
    col = 3 + len(base.terms) - 1
    valid: list[Optional[bool]] = [None] * len(pars)
    phases = [np.array(p.phases, dtype=np.float64) for p in pars]
    totals = [0.0] * len(pars)
    for i, e in enumerate(exps):
        best = [(math.inf, float(ph[i])) for ph in phases]
        for d in PHASE_SCREEN:
            trial = np.array(base.phases, dtype=np.float64)
            trial[i] += d
            try:
                out = augmented_output(e, replace(base, phases=trial), i, substeps=substeps, jacobian=True)
            except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
                raise
            except BoucWenIdError:
                continue
            for k, par in enumerate(pars):
                if valid[k] is None:  # where the loop is fine, only the level itself can be refused
                    valid[k] = _accepted(e, replace(par, phases=trial), i, substeps)
                if not valid[k]:
                    continue
                dv = float(par.values[-1]) - v0
                y = out.y if dv == 0.0 else out.y + dv * out.jacobian[:, col]
                c = e.weight * float(np.sum((e.ybar - y) ** 2))
                if c < best[k][0]:
                    best[k] = (c, float(trial[i]))
        for k in range(len(pars)):
            phases[k][i] = best[k][1]
            totals[k] += best[k][0]
    return [(replace(par, phases=ph), t) for par, ph, t in zip(pars, phases, totals)]


def _accepted(e: AugExperiment, par: AugParams, i: int, substeps: int) -> bool:
    try:
        augmented_output(e, par, i, substeps=substeps)
    except BudgetExceededError:
        raise
    except BoucWenIdError:
        return False
    return True


#: Levels of a phase-screened term tried beside its own starts, as fractions of the data's peak |ybar|.
SCREEN_LEVELS = (0.03, 0.1, 0.3)


def fit_with(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> Optional[AugFit]:
    """``fit``'s model plus ``term`` from the starts of :func:`candidate_starts`; the best, or None.

    The first start that converges to a valid model is kept for a linear output term (its informed start
    is the least-squares value on the current residual); for the others every start is screened with
    ``SCREEN_ITER`` iterations and the best is finished. A model with a dry friction has its smoothing
    width profiled (coulomb_width.py): the width that fits the friction alone is not the one that fits it
    beside the term that joins it (a damper's share of the turn).
    """
    out = _fit_with(exps, fit, term, substeps)
    if out is None or not coulomb_width.has_dry_friction(out.params):
        return out
    return coulomb_width.profile(
        out, lambda st: fit_from(exps, st, substeps, max_iter=coulomb_width.REFIT_ITER)
    )


def _fit_with(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> Optional[AugFit]:
    """:func:`fit_with` without the width's profile."""
    starts = candidate_starts(exps, fit, term, substeps)
    if TERMS[term].phase_screen:
        return _fit_phase_screened(exps, starts, substeps)
    if TERMS[term].linear:
        for st in starts:
            f = fit_from(exps, st, substeps)
            if f is not None:
                return f
        return None
    screened = best_of([fit_from(exps, st, substeps, max_iter=SCREEN_ITER) for st in starts])
    if screened is None:
        return None
    best = best_of([screened, fit_from(exps, screened.params, substeps)])
    return None if best is not None and at_a_limit(exps, best, term) else best


#: A two-term element (Dahl friction) whose fitted shape ``sigma A / Fc`` lies below the first bound at every
#: experiment is its spring limit, above the second its dry-friction limit: the simpler term, not the element.
LIMIT_SHAPES = (0.05, 200.0)


def _shapes(exps: Sequence[AugExperiment], fit: AugFit, term: str) -> list[float]:
    """``fit``'s shapes ``sigma A / Fc`` of the two-term element ``term`` per experiment (empty: not such an
    element in ``fit``, or no friction, its null)."""
    cls, par = TERMS[term], fit.params
    if not cls.companion or term not in par.terms or cls.companion not in par.terms:
        return []
    fc = float(par.values[par.terms.index(term)])
    sigma = float(par.values[par.terms.index(cls.companion)])
    if fc <= 0.0:
        return []  # no friction: the null, not a limit
    on_x = cls.acts_on == Place.X
    return [sigma * abs(e.amplitude * (g if on_x else 1.0)) / fc for e, g in zip(exps, par.gains)]


def at_a_limit(exps: Sequence[AugExperiment], fit: AugFit, term: str) -> bool:
    """Whether ``fit``'s two-term element ``term`` sits at one of its limits (:data:`LIMIT_SHAPES`)."""
    shapes = _shapes(exps, fit, term)
    return bool(shapes) and (max(shapes) < LIMIT_SHAPES[0] or min(shapes) > LIMIT_SHAPES[1])


def nearer_limit(exps: Sequence[AugExperiment], fit: AugFit, term: str) -> str:
    """The simpler term (of ``term``'s ``limits``: the spring, ``Fc -> inf``, then dry friction,
    ``sigma -> inf``) that ``fit``'s element leans to: the spring where the shapes' geometric mean is below 1
    (the pre-sliding stiffness spans the travel), dry friction above; "" for a term without limits."""
    shapes = _shapes(exps, fit, term)
    limits: tuple[str, ...] = getattr(TERMS[term], "limits", ())
    if len(limits) < 2 or not shapes or min(shapes) <= 0.0:
        return ""
    return str(limits[0] if sum(math.log(v) for v in shapes) < 0.0 else limits[1])


def _fit_phase_screened(
    exps: Sequence[AugExperiment], starts: Sequence[AugParams], substeps: int
) -> Optional[AugFit]:
    """A term whose output steps with the phases (:attr:`Term.phase_screen`): the plain fit's phases are
    biased by the very step it leaves out (0.2-0.3 rad for a 30x friction on x) and its loop has absorbed
    the step's fundamental, so the cost at the held hysteresis does not rank the term's levels. Each start,
    and each of :data:`SCREEN_LEVELS` (positive: a friction level), has its phases screened
    (:func:`screen_phases`) and is fitted for ``SCREEN_ITER`` iterations; the best is finished."""
    peak = max(float(np.max(np.abs(e.ybar))) for e in exps)
    base = starts[0]
    levels = [float(v) for st in starts for v in st.values[-1:]]
    levels += [f * peak for f in SCREEN_LEVELS]
    at = [replace(base, values=np.append(base.values[:-1], v)) for v in levels]
    if speed.SCREEN_ONCE and TERMS[base.terms[-1]].linear:
        screened_starts = [par for par, _ in screen_phases_linear(exps, at, substeps)]
    else:
        screened_starts = [screen_phases(exps, par, substeps)[0] for par in at]
    fits = [fit_from(exps, par, substeps, max_iter=SCREEN_ITER) for par in screened_starts]
    screened = best_of(fits)
    if screened is None:
        return None
    return best_of([screened, fit_from(exps, screened.params, substeps)])


def subset(
    exps: Sequence[AugExperiment], fit_params: AugParams, keep: Sequence[int]
) -> tuple[list[AugExperiment], AugParams]:
    """The experiments ``keep`` and the parameters restricted to them."""
    ks = list(keep)
    return [exps[i] for i in ks], replace(
        fit_params, gains=fit_params.gains[ks].copy(), phases=fit_params.phases[ks].copy()
    )


def fit_own(
    e: AugExperiment, params: AugParams, gain: float, phase: float, substeps: int
) -> tuple[float, FloatArray]:
    """Held-out refit: only the experiment's own ``(g, phi)``, the physics frozen; (cost, output)."""
    p = e.ybar.size

    def evaluate(g: float, ph: float) -> tuple[FloatArray, FloatArray]:
        own = replace(params, gains=np.array([g]), phases=np.array([ph]))
        out = augmented_output(e, own, 0, substeps=substeps, jacobian=True)
        return out.y, out.own_jacobian

    x = np.array([gain, phase])
    try:
        y, jo = evaluate(*x)
    except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
        raise
    except BoucWenIdError:
        return math.inf, np.full(p, np.nan)
    r = free_dc.centred(
        e, e.ybar - y, held_out=True
    )  # a free DC (free_dc.py): the residual's mean has no weight
    jo = free_dc.centred(e, jo, held_out=True)
    cost = e.weight * float(r @ r)
    lam = 1e-3
    for _ in range(OWN_MAX_ITER):
        a = e.weight * (jo.T @ jo)
        b = e.weight * (jo.T @ r)
        step = np.linalg.solve(a + lam * np.diag(np.diag(a) + 1e-300), b) if np.all(np.isfinite(a)) else None
        if step is None:
            break
        trial = x + step
        try:
            y2, jo2 = evaluate(*trial)
        except BudgetExceededError:  # a limit the user set: never a failed start (issue 19)
            raise
        except BoucWenIdError:
            lam *= 10.0
            continue
        r2 = free_dc.centred(e, e.ybar - y2, held_out=True)
        jo2 = free_dc.centred(e, jo2, held_out=True)
        c2 = e.weight * float(r2 @ r2)
        if c2 < cost:
            done = (cost - c2) <= 1e-10 * cost
            x, y, jo, r, cost = trial, y2, jo2, r2, c2
            lam = max(lam * 0.2, 1e-12)
            if done:
                break
        else:
            lam *= 10.0
            if lam > 1e12:
                break
    return cost, (e.ybar - r if free_dc.count([e], held_out=True) else y)  # a free DC: the data's own


def physical(fit: AugFit, s: Scale, term: str) -> tuple[float, float]:
    """A term's value and standard error in physical units."""
    par = fit.params
    i = par.terms.index(term)
    f = s.factor(term, par.mu)
    v = float(par.values[i]) * f
    se = fit.standard_error(term) * abs(f)
    c = TERMS[term].scaling[2]
    if c:
        # q = q~ s^(c mu) (asymmetry: delta = delta~ s^-mu): the delta method through mu as well.
        cov = fit.covariance
        j = 3 + i
        ln = c * math.log(s.y)
        var = f**2 * (cov[j, j] + (par.values[i] * ln) ** 2 * cov[2, 2] + 2 * par.values[i] * ln * cov[j, 2])
        se = math.sqrt(var) if var >= 0 else math.nan
    return v, se


def nrmse(e: AugExperiment, y: FloatArray) -> float:
    spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
    return float(np.linalg.norm(e.ybar - y)) / spread if spread > 0 else math.nan

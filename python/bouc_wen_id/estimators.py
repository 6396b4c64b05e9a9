"""The estimators: the paper's separable fit, its phase-profiled form, and the joint output-error refinement.

All work on :class:`~bouc_wen_id.prepare.Prepared` experiments in scaled units (see
:func:`~bouc_wen_id.prepare.scale`), with phases local to each averaged window's first sample.

``"paper"``
    Phase from the averaged output's maximum (9), golden-section search of the separable least-squares
    cost (21) over mu with ``sgn(d ybar/dt)`` in the regressor (18)-(24), and the gain (27b) elsewhere.
``"profile"``
    The same cost profiled over the phase (Proposition 2), at every frequency.
``"refined"``
    The profile estimates as a start, then Levenberg-Marquardt on the steady loops of every experiment at
    once (design.md section 7), safeguarded by generic starts against wrong basins.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ._backend import MultiStart, Paper, Parts
from .errors import BoucWenIdError, InsufficientDataError, SearchAtBoundError
from .prepare import Prepared
from .result import Adequacy

__all__ = ["Fit", "Start", "LMRun", "fit", "refine", "adequacy", "linear_nrmse", "loop_fit", "weights"]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Smallest margin of beta over |gamma| the refinement starts from (no steady loop below 0).
MIN_BETA_PLUS_GAMMA = 1e-3
#: The refinement starts at least this fraction of the mu bracket away from its ends.
START_MU_MARGIN = 1e-2
#: A refined mu closer than this fraction of the bracket to one of its ends is "at the bound".
AT_BOUND_FRACTION = 1e-4
#: Below this noise sd relative to the loop's peak, data count as noise-free (no adequacy test).
NOISE_FREE_RTOL = 1e-9
#: Generic starts of the joint fit (see :func:`_generic_starts`): mu values, gamma/beta ratios, and the
#: depth of saturation A / w_sat.
START_MUS = (1.15, 1.6, 2.5, 5.0)
START_RATIOS = (0.5, -0.5)
START_DEPTHS = (1.5, 4.0)
#: LM iterations of each generic start's screening fit (the best one is then run to convergence).
SCREEN_ITER = 25
#: The screening runs in two rounds (``rust/multistart.rs``): after this many iterations a start whose cost
#: is still over SCREEN_ABANDON_RATIO times the best start's stops there; a wrong basin that far behind
#: after a few LM steps does not catch up, and most generic starts are in one (issue #8).
SCREEN_ABANDON_AFTER = 5
SCREEN_ABANDON_RATIO = 10.0
#: RK4 steps per period of the screening fits (a coarse steady-loop lattice; the finish runs at
#: STEADY_STEPS_PER_PERIOD).  The screening only ranks the starts: on the 10-experiment bench of
#: benches/bench_pipeline.py (issue #8) 512 steps gave the same winner and final fit as 2048 (cost
#: 859.503 to all printed digits) in about a quarter of the screening time (forced restarts 0.426 s ->
#: 0.162 s, load average 3.3); 256 ranked them the same too, but a coarser lattice leaves less margin on
#: sharper loops (mu near 1, or up to 40 in a widened bracket).
SCREEN_STEPS_PER_PERIOD = 512
#: Screened starts finished at full resolution (the best ones; the lowest full-resolution cost wins).
#: One, as before the coarse lattice: finishing the best two (0.212 s on the bench) changed a result of
#: studies/real_data.py (the friction damper's 0.25Hz30lbtension0.5amplitude, retried on mu in (1, 40],
#: went from mu = 14.1 to a refusal at mu -> 40 through a second start's lower cost at the bound); with
#: one it is unchanged.
SCREEN_FINISH = 1
#: Assumed lag (rad) of the loop's fundamental behind x for the generic starts.
START_LAG = 0.3
#: A fit is checked from the generic starts when it ends this close (relative) to beta = |gamma|.
ON_CONSTRAINT_RTOL = 1e-6
#: RK4 steps per period of the steady-loop solver: a step of at most 2 pi / 2048 rad.
STEADY_STEPS_PER_PERIOD = 2048


@dataclass(frozen=True)
class Start:
    """A starting point of the joint fit: shared ``beta, gamma, mu`` and per-experiment ``|G|, phi``."""

    beta: float
    gamma: float
    mu: float
    gains: FloatArray
    phis: FloatArray


@dataclass(frozen=True)
class LMRun:
    """One Levenberg-Marquardt run of the core's ``refine``.

    ``params`` is ``[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]``; ``fisher`` the Gauss-Newton
    information matrix at the end; ``loops`` the fitted steady loops.
    """

    params: FloatArray
    cost: float
    iterations: int
    converged: bool
    fisher: FloatArray
    loops: list[FloatArray]
    #: The stopping rule that ended the run (``"ftol"``, ``"xtol"``, ``"no_decrease"``, ``"max_iter"``).
    stop: str = "ftol"
    #: The constraints the run ended on and that hold it there (``"beta=gamma"``, ``"mu=lower"``, ...).
    active: tuple[str, ...] = ()

    @classmethod
    def from_core(cls, out: tuple[Any, ...]) -> LMRun:
        params, cost, iterations, converged, fisher, loops, stop, active = out
        return cls(
            np.asarray(params),
            float(cost),
            int(iterations),
            bool(converged),
            np.asarray(fisher),
            [np.asarray(w) for w in loops],
            str(stop),
            tuple(str(a) for a in active),
        )

    def start(self) -> Start:
        """The run's end as a start of another run."""
        p = self.params
        return Start(float(p[0]), float(p[1]), float(p[2]), p[3::2].copy(), p[4::2].copy())


@dataclass
class Fit:
    """Estimates in the scaled units the estimators worked in."""

    beta: float
    gamma: float
    mu: float
    gains: FloatArray
    phis: FloatArray
    cost: float
    iterations: int
    cov: Optional[FloatArray]
    loops: list[Optional[FloatArray]]
    #: Whether the Levenberg-Marquardt run the estimates come from converged (None: no such run).
    converged: Optional[bool] = None
    #: Its stopping rule (None: no such run) and the constraints it ended on (see :class:`LMRun`).
    stop: Optional[str] = None
    active: tuple[str, ...] = ()


def steady_substeps(p: int) -> int:
    """RK4 steps per sample of the steady-loop solver on ``p`` samples per period."""
    return max(2, math.ceil(STEADY_STEPS_PER_PERIOD / p))


def loop_fit(
    core: Paper, e: Prepared, gain: float, phi_local: float, beta: float, gamma: float, mu: float
) -> tuple[Optional[FloatArray], float]:
    """The identified model's steady loop on the data grid and its NRMSE against ybar."""
    try:
        w = np.asarray(
            core.steady_loop(e.amplitude * gain, beta, gamma, mu, phi_local, e.p, steady_substeps(e.p))[0]
        )
    except BoucWenIdError:
        return None, math.nan
    spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
    return w, float(np.linalg.norm(e.ybar - w)) / spread if spread > 0 else math.nan


def weights(prepared: Sequence[Prepared]) -> FloatArray:
    """N / sigma^2 per experiment; the variance is floored at rounding level for noise-free data."""
    out = []
    for e in prepared:
        floor = (1e-13 * float(np.max(np.abs(e.ybar)))) ** 2 + np.finfo(float).tiny
        out.append(e.n / max(e.noise_var, floor))
    return np.array(out)


def adequacy(
    prepared: Sequence[Prepared], loops: Sequence[Optional[FloatArray]], n_params: int
) -> Optional[Adequacy]:
    """The F-test of the fitted loops' residual power against the noise floor (None when it cannot be run)."""
    fitted = [w for w in loops if w is not None]
    if len(fitted) != len(loops) or any(not math.isfinite(e.noise_var) for e in prepared):
        return None
    if any(e.noise_var <= (NOISE_FREE_RTOL * float(np.max(np.abs(e.ybar)))) ** 2 for e in prepared):
        # Noise-free (simulated) data: the floor is rounding, and any discretisation error "rejects".
        return None
    # scipy.special, not scipy.stats: the latter takes over a second to import.
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    wts = weights(prepared)
    statistic = float(sum(wt * np.sum((e.ybar - w) ** 2) for wt, e, w in zip(wts, prepared, fitted)))
    dof = sum(e.p for e in prepared) - n_params
    noise_dof = sum(e.noise_dof for e in prepared)
    if dof < 1:
        return None
    p_value = float(fdtrc(dof, noise_dof, statistic / dof))
    return Adequacy(statistic, dof, noise_dof, p_value)


def fit(
    prepared: Sequence[Prepared],
    parts: Parts,
    method: str,
    reference: int,
    lo: float,
    hi: float,
    tol: float,
    phase_grid: int,
    max_iter: int,
) -> Fit:
    """Run the chosen estimator; phases are local (relative to each averaged window's first sample).

    Raises
    ------
    SearchAtBoundError
        mu ended on an end of its bracket; at mu = 1, the model's own limit, the message says what that
        means for the data.
    """
    core = parts.paper
    try:
        if method == "paper":
            return _with_loops(prepared, core, *_paper(prepared, core, reference, lo, hi, tol))
        try:
            start, cost = _profile(prepared, core, reference, lo, hi, tol, phase_grid)
        except SearchAtBoundError as exc:
            # The separable fit is only the refinement's start: when it runs to mu's lower end, the
            # output-error fit still gets its chance from generic starts (and is refused only if it
            # ends there too).
            if method != "refined" or not exc.lower:
                raise
            return refine(prepared, core, None, lo, hi, max_iter, exc, parts.multistart)
        if method != "refined":
            return _with_loops(prepared, core, start, cost, 0)
        return refine(prepared, core, start, lo, hi, max_iter, multistart=parts.multistart)
    except SearchAtBoundError as exc:
        if not (exc.lower and exc.bound is not None and exc.bound <= 1.0):
            raise
        raise _at_model_limit(exc) from exc


def _at_model_limit(exc: SearchAtBoundError) -> SearchAtBoundError:
    """mu = 1 is the model's own limit, so "widen the bracket" is no advice there: say what it means."""
    return SearchAtBoundError(
        "the fit drove mu to 1, the lower end of the model's range (mu > 1): the data turn at each "
        "reversal in a way no Bouc-Wen loop with mu > 1 draws (typically a force that jumps at the "
        "reversal, as Coulomb friction, or keeps growing with velocity, as viscous damping beside "
        "friction in MR dampers). The plain Wiener-Bouc-Wen model does not describe these data; the "
        "physics it leaves out must be modelled",
        bound=exc.bound,
        lower=exc.lower,
    )


def _paper(
    prepared: Sequence[Prepared], core: Paper, reference: int, lo: float, hi: float, tol: float
) -> tuple[Start, float, int]:
    """The seed paper's estimator: phase (9), separable search (18)-(24), gains (27b)."""
    ref = prepared[reference]
    phis = np.array([float(core.phase_from_max(e.ybar)) for e in prepared])
    mu, theta, cost, iterations = core.sls_search(
        ref.ybar, ref.ydot, ref.amplitude, ref.frequency, phis[reference], lo, hi, tol
    )
    theta = np.asarray(theta)
    beta, gamma = float(theta[1] / theta[0]), float(theta[2] / theta[0])
    gains = np.zeros(len(prepared))
    for i, e in enumerate(prepared):
        gains[i] = (
            float(theta[0])
            if i == reference
            else float(core.gain_estimate(e.ybar, e.ydot, e.amplitude, e.frequency, phis[i], beta, gamma, mu))
        )
    return Start(beta, gamma, float(mu), gains, phis), float(cost), int(iterations)


def _profile(
    prepared: Sequence[Prepared],
    core: Paper,
    reference: int,
    lo: float,
    hi: float,
    tol: float,
    phase_grid: int,
) -> tuple[Start, float]:
    """The separable fit profiled over the phase on the reference, then gain and phase elsewhere."""
    ref = prepared[reference]
    phi_r, mu, g_r, beta, gamma, cost, _ = core.profile_phase_sls(
        ref.ybar, ref.ydot, ref.amplitude, ref.frequency, lo, hi, tol, phase_grid
    )
    m = len(prepared)
    gains, phis = np.zeros(m), np.zeros(m)
    for i, e in enumerate(prepared):
        if i == reference:
            gains[i], phis[i] = g_r, phi_r
        else:
            gains[i], phis[i], _ = core.profile_phase_gain(
                e.ybar, e.ydot, e.amplitude, e.frequency, beta, gamma, mu, phase_grid
            )
    return Start(float(beta), float(gamma), float(mu), gains, phis), float(cost)


def _with_loops(prepared: Sequence[Prepared], core: Paper, est: Start, cost: float, iterations: int) -> Fit:
    """A separable fit's estimates with the steady loops they draw (no covariance)."""
    loops = [
        loop_fit(core, e, est.gains[i], est.phis[i], est.beta, est.gamma, est.mu)[0]
        for i, e in enumerate(prepared)
    ]
    return Fit(est.beta, est.gamma, est.mu, est.gains, est.phis, cost, iterations, None, loops)


def _fundamental(ybar: FloatArray) -> complex:
    """``c`` with ``ybar`` ~ Re(c exp(i 2 pi j / P)): the averaged output's first harmonic."""
    return complex(2.0 * np.fft.rfft(ybar)[1] / ybar.size)


def _linear_residual(ybar: FloatArray) -> FloatArray:
    """``ybar`` minus its fundamental: the residual of the best linear (spring + dashpot) model."""
    theta = TWO_PI * np.arange(ybar.size) / ybar.size
    out: FloatArray = ybar - np.real(_fundamental(ybar) * np.exp(1j * theta))
    return out


def linear_nrmse(ybar: FloatArray) -> float:
    """NRMSE of ybar's fundamental alone (the best linear model) against ybar, as ``nrmse``."""
    spread = float(np.linalg.norm(ybar - ybar.mean()))
    if spread == 0.0:
        return math.nan
    return float(np.linalg.norm(_linear_residual(ybar))) / spread


def _linear_cost(prepared: Sequence[Prepared], wts: FloatArray) -> float:
    """The weighted cost of the best linear (spring + dashpot) model: each ybar's fundamental alone.

    A Bouc-Wen loop driven far below saturation is x itself, of any amplitude and phase, so the joint
    fit can always reach this cost; a fit above it sits in a wrong basin.
    """
    return sum(float(wt) * float(np.sum(_linear_residual(e.ybar) ** 2)) for e, wt in zip(prepared, wts))


def _generic_starts(prepared: Sequence[Prepared], lo: float, hi: float) -> list[Start]:
    """Starting points spread over the shapes a Bouc-Wen loop can take, scaled to the data.

    The saturation level ``w_sat = (beta + gamma)^(-1/mu)`` is set a little above the largest averaged
    output; each experiment's x reaches ``depth`` times its loop's amplitude, with the phase of its
    fundamental less a typical hysteretic lag.
    """
    fund = [_fundamental(e.ybar) for e in prepared]
    peak = max(max(float(np.max(np.abs(e.ybar))) for e in prepared), 1e-300)
    margin = START_MU_MARGIN * (hi - lo)
    starts = []
    for mu in START_MUS:
        mu = min(max(mu, lo + margin), hi - margin)
        total = (1.1 * peak) ** (-mu)
        for ratio in START_RATIOS:
            beta = total / (1.0 + ratio)
            gamma = ratio * beta
            for depth in START_DEPTHS:
                gains = np.array([depth * 1.1 * abs(c) / e.amplitude for c, e in zip(fund, prepared)])
                phis = np.array([-math.atan2(c.imag, c.real) - START_LAG for c in fund])
                starts.append(Start(beta, gamma, mu, gains, phis))
    return starts


#: What each face of the admissible range means to the user (the names of ``rust/refine.rs`` ``Constraint``).
_FACES = {
    "beta=gamma": "beta = gamma (the Bouc-Wen condition beta >= |gamma|)",
    "mu=lower": "mu = the lower end of its bracket",
    "mu=upper": "mu = the upper end of its bracket",
}
#: What each stopping rule means (``StopReason::code``).
_STOPS = {
    "ftol": "the cost stopped decreasing",
    "xtol": "the step became negligible",
    "no_decrease": "no admissible step decreases the cost",
    "max_iter": "the iteration cap",
    "stall": "the cost stopped falling by enough to move a test",
    # diagnosis/free_dc.NOT_CONVERGED: the fit around the core's, not a core stop (its own note says more)
    "dc_not_converged": "the free DCs of a wandering baseline did not settle",
}


#: What a fit held at mu = 1 alone means (review 38, 7a: a true mu = 1 piezo was told its intervals do not
#: hold): mu = 1 is a valid exponent at the bracket's end, not data pulling the model beyond what it draws.
MU_ONE_NOTE = (
    "{what} ended with mu = 1, the lower end of its bracket ({rule}): a valid exponent (a loop that "
    "approaches saturation exponentially, common for piezoelectric stacks); the estimate sits on the "
    "bracket's end, so the intervals of the parameters tied to mu (mu, beta, gamma) are one-sided there "
    "(read them as conservative), as expected when the device's exponent is 1 (an exponent below 1, "
    "outside the model, would also stop there: the adequacy test tells them apart)"
)


def boundary_note(
    stop: Optional[str], active: Sequence[str], what: str = "the joint fit", mu: float = math.nan
) -> Optional[str]:
    """A plain-language warning when a Levenberg-Marquardt run ended on faces of the admissible range
    (``active``, as the core names them), or None when it ended inside. ``mu``: the fit's exponent; held
    at mu = 1 alone it is said as a valid value on the bracket's end (:data:`MU_ONE_NOTE`)."""
    if not active:
        return None
    if tuple(active) == ("mu=lower",) and math.isclose(mu, 1.0, rel_tol=1e-6):
        return MU_ONE_NOTE.format(what=what, rule=_STOPS.get(stop or "", stop or "unknown"))
    faces = []
    for a in active:
        name, _, side = a.partition("=")
        faces.append(_FACES.get(a, f"{name} at {'0' if side == '0' else 'its upper limit'}"))
    rule = _STOPS.get(stop or "", stop or "unknown")
    return (
        f"{what} stopped on the boundary of the model's admissible range, held there by "
        f"{' and '.join(faces)} "
        f"({rule}): the data pull the model beyond what it can draw, so its intervals do not hold there; "
        "a physical effect the model lacks (bouc_wen_id.diagnose names it), a wrong channel or a transient "
        "is the usual cause"
    )


def on_constraint(beta: float, gamma: float) -> bool:
    """True when ``(beta, gamma)`` lies on the Bouc-Wen constraint beta = |gamma| (to rounding)."""
    return beta - abs(gamma) <= ON_CONSTRAINT_RTOL * max(abs(beta), abs(gamma), 1e-300)


def refine(
    prepared: Sequence[Prepared],
    core: Paper,
    start: Optional[Start],
    lo: float,
    hi: float,
    max_iter: int,
    profile_error: Optional[SearchAtBoundError] = None,
    multistart: Optional[MultiStart] = None,
) -> Fit:
    """The joint output-error fit from ``start`` (the profile estimates), safeguarded by generic starts.

    The generic starts run when there is no profile start (its mu ran to the lower bound), or when the
    fit from it ends on the Bouc-Wen constraint beta = |gamma| or costs more than the best linear model
    (both signs of a wrong basin); the lowest cost wins.  With ``multistart`` (the Rust backend's) they are
    screened all at once on every core; without it (the NumPy backend) one by one.
    """
    short = [e.source for e in prepared if e.n < 2]
    if short:
        raise InsufficientDataError(
            f"method='refined' estimates the noise floor from the period-to-period spread and needs at "
            f"least 2 averaged periods; {', '.join(short)} have fewer. Use method='paper' or record longer"
        )
    wts = weights(prepared)
    substeps = max(steady_substeps(e.p) for e in prepared)
    margin = START_MU_MARGIN * (hi - lo)

    def run(s: Start, iters: int = max_iter) -> Optional[LMRun]:
        # The separable fit knows nothing of the Bouc-Wen conditions (beta >= |gamma|) and a loop too
        # linear to fix beta + gamma can put it outside them, where no steady loop exists: start the
        # joint fit just inside, and within the mu bracket, and let the data speak.
        beta = max(s.beta, abs(s.gamma) + MIN_BETA_PLUS_GAMMA)
        mu = min(max(s.mu, lo + margin), hi - margin)
        try:
            out = core.refine(
                [e.ybar for e in prepared],
                [e.amplitude for e in prepared],
                wts,
                beta,
                s.gamma,
                mu,
                s.gains,
                s.phis,
                max_iter=iters,
                substeps=substeps,
                mu_lo=lo,
                mu_hi=hi,
            )
        except BoucWenIdError:
            if start is None:
                return None  # a generic start that is no valid loop: the others decide
            raise
        return LMRun.from_core(out)

    best = None if start is None else run(start)
    linear = _linear_cost(prepared, wts)

    def suspicious(r: LMRun) -> bool:
        return on_constraint(float(r.params[0]), float(r.params[1])) or r.cost > linear

    if best is None or suspicious(best):
        # Screen every generic start with a short fit, then finish the most promising one.
        candidates = _generic_starts(prepared, lo, hi)
        if multistart is not None:
            best = _screen_in_parallel(
                prepared, multistart, candidates, run, best, wts, substeps, lo, hi, max_iter
            )
        else:
            screened: Optional[LMRun] = None
            for candidate in candidates:
                out = run(candidate, iters=min(SCREEN_ITER, max_iter))
                if out is not None and (screened is None or out.cost < screened.cost):
                    screened = out
            if screened is not None and (best is None or screened.cost < best.cost):
                final = run(screened.start())
                best = final if final is not None and final.cost <= screened.cost else screened
    if best is None:
        if profile_error is not None:
            raise profile_error
        raise SearchAtBoundError("no start of the joint fit gave a valid steady loop")
    return _refined_fit(best, len(prepared), lo, hi)


def _screen_in_parallel(
    prepared: Sequence[Prepared],
    multistart: MultiStart,
    candidates: Sequence[Start],
    run: Any,
    best: Optional[LMRun],
    wts: FloatArray,
    substeps: int,
    lo: float,
    hi: float,
    max_iter: int,
) -> Optional[LMRun]:
    """The generic starts screened by ``refine_many`` (all cores, the interpreter released; hopeless
    starts abandoned after :data:`SCREEN_ABANDON_AFTER` iterations) on a coarse steady-loop lattice of
    :data:`SCREEN_STEPS_PER_PERIOD` RK4 steps per period; the best :data:`SCREEN_FINISH` are then finished
    by ``run`` at full resolution and the lowest full-resolution cost wins.

    Deterministic: the outcome does not depend on the number of cores (``rust/multistart.rs``).
    """
    margin = START_MU_MARGIN * (hi - lo)
    flat = []
    for c in candidates:
        # As ``run``: just inside the Bouc-Wen conditions and the mu bracket.
        beta = max(c.beta, abs(c.gamma) + MIN_BETA_PLUS_GAMMA)
        mu = min(max(c.mu, lo + margin), hi - margin)
        v = np.empty(3 + 2 * len(prepared))
        v[:3] = (beta, c.gamma, mu)
        v[3::2], v[4::2] = c.gains, c.phis
        flat.append(v)
    screen_iter = min(SCREEN_ITER, max_iter)
    # The coarse lattice: as steady_substeps, at SCREEN_STEPS_PER_PERIOD (never finer than the finish).
    coarse = min(substeps, max(2, math.ceil(SCREEN_STEPS_PER_PERIOD / min(e.p for e in prepared))))
    outs = multistart.refine_many(
        [e.ybar for e in prepared],
        [e.amplitude for e in prepared],
        wts,
        flat,
        max_iter=screen_iter,
        substeps=coarse,
        mu_lo=lo,
        mu_hi=hi,
        abandon_after=SCREEN_ABANDON_AFTER if SCREEN_ABANDON_AFTER < screen_iter else 0,
        abandon_ratio=SCREEN_ABANDON_RATIO,
        threads=0,
    )
    scored = sorted(((float(o[1]), np.asarray(o[0])) for o in outs if o is not None), key=lambda sp: sp[0])
    # The coarse costs only rank the starts: the best few are finished at full resolution (LM accepts
    # only decreasing steps, so each finish ends no worse than its start at that resolution) and the
    # full-resolution costs decide, against the run from the profile start too.
    for _, p in scored[:SCREEN_FINISH]:
        final: Optional[LMRun] = run(
            Start(float(p[0]), float(p[1]), float(p[2]), p[3::2].copy(), p[4::2].copy())
        )
        if final is not None and (best is None or final.cost < best.cost):
            best = final
    return best


def _refined_fit(best: LMRun, m: int, lo: float, hi: float) -> Fit:
    """The winning run as a :class:`Fit` with its covariance, on the canonical branch (|G| > 0).

    Raises
    ------
    SearchAtBoundError
        mu ended on an end of its bracket.
    """
    beta, gamma, mu = (float(v) for v in best.params[:3])
    if min(mu - lo, hi - mu) <= AT_BOUND_FRACTION * (hi - lo):
        lower = mu - lo <= hi - mu
        raise SearchAtBoundError(
            f"the joint fit ended on the {'lower' if lower else 'upper'} end of the mu bracket "
            f"[{lo}, {hi}] (mu = {mu:.6g}); widen the bracket, or check that the data excite the "
            "hysteresis",
            bound=lo if lower else hi,
            lower=lower,
        )
    gains = best.params[3::2].copy()
    phis = best.params[4::2].copy()
    # Flip the sign of g_i rows/columns where the canonical branch (|G| > 0) is reported.
    flip = np.ones(3 + 2 * m)
    flip[3::2] = np.where(gains < 0, -1.0, 1.0)
    fisher = best.fisher * np.outer(flip, flip)
    try:
        cov = np.asarray(np.linalg.inv(fisher), dtype=np.float64)
    except np.linalg.LinAlgError:
        cov = np.full_like(fisher, np.nan)
    loops: list[Optional[FloatArray]] = list(best.loops)
    return Fit(
        beta,
        gamma,
        mu,
        gains,
        phis,
        best.cost,
        best.iterations,
        cov,
        loops,
        best.converged,
        best.stop,
        best.active,
    )

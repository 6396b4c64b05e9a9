#!/usr/bin/env python
"""Speed of the refined identification against the same fit built from SciPy (target: >= 100x).

Run in an environment where the package is installed (or built with ``maturin develop --release``)::

    python benches/bench_refine.py                  # full run: 2-4 minutes (SciPy capped at 3)
    python benches/bench_refine.py --quick          # smoke run: P = 200, N = 20, SciPy capped at ~20 s
    python benches/bench_refine.py --scipy-budget 0 # no cap: run SciPy to convergence (long)
    python benches/bench_refine.py --misfit-only    # only the misfit folders (issue 19): < 30 s

The problem
-----------
Ten sine experiments on the demo plant (``bw.demo_plant()``: ``G(s) = e^{-0.05 s} 25/(s^2 + 2 s + 25)``,
Bouc-Wen alpha = 2, beta = 1.6, gamma = 0.4, mu = 1.6, i.e. alpha-normalised beta = 0.8, gamma = 0.2) at
``omega = geomspace(1, 10, 10)`` rad/s, amplitudes from ``bw.demo.design_amplitudes`` (``|G| U = 1.2 w_0``),
``P = 1000`` samples per period, ``N = 200`` averaged periods after 20 settling ones, noise sd 0.02, one seed.
The recordings are simulated once (``bw.simulate``) and shared by both implementations.

What is timed
-------------
Library (Rust core, single-threaded):

- ``bw.identify(recs, method="refined")``: the whole call (input checks, averaging, noise floor, the
  profile-phase start, the LM refinement, covariance, adequacy), best of ``--repeats``;
- the refinement step alone, ``bouc_wen_id._core.refine`` with exactly the inputs identify passes it,
  recorded by wrapping ``_core.refine`` during one identify call (the averaged periods and amplitudes in the
  unit-order units identify works in, the weights N/sigma^2, the profile-phase start, ``max_iter``, the mu
  bracket, the RK4 substeps), best of ``--repeats``; its result is checked against the call inside identify,
  and its start against ``identify(method="profile")``;
- one model + Jacobian evaluation: the ten ``_core.steady_loop`` calls (loop and exact sensitivities) that
  one LM iteration of the library makes.

SciPy peer (in the same units as the library's refinement): ``scipy.optimize.least_squares`` on the same
weighted residuals ``sqrt(N_i / sigma_i^2) (ybar_i - w_i(beta, gamma, mu, g_i, phi_i))`` (the library's cost
is their sum of squares), from the SAME start (``bw.identify(recs, method="profile")``: its beta, gamma, mu,
gains and phases are exactly what identify hands to the refinement, as the recordings start at t = 0), where
the model loop ``w_i`` comes from ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-11, atol 1e-13) of the alpha
= 1 Bouc-Wen ODE driven by ``x = U g cos(omega t - phi)`` from ``w(0) = 0`` over 8 periods, sampled
(``t_eval``) on the last period's grid. The Jacobian is least_squares' own finite differences (``diff_step =
1e-6``: with the default sqrt(eps) step the ODE solver's error swamps the difference quotient). The tolerance
matters: the right-hand side has kinks (``|xdot|`` at the turning points of x), and at rtol 1e-9 the adaptive
solver leaves sporadic errors of 1e-6..1e-5 at single samples that change non-smoothly with the parameters;
the finite-difference Jacobian then misleads the trust region, and both 'trf' and 'lm' stopped on xtol about
0.6 standard errors away from the minimum. At rtol 1e-11 the loops agree with the library's to ~1e-8 and SciPy
converges to the library's fit. ``--scipy-method trf`` (default) passes ``jac_sparsity`` (each (g_i, phi_i)
touches only its own experiment), so one finite-difference Jacobian costs 5 residual evaluations instead of
23: the strongest SciPy configuration we know, i.e. the most conservative ratio. ``--scipy-method lm``
(MINPACK Levenberg-Marquardt, the library's algorithm) differences all 23 columns.

Misfit folders (issue 19, printed last, alone with ``--misfit-only``): ``bw.identify`` on ten
recordings of the independent generator (``benches/generator.py``) whose plant hides a large mechanical
term (300x the averaged noise), so that the plain model's fit runs into beta = gamma: wall and CPU seconds
(target <= 2 s wall), the core refinements identify ran, the LM iterations, and the final run's stopping
rule and faces.

The SciPy fit can take many minutes.  Unless ``--scipy-budget 0``, it is capped at ``--scipy-budget`` seconds
(180 by default): by ``max_nfev`` when even the library's iteration count would not fit, and by a wall-clock
guard in the residual function otherwise.  When it stops on the cap, the printed total is EXTRAPOLATED
(labelled so): SciPy seconds per LM iteration (1 trial evaluation + one finite-difference Jacobian, from
the mean evaluation time) times the iterations the library's LM needed, i.e. it assumes SciPy would converge
in as many iterations (an estimate either way: SciPy differences a Jacobian only at accepted points, but may
need more iterations).  The time already spent when the cap hit is a hard lower bound, and its ratios are
printed too.
The measured per-evaluation costs and their ratio are printed as well.  The agreement of the two fits is
printed when SciPy converged (otherwise the distance of its best point so far, for information).

Ratios are time(SciPy) / time(library) for the same refinement from the same start; the target line
(>= 100x) ends in PASS or MISS.  Every figure comes from one run; on a loaded machine (see the load average
in the header) rerun before trusting a ratio near its target.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from typing import Any, Callable, Optional

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import bouc_wen_id as bw  # noqa: E402
import numpy as np  # noqa: E402
import scipy  # noqa: E402
from bouc_wen_id import _core  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

TARGET = 100.0
IVP_METHOD, IVP_RTOL, IVP_ATOL = "DOP853", 1e-11, 1e-13
SETTLE_PERIODS_IVP = 8
DIFF_STEP = 1e-6


def fmt_time(sec: float) -> str:
    if sec >= 1.0:
        return f"{sec:.3f} s"
    if sec >= 1e-3:
        return f"{sec * 1e3:.3f} ms"
    return f"{sec * 1e6:.1f} us"


def best_of(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    best, out = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def ivp_loop(
    amp: float, beta: float, gamma: float, mu: float, phi: float, omega: float, p: int
) -> np.ndarray:
    """Steady loop by time-domain integration: w(0) = 0, 8 periods, samples of the last period's grid.

    ``x = amp cos(omega t - phi)`` (``amp = U g``), alpha = 1:
    ``wdot = xdot - beta |xdot| |w|^(mu-1) w - gamma xdot |w|^mu``.
    """
    period = 2.0 * math.pi / omega
    sin, copysign = math.sin, math.copysign

    def rhs(t: float, y: np.ndarray) -> list[float]:
        w = float(y[0])
        xd = -amp * omega * sin(omega * t - phi)
        wm = abs(w) ** mu
        sw = copysign(wm, w) if w != 0.0 else 0.0
        return [xd - beta * abs(xd) * sw - gamma * xd * wm]

    t_eval = (SETTLE_PERIODS_IVP - 1) * period + np.arange(p) * (period / p)
    sol = solve_ivp(
        rhs,
        (0.0, SETTLE_PERIODS_IVP * period),
        [0.0],
        method=IVP_METHOD,
        t_eval=t_eval,
        rtol=IVP_RTOL,
        atol=IVP_ATOL,
    )
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    out: np.ndarray = sol.y[0]
    return out


class OutOfBudget(Exception):
    """Raised by the residual function once the SciPy fit has used its time budget."""


class ScipyProblem:
    """The library's weighted output-error residuals, with the model loop from solve_ivp."""

    def __init__(self, ybars: list[np.ndarray], amps: np.ndarray, omegas: np.ndarray, weights: np.ndarray):
        self.ybars, self.amps, self.omegas = ybars, amps, omegas
        self.sqw = np.sqrt(weights)
        self.m = len(ybars)
        self.calls = 0
        self.seconds = 0.0
        self.deadline: Optional[float] = None
        self.best: tuple[float, Optional[np.ndarray]] = (math.inf, None)

    def residuals(self, par: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        if self.deadline is not None and t0 > self.deadline:
            raise OutOfBudget
        self.calls += 1
        beta, gamma, mu = par[:3]
        out = []
        for i in range(self.m):
            p = self.ybars[i].size
            if mu <= 1.0 or beta + gamma <= 0.0:
                # Outside the model's domain: no bounded loop.  A large residual keeps the LM away.
                w = np.full(p, 1e3)
            else:
                w = ivp_loop(
                    self.amps[i] * par[3 + 2 * i], beta, gamma, mu, par[4 + 2 * i], self.omegas[i], p
                )
            out.append(self.sqw[i] * (self.ybars[i] - w))
        self.seconds += time.perf_counter() - t0
        r = np.concatenate(out)
        cost = float(r @ r)
        if cost < self.best[0]:
            self.best = (cost, np.array(par, dtype=float))
        return r

    def sparsity(self) -> np.ndarray:
        n = 3 + 2 * self.m
        rows = sum(y.size for y in self.ybars)
        s = np.zeros((rows, n), dtype=int)
        s[:, :3] = 1
        r0 = 0
        for i, y in enumerate(self.ybars):
            s[r0 : r0 + y.size, 3 + 2 * i : 5 + 2 * i] = 1
            r0 += y.size
        return s


def machine_info() -> str:
    try:
        load = os.getloadavg()
        lt = f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
    except OSError:  # pragma: no cover
        lt = "load average n/a"
    return (
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"bouc_wen_id {bw.__version__}; {os.cpu_count()} CPUs, {lt}"
    )


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: P = 200, N = 20, SciPy capped at ~20 s")
    ap.add_argument("--scipy-method", choices=("trf", "lm"), default="trf")
    ap.add_argument(
        "--scipy-budget",
        type=float,
        default=None,
        help="seconds for the SciPy fit (0: no cap); 180 by default",
    )
    ap.add_argument("--repeats", type=int, default=5, help="repeats of the library timings (best is kept)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--misfit-only", action="store_true", help="only the misfit table (issue 19)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    if args.misfit_only:
        misfit_table(args.quick)
        return 0
    p, n_per = (200, 20) if args.quick else (1000, 200)
    budget = args.scipy_budget if args.scipy_budget is not None else (20.0 if args.quick else 180.0)

    plant = bw.demo_plant()
    freqs = np.geomspace(1.0, 10.0, 10)
    amps = bw.demo.design_amplitudes(plant, freqs)
    plan = bw.SinePlan(
        freqs,
        amps,
        settle_periods=20,
        periods=n_per,
        samples_per_period=p,
        substeps=2,
        noise_sd=0.02,
        seed=args.seed,
    )
    print("Refined identification: library vs SciPy (least_squares + solve_ivp)")
    print(machine_info())
    print(
        f"demo plant, {len(plan)} experiments at omega = geomspace(1, 10, 10), P = {p}, N = {n_per} "
        f"(+20 settling), noise sd 0.02, seed {args.seed}"
        + ("  [--quick: not for conclusions]" if args.quick else "")
    )
    t0 = time.perf_counter()
    recs = bw.simulate(plant, plan)
    print(f"simulation of the recordings (not timed below): {time.perf_counter() - t0:.2f} s")

    # --- the library -------------------------------------------------------------------------------
    # identify() prepares the data (averaging, noise floor, scaling to unit-order y and u) and hands the
    # refinement its inputs; record them by wrapping _core.refine for one call, so that the refinement
    # alone is timed on exactly those inputs whatever identify's internals do.
    captured: dict[str, Any] = {}
    original = _core.refine

    def recording_refine(*a: Any, **k: Any) -> Any:
        captured["args"], captured["kwargs"] = a, k
        out = original(*a, **k)
        captured["out"] = out
        return out

    _core.refine = recording_refine  # type: ignore[assignment]
    try:
        res = bw.identify(recs, method="refined")
    finally:
        _core.refine = original  # type: ignore[assignment]
    start = bw.identify(recs, method="profile")
    t_ident, res = best_of(lambda: bw.identify(recs, method="refined"), args.repeats)
    t_profile, _ = best_of(lambda: bw.identify(recs, method="profile"), args.repeats)
    ra, rk = captured["args"], captured["kwargs"]
    ybars = [np.ascontiguousarray(y, dtype=float) for y in ra[0]]
    u_amps = np.asarray(ra[1], dtype=float)
    weights = np.asarray(ra[2], dtype=float)
    beta0, gamma0, mu0 = (float(v) for v in ra[3:6])
    gains0, phis0 = np.asarray(ra[6], dtype=float), np.asarray(ra[7], dtype=float)
    substeps = int(rk.get("substeps", 4))
    omegas = np.array([r.frequency for r in recs])
    x0 = np.concatenate([[beta0, gamma0, mu0], np.column_stack([gains0, phis0]).ravel()])
    # The start is the profile-phase estimate, in the units identify works in (y and u scaled to order
    # one: beta' = beta s_y^mu, |G'| = |G| s_u / s_y); check it against identify(method="profile").
    scales = res.settings.get("scales", {"y": 1.0, "u": 1.0})
    s_y, s_u = float(scales["y"]), float(scales["u"])
    start_dev = max(
        abs(beta0 / s_y**mu0 - start.beta),
        abs(gamma0 / s_y**mu0 - start.gamma),
        abs(mu0 - start.mu),
        float(np.max(np.abs(np.abs(gains0) * s_y / s_u - start.gains))),
        float(np.max(np.abs(np.mod(phis0 - start.phases + math.pi, 2 * math.pi) - math.pi))),
    )

    def lib_refine() -> Any:
        return original(*ra, **rk)

    t_refine, out = best_of(lib_refine, args.repeats)
    lib_params, lib_cost, lib_iter, lib_conv, lib_fisher, _ = out
    lib_params = np.asarray(lib_params)
    dev = float(np.max(np.abs(lib_params - np.asarray(captured["out"][0]))))

    def lib_eval() -> None:
        for i in range(len(ybars)):
            _core.steady_loop(
                u_amps[i] * lib_params[3 + 2 * i],
                lib_params[0],
                lib_params[1],
                lib_params[2],
                lib_params[4 + 2 * i],
                ybars[i].size,
                substeps,
            )

    t_lib_eval, _ = best_of(lib_eval, max(args.repeats, 20))

    print("\nlibrary (Rust core)")
    print(
        f"  identify(method='refined'), whole call        {fmt_time(t_ident):>12}   "
        f"({args.repeats} repeats, best)"
    )
    print(f"  identify(method='profile'), the start          {fmt_time(t_profile):>12}")
    print(
        f"  _core.refine alone                             {fmt_time(t_refine):>12}   "
        f"{lib_iter} LM iterations, converged: {lib_conv}, cost (chi2) {lib_cost:.6g}"
    )
    print(
        f"  one model + exact Jacobian evaluation (10 loops){fmt_time(t_lib_eval):>12}   "
        f"(substeps {substeps})"
    )
    print(
        f"  refine inputs: {len(ybars)} averaged periods, weights N/sigma^2, substeps {substeps}, "
        f"{', '.join(f'{k} = {v}' for k, v in rk.items() if k != 'substeps')}; units scaled by "
        f"s_y = {s_y:.4g}, s_u = {s_u:.4g}"
    )
    print(f"  start vs identify(method='profile') (in its units): max |difference| = {start_dev:.1e}")
    print(f"  _core.refine alone vs the call inside identify(): max |parameter difference| = {dev:.1e}")
    print(
        f"  identify fit: beta {res.beta:.6f}, gamma {res.gamma:.6f}, mu {res.mu:.6f} (truth 0.8, 0.2, 1.6)"
        + (
            f"; se {res.standard_errors['beta']:.1e}, {res.standard_errors['gamma']:.1e}, "
            f"{res.standard_errors['mu']:.1e}"
            if res.standard_errors
            else ""
        )
    )

    # --- SciPy ---------------------------------------------------------------------------------------
    prob = ScipyProblem(ybars, u_amps, omegas, weights)
    m = len(ybars)
    n_par = 3 + 2 * m
    # Accuracy of the time-domain loop against the library's steady loop, at the library's fit.
    r_ivp = prob.residuals(lib_params)
    t_res = prob.seconds
    lib_loops = np.concatenate(
        [
            np.asarray(
                _core.steady_loop(
                    u_amps[i] * lib_params[3 + 2 * i],
                    *lib_params[:3],
                    lib_params[4 + 2 * i],
                    ybars[i].size,
                    substeps,
                )[0]
            )
            for i in range(m)
        ]
    )
    ivp_loops = np.concatenate(ybars) - r_ivp / np.repeat(prob.sqw, [y.size for y in ybars])
    loop_dev = float(np.max(np.abs(ivp_loops - lib_loops)))
    cost_ivp = float(np.sum(r_ivp**2))
    if args.scipy_method == "trf":
        fd_per_jac = 5  # 3 shared columns + one group for all g_i, one for all phi_i
        kw: dict[str, Any] = {"method": "trf", "jac_sparsity": prob.sparsity(), "x_scale": "jac"}
    else:
        fd_per_jac = n_par
        kw = {"method": "lm", "x_scale": "jac"}
    per_iter = (1 + fd_per_jac) * t_res
    est_total = lib_iter * per_iter
    print(
        f"\nSciPy peer: least_squares(method='{args.scipy_method}', diff_step {DIFF_STEP:g}) + "
        f"solve_ivp({IVP_METHOD}, rtol {IVP_RTOL:g}, atol {IVP_ATOL:g}), "
        f"{SETTLE_PERIODS_IVP} periods from w = 0"
    )
    print(f"  one residual evaluation (10 solve_ivp runs)     {fmt_time(t_res):>12}")
    print(
        f"  its loops vs the library's steady loops at the library fit: max |dw| = {loop_dev:.1e}; "
        f"cost {cost_ivp:.6g} (library {lib_cost:.6g})"
    )
    print(
        f"  one LM iteration ~ 1 + {fd_per_jac} evaluations (finite-difference Jacobian) "
        f"{fmt_time(per_iter):>12}"
    )
    if budget > 0:
        # Two caps: max_nfev (trial points; finite-difference calls are not counted by SciPy >= 1.15's
        # 'trf' nor by its 'lm') when even the library's iteration count would not fit, and a wall-clock
        # guard in the residual function (the fit usually needs more iterations than the library).
        if est_total > budget:
            kw["max_nfev"] = max(2, int(budget / per_iter))
        print(
            f"  capped: wall-clock budget {budget:.0f} s"
            + (f", max_nfev = {kw['max_nfev']}" if "max_nfev" in kw else "")
            + " (--scipy-budget 0 lifts the cap)"
        )
    prob.calls, prob.seconds, prob.best = 0, 0.0, (math.inf, None)
    t0 = time.perf_counter()
    prob.deadline = t0 + budget if budget > 0 else None
    sol: Any = None
    try:
        sol = least_squares(prob.residuals, x0, diff_step=DIFF_STEP, ftol=1e-12, xtol=1e-10, gtol=1e-12, **kw)
    except OutOfBudget:
        pass
    t_scipy = time.perf_counter() - t0
    prob.deadline = None
    converged = sol is not None and sol.status > 0
    t_call = prob.seconds / max(prob.calls, 1)
    if sol is not None:
        status = f"nfev {sol.nfev}, njev {sol.njev}, status {sol.status} ({sol.message.strip()})"
    else:
        status = "stopped by the wall-clock budget"
    print(
        f"  least_squares: {t_scipy:.1f} s, {prob.calls} residual evaluations "
        f"({fmt_time(t_call)} each), {status}"
    )
    final = sol.x if converged else prob.best[1]
    assert final is not None
    d = np.array(final, dtype=float) - lib_params
    d[4::2] = (d[4::2] + math.pi) % (2 * math.pi) - math.pi
    try:
        se = np.sqrt(np.abs(np.diag(np.linalg.inv(np.asarray(lib_fisher)))))
    except np.linalg.LinAlgError:
        se = np.full(n_par, math.nan)
    what = "converged fit" if converged else "best point of the capped run (NOT converged)"
    print(f"  SciPy {what} minus library fit (refinement units; in the library's standard errors):")
    print(
        f"    beta {d[0]:+.2e} ({d[0] / se[0]:+.3f} se), gamma {d[1]:+.2e} ({d[1] / se[1]:+.3f} se), "
        f"mu {d[2]:+.2e} ({d[2] / se[2]:+.3f} se)"
    )
    print(
        f"    max |d g_i| {np.max(np.abs(d[3::2])):.2e} ({np.max(np.abs(d[3::2] / se[3::2])):.3f} se), "
        f"max |d phi_i| {np.max(np.abs(d[4::2])):.2e} ({np.max(np.abs(d[4::2] / se[4::2])):.3f} se); "
        f"cost {float(np.sum(prob.residuals(final) ** 2)):.6g} (library {lib_cost:.6g}; "
        f"start {float(np.sum(prob.residuals(x0) ** 2)):.6g})"
    )

    # --- ratios ----------------------------------------------------------------------------------------
    if converged:
        scipy_total, label = t_scipy, "measured (converged)"
    else:
        # Seconds per SciPy iteration from the capped run's mean evaluation (trial point + its Jacobian).
        per_iter_run = (1 + fd_per_jac) * t_call
        scipy_total = max(lib_iter * per_iter_run, t_scipy)
        label = (
            f"EXTRAPOLATED: {lib_iter} LM iterations (as many as the library needed) x "
            f"{fmt_time(per_iter_run)} per SciPy iteration (mean evaluation of the capped run), at least "
            f"the {t_scipy:.0f} s already spent"
        )
    print("\nratios SciPy / library (same refinement, same start)")
    print(f"  per model evaluation: solve_ivp residual / Rust loop+Jacobian   {t_call / t_lib_eval:10.0f}x")
    print(
        f"  per LM iteration: (1 + {fd_per_jac}) residuals / one Rust evaluation      "
        f"{(1 + fd_per_jac) * t_call / t_lib_eval:10.0f}x"
    )
    print(f"  SciPy refinement total: {scipy_total:.1f} s, {label}")
    rows = [("", scipy_total)]
    if not converged:
        rows.append((f"lower bound ({t_scipy:.0f} s spent when capped) ", t_scipy))
    for what, total in rows:
        for name, t_lib in (("identify() whole call", t_ident), ("_core.refine alone   ", t_refine)):
            r = total / t_lib
            verdict = "PASS" if r >= TARGET else "MISS"
            print(f"  {what}SciPy refinement / library {name} {r:9.0f}x  target >= {TARGET:.0f}x  {verdict}")
    misfit_table(args.quick)
    print(f"\n(total bench time {time.perf_counter() - t_start:.1f} s)")
    return 0


#: Misfit cases of the independent generator (benches/generator.py): a plant hiding a large mechanical term
#: (300x the averaged noise), ten experiments each; the plain model's fit runs into beta = gamma (issue 19).
MISFIT_CASES = (("viscous", "u", 1), ("inertia", "x", 1), ("inertia", "x", 2), ("coulomb", "u", 1))
#: Target wall time of identify on a ten-experiment misfit folder.
MISFIT_TARGET_S = 2.0


def misfit_table(quick: bool) -> None:
    """identify() on misfit folders: wall and CPU seconds, LM iterations, the stopping rule and the faces."""
    import warnings

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import generator as gen  # the bench's own generator, beside this script
    from bouc_wen_id import estimators

    runs: list[Any] = []
    original = estimators.LMRun.from_core

    def recording(out: tuple[Any, ...]) -> Any:
        run = original(out)
        runs.append(run)
        return run

    print("\nmisfit folders (10 experiments, plain model): identify() until it stops on the boundary")
    print(f"  {'case':<22}{'wall s':>8}{'cpu s':>8}{'refines':>9}{'iters':>7}  stop / faces of the final run")
    cases = MISFIT_CASES[:1] if quick else MISFIT_CASES
    estimators.LMRun.from_core = recording  # type: ignore[method-assign]
    try:
        for name, place, seed in cases:
            recs = gen.make_case("effect", name, place, 300.0, seed).recordings
            runs.clear()
            t0, c0 = time.perf_counter(), time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    res = bw.identify(recs)
                    iters = str(res.iterations)
                except bw.BoucWenIdError as exc:
                    iters = type(exc).__name__
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            last = runs[-1] if runs else None
            faces = f"{last.stop} / {','.join(last.active) or '-'}" if last is not None else "-"
            verdict = "PASS" if wall <= MISFIT_TARGET_S else "MISS"
            label = f"{name} on {place}, seed {seed}"
            print(
                f"  {label:<22}{wall:8.2f}{cpu:8.2f}{len(runs):9d}{iters:>7}  {faces}"
                f"  (<= {MISFIT_TARGET_S} s: {verdict})"
            )
    finally:
        estimators.LMRun.from_core = original  # type: ignore[method-assign]


if __name__ == "__main__":
    sys.exit(main())

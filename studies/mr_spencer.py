"""MR damper: does Spencer's full phenomenological model reach a held-out NRMSE <= 0.03 (issue 18)?

Spencer, Dyke, Sain and Carlson (1997), with the measured displacement x = u (the displacement is measured
at the damper; one shared gain on x is redundant with the parameters, see below):

    F     = c1 ydot + k1 x + f0                      (f0 = -k1 x0)
    ydot  = (alpha z + c0 xdot + k0 (x - y)) / (c0 + c1)
    zdot  = -gamma |v| z |z|^(n-1) - beta v |z|^n + A v,   v = xdot - ydot

A is fixed at 1: scaling z by s maps (alpha, A, beta, gamma) to (alpha / s, s A, beta s^(1-n), gamma s^(1-n))
with the same force, so A is not identifiable beside alpha. A gain g on x is redundant too (c0, c1, k0, k1,
beta, gamma divided by g, y and x0 multiplied by g give the same force), so x = u exactly.
The state is (w, z) with w = x - y. The variants (which part of the model buys the fit):

- ``bw``: Spencer's simple Bouc-Wen model, F = alpha z + c0 xdot + k1 x + f0 with z driven by xdot
  (c1 -> infinity, k0 = 0);
- ``series``: Spencer without k0 (k0 = 0). This is exactly the library's series dashpot (rho = 1/c1') plus a
  dashpot c0' across the damper (a reparametrisation: c0' = c0 c1 / (c0 + c1), c1' = c1^2 / (c0 + c1));
- ``spencer``: the full model.

Per coil current level (the six files, as ``studies/diagnose_real.py`` groups them, reduced to their averaged
periods by the diagnosis's own ``prepare``), one parameter set shared by the six files is fitted by
``scipy.optimize.least_squares`` (trf, bounds) on the periodic steady state: RK4 on a fixed grid of N steps
per period in the phase z = omega t, driven by the measured input's waveform; the periodic orbit found by
Newton shooting on the initial state (w, z) (finite-difference monodromy), its periodicity error reported;
the model's force projected on the same K harmonics as the averaged period and evaluated on its P points.
Each file's residual is divided by the spread of its averaged period, so the cost is the sum of the squared
NRMSEs. Held out: leave one file out (``diagnosis.select.folds``), fit on the other five from the full fit,
predict the left-out file with nothing refitted (no gain, no phase: stricter than the diagnosis's held-out,
which refits the left-out file's |G| and phase). The floor per file is ``mr_what_is_left.floor_of``.

All fits run concurrently: each ``least_squares`` call runs in its own thread and its evaluations (residual
and the forward-difference Jacobian, one batch of parameter sets) are stacked with every other fit's into
one vectorised RK4 run (:class:`Batcher`), so the cost is that of the longest fit, not their sum.

Usage: ``python studies/mr_spencer.py [--data DIR] [--levels 0,0.5] [--variants bw,series,spencer]
[--starts 4] [--seed 0] [--steps 720] [--json OUT]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the sibling modules import by name (studies/ is not a package)
    sys.path.insert(0, str(HERE))

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi
TARGET = 0.03
#: The natural parameters (A = 1). ``gratio`` = gamma / beta in [-1, 1] keeps beta >= |gamma|.
NAMES = ("alpha", "beta", "gratio", "n", "c0", "c1", "k0", "k1", "f0")
#: Parameters fitted in logs (positive).
LOGS = frozenset({"alpha", "beta", "c0", "c1", "k0"})
#: Bounds in natural units (N, mm, s): physical and wide.
BOUNDS = {
    "alpha": (1e-2, 1e7),
    "beta": (1e-6, 1e8),
    "gratio": (-1.0, 1.0),
    "n": (0.5, 10.0),
    "c0": (1e-4, 1e3),
    "c1": (1e-3, 1e5),
    "k0": (1e-4, 1e5),
    "k1": (-1e3, 1e3),
    "f0": (-1e4, 1e4),
}
#: A c1 this large is a rigid series element (the ``bw`` variant).
RIGID = 1e12
#: Variants: the parameters held fixed (natural values).
VARIANTS: dict[str, dict[str, float]] = {
    "bw": {"c1": RIGID, "k0": 0.0},
    "series": {"k0": 0.0},
    "spencer": {},
}
#: Newton shooting: periodicity tolerance (state error relative to its scale) and most rounds.
SHOOT_TOL = 1e-7
SHOOT_ROUNDS = 6


# ------------------------------------------------------------------------------------------------------
# The experiments and the simulator


@dataclass
class Exp:
    """One averaged period: its data and the input on the RK4 half-step grid."""

    source: str
    ybar: FloatArray
    amplitude: float
    omega: float
    waveform: FloatArray
    grid_phase: float
    spread: float = 0.0
    cache: dict[int, tuple[FloatArray, FloatArray]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.spread = float(np.linalg.norm(self.ybar - self.ybar.mean()))

    @property
    def harmonics(self) -> int:
        return (self.ybar.size - 1) // 2

    def inputs(self, steps: int) -> tuple[FloatArray, FloatArray]:
        """x (mm) and xdot (mm/s) at the phases psi + j pi / steps, j = 0..2 steps."""
        if steps not in self.cache:
            zz = self.grid_phase + np.arange(2 * steps + 1) * (math.pi / steps)
            w = self.waveform
            c = np.concatenate([[1.0 + 0.0j], w[0::2] + 1j * w[1::2]])
            k = np.arange(1, c.size + 1)
            e = np.exp(1j * np.outer(zz, k))
            x = self.amplitude * np.real(e @ c)
            xd = self.amplitude * self.omega * np.real(e @ (1j * k * c))
            self.cache[steps] = (x, xd)
        return self.cache[steps]


def experiments(ms: Sequence[Any]) -> list[Exp]:
    """The level's averaged periods as the diagnosis prepares them (``diagnosis.data.prepare``)."""
    from bouc_wen_id.diagnosis.data import prepare

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exps = prepare(list(ms))
    return [
        Exp(
            e.source,
            np.asarray(e.ybar, dtype=np.float64),
            float(e.amplitude),
            float(e.frequency),
            np.asarray(e.waveform, dtype=np.float64),
            float(e.grid_phase),
        )
        for e in exps
    ]


def natural(theta: FloatArray) -> dict[str, FloatArray]:
    """Columns of ``theta`` (rows: parameter sets, columns :data:`NAMES`) with gamma = gratio beta."""
    d = {k: theta[:, i] for i, k in enumerate(NAMES)}
    d["gamma"] = d["gratio"] * d["beta"]
    return d


@dataclass
class Steady:
    """Outputs (the model's averaged period per lane), the periodicity error and the end states."""

    outputs: list[FloatArray]
    periodicity: float
    states: FloatArray
    rounds: int


def _period(
    p: dict[str, FloatArray],
    x: FloatArray,
    xd: FloatArray,
    iom: FloatArray,
    w: FloatArray,
    z: FloatArray,
    record: bool,
) -> tuple[FloatArray, FloatArray, Optional[FloatArray]]:
    """One period of RK4 from (w, z) on every lane; the force at the N nodes when ``record``."""
    al, c0, c1, k0, k1, f0 = p["alpha"], p["c0"], p["c1"], p["k0"], p["k1"], p["f0"]
    inv_c = 1.0 / (c0 + c1)
    bpg, bmg, n = p["beta"] + p["gamma"], p["beta"] - p["gamma"], p["n"]
    steps = (x.shape[0] - 1) // 2
    h = TWO_PI / steps

    def rhs(w: FloatArray, z: FloatArray, xd_: FloatArray) -> tuple[FloatArray, FloatArray]:
        wd = xd_ - (al * z + c0 * xd_ + k0 * w) * inv_c
        zd = wd * (1.0 - np.abs(z) ** n * np.where(wd * z > 0.0, bpg, bmg))
        return wd * iom, zd * iom

    force = np.empty((steps, w.size)) if record else None
    for m in range(steps):
        d0, dm, d1 = xd[2 * m], xd[2 * m + 1], xd[2 * m + 2]
        a1, b1 = rhs(w, z, d0)
        if force is not None:
            force[m] = c1 * ((al * z + c0 * d0 + k0 * w) * inv_c) + k1 * x[2 * m] + f0
        a2, b2 = rhs(w + 0.5 * h * a1, z + 0.5 * h * b1, dm)
        a3, b3 = rhs(w + 0.5 * h * a2, z + 0.5 * h * b2, dm)
        a4, b4 = rhs(w + h * a3, z + h * b3, d1)
        w = w + (h / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        z = z + (h / 6.0) * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
    return w, z, force


def _project(force: FloatArray, sizes: Sequence[int]) -> list[FloatArray]:
    """Each lane's force (N nodes) on its averaged period's K harmonics at its P points."""
    steps = force.shape[0]
    spec = np.fft.rfft(force, axis=0)
    out = []
    for j, p in enumerate(sizes):
        k = (p - 1) // 2
        c = np.zeros(p // 2 + 1, dtype=np.complex128)
        c[: k + 1] = spec[: k + 1, j] * (p / steps)
        out.append(np.fft.irfft(c, n=p))
    return out


#: Most RK4 steps per radian times the lane's stiffness (RK4 is stable below 2.78; 1.5 keeps it accurate).
STIFF_STEP = 1.5
#: Largest multiple of the base step count a stiff lane gets.
MAX_MULTIPLE = 16


def multiples(theta: FloatArray, exps: Sequence[Exp], steps: int) -> NDArray[np.int64]:
    """Per lane, the power of two times ``steps`` that keeps h lambda <= :data:`STIFF_STEP`, with lambda per
    radian the series relaxation (alpha + k0) / ((c0 + c1) omega) plus the element's own n U / z_s (its
    stiffness at saturation over a stroke U): a large stroke at a low frequency with a short yield travel
    needs many more steps per period than a small fast one."""
    p = natural(theta)
    om = np.array([e.omega for e in exps])
    u = np.array([e.amplitude for e in exps])
    with np.errstate(all="ignore"):
        zs = (p["beta"] + np.abs(p["gamma"])) ** (-1.0 / p["n"])
        lam = (p["alpha"] + p["k0"]) / ((p["c0"] + p["c1"]) * om) + np.maximum(p["n"], 1.0) * u / zs
        need = np.where(np.isfinite(lam), TWO_PI * lam / STIFF_STEP / steps, MAX_MULTIPLE)
        m = 2.0 ** np.ceil(np.log2(np.clip(need, 1.0, MAX_MULTIPLE)))
    return m.astype(np.int64)


def steady(
    theta: FloatArray,
    exps: Sequence[Exp],
    steps: int,
    start: Optional[FloatArray] = None,
    mult: Optional[NDArray[np.int64]] = None,
) -> Steady:
    """:func:`steady_fixed` with each lane's steps per period ``steps`` times its multiple (``mult``, else
    :func:`multiples` of its own parameters), lanes of one multiple run together."""
    m = multiples(theta, exps, steps) if mult is None else mult
    outputs: list[FloatArray] = [np.zeros(0)] * len(exps)
    states = np.empty((len(exps), 2))
    err, rounds = 0.0, 0
    for k in np.unique(m):
        idx = np.flatnonzero(m == k)
        st = None if start is None else start[idx]
        r = steady_fixed(theta[idx], [exps[i] for i in idx], int(steps * k), st)
        for i, o in zip(idx, r.outputs):
            outputs[i] = o
        states[idx] = r.states
        err, rounds = max(err, r.periodicity), max(rounds, r.rounds)
    return Steady(outputs, err, states, rounds)


def steady_fixed(
    theta: FloatArray, exps: Sequence[Exp], steps: int, start: Optional[FloatArray] = None
) -> Steady:
    """The periodic steady state of every (parameter set, experiment) lane.

    ``theta``: (L, 9) natural parameters per lane; ``exps``: the L lanes' experiments; ``start``: (L, 2)
    initial (w, z), else one period from rest. Newton shooting on (w, z) with a finite-difference monodromy
    (three lanes per lane), then a recorded period from the orbit's start; repeated while the periodicity
    error (relative to U and to z's saturation level) exceeds :data:`SHOOT_TOL`.
    """
    lanes = len(exps)
    x = np.column_stack([e.inputs(steps)[0] for e in exps])
    xd = np.column_stack([e.inputs(steps)[1] for e in exps])
    iom = np.array([1.0 / e.omega for e in exps])
    p = natural(theta)
    scale = np.column_stack(
        [np.array([e.amplitude for e in exps]), (p["beta"] + np.abs(p["gamma"]) + 1e-300) ** (-1.0 / p["n"])]
    )
    with np.errstate(all="ignore"):
        s = np.full((lanes, 2), np.nan) if start is None else start.copy()
        cold = ~np.all(np.isfinite(s), axis=1)
        if np.any(cold):  # one period from rest for the lanes without a start
            w, z, _ = _period(p, x, xd, iom, np.zeros(lanes), np.zeros(lanes), False)
            s[cold] = np.column_stack([w, z])[cold]
        p3 = {k: np.tile(v, 3) for k, v in p.items()}
        x3, xd3, iom3 = np.tile(x, (1, 3)), np.tile(xd, (1, 3)), np.tile(iom, 3)
        err, rounds, force = np.inf, 0, None
        while rounds < SHOOT_ROUNDS:
            rounds += 1
            d = 1e-6 * scale
            w0 = np.concatenate([s[:, 0], s[:, 0] + d[:, 0], s[:, 0]])
            z0 = np.concatenate([s[:, 1], s[:, 1], s[:, 1] + d[:, 1]])
            w1, z1, _ = _period(p3, x3, xd3, iom3, w0, z0, False)
            phi = np.column_stack([w1[:lanes], z1[:lanes]])
            m11 = (w1[lanes : 2 * lanes] - phi[:, 0]) / d[:, 0] - 1.0
            m21 = (z1[lanes : 2 * lanes] - phi[:, 1]) / d[:, 0]
            m12 = (w1[2 * lanes :] - phi[:, 0]) / d[:, 1]
            m22 = (z1[2 * lanes :] - phi[:, 1]) / d[:, 1] - 1.0
            r = phi - s
            det = m11 * m22 - m12 * m21
            # k0 = 0: w does not enter the dynamics nor the force (a neutral direction): z-only steps.
            ok = (p["k0"] > 0.0) & (np.abs(det) > 1e-9 * (np.abs(m11 * m22) + np.abs(m12 * m21) + 1e-300))
            step_w = np.where(ok, (m22 * r[:, 0] - m12 * r[:, 1]) / np.where(ok, det, 1.0), 0.0)
            step_z = np.where(ok, (-m21 * r[:, 0] + m11 * r[:, 1]) / np.where(ok, det, 1.0), r[:, 1] / m22)
            # A lane whose monodromy is singular (k0 = 0: w is neutral) takes the z-only step.
            new = s - np.column_stack([step_w, step_z])
            new = np.where(np.isfinite(new), new, phi)
            w2, z2, force = _period(p, x, xd, iom, new[:, 0], new[:, 1], True)
            end = np.column_stack([w2, z2])
            e = np.abs(end - new) / scale
            e[p["k0"] == 0.0, 0] = 0.0  # the neutral w does not enter the force
            err = float(np.nanmax(e)) if np.all(np.isfinite(e)) else np.inf
            s = end
            if err < SHOOT_TOL:
                break
    assert force is not None
    return Steady(_project(force, [e.ybar.size for e in exps]), err, s, rounds)


# ------------------------------------------------------------------------------------------------------
# Concurrent least-squares fits


class Batcher:
    """Runs several fits in threads; each evaluation request waits until every live fit has asked, then all
    requests are simulated as one vectorised batch (the GIL makes the threads take turns anyway)."""

    def __init__(self, steps: int) -> None:
        self.steps = steps
        self.cv = threading.Condition()
        self.pending: dict[int, tuple[FloatArray, list[Exp], Optional[FloatArray]]] = {}
        self.results: dict[int, Steady] = {}
        self.active = 0
        self.batches = 0
        self.worst_periodicity = 0.0

    def _maybe_run(self) -> None:
        if not self.pending or len(self.pending) < self.active:
            return
        reqs, self.pending = self.pending, {}
        thetas, lanes, starts, owners = [], [], [], []
        for tid, (theta, exps, start) in reqs.items():
            k = theta.shape[0]
            thetas.append(np.repeat(theta, len(exps), axis=0))
            lanes += list(exps) * k
            starts.append(None if start is None else np.tile(start, (k, 1)))
            owners.append((tid, k * len(exps)))
        st0 = np.concatenate(
            [np.full((n, 2), np.nan) if s is None else s for s, (_, n) in zip(starts, owners)]
        )
        # One step multiple per (fit, experiment), from its base parameter set, so a forward-difference
        # Jacobian compares outputs of one step size.
        mult = np.concatenate(
            [
                np.tile(multiples(np.repeat(th[:1], len(ex), axis=0), ex, self.steps), th.shape[0])
                for th, ex, _ in reqs.values()
            ]
        )
        res = steady(np.concatenate(thetas), lanes, self.steps, st0, mult)
        self.batches += 1
        if math.isfinite(res.periodicity):
            self.worst_periodicity = max(self.worst_periodicity, res.periodicity)
        a = 0
        for tid, size in owners:
            self.results[tid] = Steady(
                res.outputs[a : a + size], res.periodicity, res.states[a : a + size], res.rounds
            )
            a += size
        self.cv.notify_all()

    def evaluate(self, tid: int, theta: FloatArray, exps: list[Exp], start: Optional[FloatArray]) -> Steady:
        with self.cv:
            self.pending[tid] = (theta, exps, start)
            self._maybe_run()
            while tid not in self.results:
                self.cv.wait()
            return self.results.pop(tid)

    def run(self, jobs: Sequence[Callable[[Callable[..., Steady]], Any]]) -> list[Any]:
        """Run each job (given its evaluate function) in its own thread; their results in order."""
        out: list[Any] = [None] * len(jobs)
        self.active = len(jobs)

        def body(i: int) -> None:
            try:
                out[i] = jobs[i](lambda th, ex, st: self.evaluate(i, th, ex, st))
            except BaseException as exc:  # reported, never swallowed: the caller re-raises
                out[i] = exc
            finally:
                with self.cv:
                    self.active -= 1
                    self._maybe_run()

        threads = [threading.Thread(target=body, args=(i,)) for i in range(len(jobs))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for r in out:
            if isinstance(r, BaseException):
                raise r
        return out


@dataclass
class Model:
    """A variant's free parameters and the map between the optimiser's q and the natural parameters."""

    variant: str
    fixed: dict[str, float]

    @property
    def free(self) -> list[str]:
        return [k for k in NAMES if k not in self.fixed]

    def theta(self, q: FloatArray) -> FloatArray:
        """(S, 9) natural parameters from (S, n_free) q."""
        q = np.atleast_2d(q)
        out = np.empty((q.shape[0], len(NAMES)))
        free = self.free
        for i, k in enumerate(NAMES):
            if k in self.fixed:
                out[:, i] = self.fixed[k]
            else:
                v = q[:, free.index(k)]
                out[:, i] = np.exp(v) if k in LOGS else v
        return out

    def q(self, nat: dict[str, float]) -> FloatArray:
        return np.array([math.log(nat[k]) if k in LOGS else nat[k] for k in self.free])

    def bounds(self) -> tuple[FloatArray, FloatArray]:
        lo = [math.log(BOUNDS[k][0]) if k in LOGS else BOUNDS[k][0] for k in self.free]
        hi = [math.log(BOUNDS[k][1]) if k in LOGS else BOUNDS[k][1] for k in self.free]
        return np.array(lo), np.array(hi)


def nrmse(e: Exp, y: FloatArray) -> float:
    """The held-out definition of the diagnosis (``diagnosis.select.held_out``): ||ybar - y|| over the
    averaged period's spread ||ybar - mean||."""
    return float(np.linalg.norm(e.ybar - y)) / (e.spread or 1.0)


@dataclass
class FitResult:
    q: FloatArray
    cost: float
    nrmse: list[float]
    nfev: int
    status: int
    at_bound: list[str]


FD_STEP = 1e-6


def fit_job(
    model: Model, exps: list[Exp], q0: FloatArray, max_nfev: int
) -> Callable[[Callable[..., Steady]], FitResult]:
    """A job for :meth:`Batcher.run`: least_squares of ``model`` on ``exps`` from ``q0``."""
    lo, hi = model.bounds()
    q0 = np.clip(q0, lo + 1e-9, hi - 1e-9)

    def job(evaluate: Callable[..., Steady]) -> FitResult:
        memo: dict[bytes, tuple[FloatArray, FloatArray]] = {}
        state: list[Optional[FloatArray]] = [None]

        def both(q: FloatArray) -> tuple[FloatArray, FloatArray]:
            key = q.tobytes()
            if key not in memo:
                memo.clear()
                hs = FD_STEP * np.maximum(1.0, np.abs(q))
                hs = np.where(q + hs > hi, -hs, hs)
                qs = np.vstack([q, q + np.diag(hs)])
                res = evaluate(model.theta(qs), exps, state[0])
                f = len(exps)
                rows = []
                for s in range(qs.shape[0]):
                    rows.append(
                        np.concatenate([(y - e.ybar) / e.spread for y, e in zip(res.outputs[s * f :], exps)])
                    )
                r = np.array(rows)
                if np.all(np.isfinite(r[0])):
                    state[0] = res.states[:f]
                r = np.where(np.isfinite(r), r, 1e3)
                memo[key] = (r[0], ((r[1:] - r[0]) / hs[:, None]).T)
            return memo[key]

        sol = least_squares(
            lambda q: both(q)[0],
            q0,
            jac=lambda q: both(q)[1],
            bounds=(lo, hi),
            x_scale="jac",
            max_nfev=max_nfev,
            ftol=1e-10,
            xtol=1e-10,
        )
        r = both(sol.x)[0]
        per, a = [], 0
        for e in exps:
            per.append(float(np.linalg.norm(r[a : a + e.ybar.size])))
            a += e.ybar.size
        near = [
            k for k, v, a_, b_ in zip(model.free, sol.x, lo, hi) if min(v - a_, b_ - v) < 1e-6 * (1 + abs(v))
        ]
        return FitResult(sol.x, float(r @ r), per, int(sol.nfev), int(sol.status), near)

    return job


def predict_job(model: Model, e: Exp, q: FloatArray) -> Callable[[Callable[..., Steady]], float]:
    def job(evaluate: Callable[..., Steady]) -> float:
        return nrmse(e, evaluate(model.theta(q), [e], None).outputs[0])

    return job


# ------------------------------------------------------------------------------------------------------
# The study


def first_guess(exps: Sequence[Exp]) -> dict[str, float]:
    """A start from the data: the yield force half the force amplitude at a 0.3 mm travel, the viscous part
    from the rest of the amplitude at the peak velocity, c1 twenty times c0, a weak k0, no k1."""
    amp = float(np.median([np.ptp(e.ybar) / 2.0 for e in exps]))
    vel = float(np.median([e.amplitude * e.omega for e in exps]))
    zs, n, g = 0.3, 2.0, 0.5
    c0 = 0.4 * amp / vel
    return {
        "alpha": 0.5 * amp / zs,
        "beta": zs**-n / (1.0 + g),
        "gratio": g,
        "n": n,
        "c0": c0,
        "c1": 20.0 * c0,
        "k0": 0.05 * amp / float(np.median([e.amplitude for e in exps])),
        "k1": 0.0,
        "f0": float(np.median([e.ybar.mean() for e in exps])),
    }


def starts(model: Model, exps: Sequence[Exp], count: int, rng: np.random.Generator) -> list[FloatArray]:
    """The data's first guess, then ``count - 1`` seeded random draws around it."""
    base = first_guess(exps)
    out = [model.q(base)]
    for _ in range(count - 1):
        d = dict(base)
        for k in LOGS:
            d[k] = base[k] * math.exp(0.8 * rng.standard_normal())
        d["n"] = rng.uniform(1.2, 3.5)
        d["gratio"] = rng.uniform(-0.5, 1.0)
        d["beta"] = d["beta"] * (1.0 + base["gratio"]) / (1.0 + d["gratio"])
        out.append(model.q(d))
    return out


def describe(model: Model, q: FloatArray) -> dict[str, float]:
    """Natural parameters, gamma, and the yield force alpha z_s (z_s = (beta + gamma)^(-1/n), mm)."""
    th = model.theta(q)[0]
    d = {k: float(v) for k, v in zip(NAMES, th)}
    d["gamma"] = d["gratio"] * d["beta"]
    d["z_s"] = (d["beta"] + d["gamma"]) ** (-1.0 / d["n"]) if d["beta"] + d["gamma"] > 0 else math.inf
    d["f_yield"] = d["alpha"] * d["z_s"]
    return d


def integration_check(model: Model, q: FloatArray, exps: Sequence[Exp], steps: int) -> dict[str, float]:
    """The fitted model at ``steps`` and ``2 steps`` per period: the largest output difference over the
    averaged period's spread, and the periodicity errors."""
    th = np.repeat(model.theta(q), len(exps), axis=0)
    a = steady(th, list(exps), steps)
    b = steady(th, list(exps), 2 * steps)
    diff = max(
        float(np.max(np.abs(x - y))) / e.spread * math.sqrt(e.ybar.size)
        for x, y, e in zip(a.outputs, b.outputs, exps)
    )
    diff_rms = max(float(np.linalg.norm(x - y)) / e.spread for x, y, e in zip(a.outputs, b.outputs, exps))
    return {
        "nrmse_change_2x_steps": diff_rms,
        "max_point_change": diff,
        "periodicity": a.periodicity,
        "periodicity_2x": b.periodicity,
        "shooting_rounds": float(a.rounds),
    }


def run(
    levels: list[tuple[str, list[Exp]]],
    variants: Sequence[str],
    n_starts: int,
    seed: int,
    steps: int,
    max_nfev: int,
    fold_nfev: int,
) -> dict[str, Any]:
    """Every (variant, level): multistart fit on all six files, then the six leave-one-out folds."""
    from bouc_wen_id.diagnosis.select import folds

    rng = np.random.default_rng(seed)
    models = {v: Model(v, VARIANTS[v]) for v in variants}
    keys = [(v, lab) for v in variants for lab, _ in levels]
    exps_of = dict(levels)
    jobs, owner = [], []
    for v, lab in keys:
        for q0 in starts(models[v], exps_of[lab], n_starts, rng):
            jobs.append(fit_job(models[v], exps_of[lab], q0, max_nfev))
            owner.append((v, lab))
    t0 = time.perf_counter()
    b = Batcher(steps)
    fits = b.run(jobs)
    t_full = time.perf_counter() - t0
    best: dict[tuple[str, str], FitResult] = {}
    all_costs: dict[tuple[str, str], list[float]] = {}
    for key, f in zip(owner, fits):
        all_costs.setdefault(key, []).append(f.cost)
        if key not in best or f.cost < best[key].cost:
            best[key] = f
    fold_jobs, fold_owner = [], []
    for v, lab in keys:
        ex = exps_of[lab]
        for j in folds(len(ex)):
            keep = [e for i, e in enumerate(ex) if i != j]
            fold_jobs.append(fit_job(models[v], keep, best[(v, lab)].q, fold_nfev))
            fold_owner.append((v, lab, j))
    t1 = time.perf_counter()
    fold_fits = Batcher(steps).run(fold_jobs)
    pred = Batcher(steps).run(
        [predict_job(models[v], exps_of[lab][j], f.q) for (v, lab, j), f in zip(fold_owner, fold_fits)]
    )
    t_folds = time.perf_counter() - t1
    out: dict[str, Any] = {
        "seconds_full_fits": t_full,
        "seconds_folds": t_folds,
        "batches": b.batches,
        "results": {},
    }
    for v, lab in keys:
        f = best[(v, lab)]
        ho = [p for (vv, ll, _), p in zip(fold_owner, pred) if (vv, ll) == (v, lab)]
        fold_q = [ff.q for (vv, ll, _), ff in zip(fold_owner, fold_fits) if (vv, ll) == (v, lab)]
        out["results"].setdefault(v, {})[lab] = {
            "held_out": ho,
            "in_sample": f.nrmse,
            "cost": f.cost,
            "start_costs": all_costs[(v, lab)],
            "nfev": f.nfev,
            "status": f.status,
            "at_bound": f.at_bound,
            "params": describe(models[v], f.q),
            "fold_params": [describe(models[v], q) for q in fold_q],
            "check": integration_check(models[v], f.q, exps_of[lab], steps),
        }
    return out


def main(argv: Optional[list[str]] = None) -> int:
    import mr_what_is_left as left

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None)
    ap.add_argument("--levels", default=None, help="coil currents, e.g. 0,0.5 (default: all five)")
    ap.add_argument("--variants", default="bw,series,spencer")
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=720, help="RK4 steps per period")
    ap.add_argument("--max-nfev", type=int, default=60)
    ap.add_argument("--fold-nfev", type=int, default=30)
    ap.add_argument("--n-min", type=float, default=BOUNDS["n"][0], help="lower bound of the exponent n")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if not 0.0 < args.n_min < BOUNDS["n"][1]:
        print(f"error: --n-min must be in (0, {BOUNDS['n'][1]})", file=sys.stderr)
        return 2
    BOUNDS["n"] = (args.n_min, BOUNDS["n"][1])
    data = args.data if args.data is not None else left._adapters().default_data_dir()
    t0 = time.perf_counter()
    lv = None if args.levels is None else [float(v) for v in args.levels.split(",")]
    loaded = left.load_levels(data, lv)
    floors = {lab: [left.floor_of(m)["floor"] for m in ms] for lab, ms in loaded}
    levels = [(lab, experiments(ms)) for lab, ms in loaded]
    res = run(
        levels, args.variants.split(","), args.starts, args.seed, args.steps, args.max_nfev, args.fold_nfev
    )
    res["floors"] = floors
    res["wall_seconds"] = time.perf_counter() - t0
    res["settings"] = vars(args) | {"data": str(data), "json": str(args.json)}
    report(res)
    if args.json is not None:
        args.json.write_text(json.dumps(res, indent=1, default=float))
    return 0


def _med(v: Sequence[float]) -> float:
    return float(np.median(v)) if len(v) else math.nan


def report(res: dict[str, Any]) -> None:
    print(
        "| variant | level | held-out median (max) | in-sample median (max) | floor median | starts' costs "
        "| integration: NRMSE change at 2N; periodicity |"
    )
    print("|---|---|---|---|---|---|---|")
    for v, per in res["results"].items():
        for lab, r in per.items():
            c = r["check"]
            print(
                f"| {v} | {lab} | {_med(r['held_out']):.3f} ({max(r['held_out']):.3f}) | "
                f"{_med(r['in_sample']):.3f} ({max(r['in_sample']):.3f}) | {_med(res['floors'][lab]):.4f} | "
                + ", ".join(f"{x:.3g}" for x in sorted(r["start_costs"]))
                + f" | {c['nrmse_change_2x_steps']:.1e}; {c['periodicity']:.0e} |"
            )
    keys = ["alpha", "beta", "gamma", "n", "c0", "c1", "k0", "k1", "f0", "z_s", "f_yield"]
    for v, per in res["results"].items():
        print(f"\n{v}: parameters (N, mm, s; A = 1)\n")
        print("| level | " + " | ".join(keys) + " | at a bound |")
        print("|---|" + "---|" * (len(keys) + 1))
        for lab, r in per.items():
            p = r["params"]
            print(
                f"| {lab} | "
                + " | ".join(f"{p[k]:.4g}" for k in keys)
                + f" | {', '.join(r['at_bound']) or '-'} |"
            )
    print(
        f"\n(wall {res['wall_seconds']:.0f} s: full fits {res['seconds_full_fits']:.0f} s, folds "
        f"{res['seconds_folds']:.0f} s)"
    )


if __name__ == "__main__":
    raise SystemExit(main())

"""A spike at the same phase of every period: a disturbance locked to the excitation (task spike43).

EMI from the drive, a switching transient or a glitch triggered by the encoder index puts a bump at the same
sample of every period. Averaging keeps it whole: the averaged period carries one sample (or a few) many
standard errors off every model, while :func:`.outliers.outlier_notes`, which compares each period with the
others, cannot see it (every period has it). Without a word the diagnosis read it as "unexplained structure
remains" at a spread of harmonics (spike43 probe: 20 se at one sample of every period of three recordings,
chi2/dof 4.2; 50 se, 20.3).

:func:`found` reads each experiment's residual ``r = ybar - model`` of the plain and of the final model, in
standard errors of the averaged period (``sqrt(spread_var / periods)``), and keeps a run of at most
:data:`MAX_RUN` adjacent samples (circular) that stands beyond the Bonferroni threshold of
:func:`.outliers.threshold` (over every sample of every experiment, at :data:`.outliers.OUTLIER_ALPHA`) in
both models, times the residual's own robust scale when it is above the noise (a broad misfit raises the
bar), while its :data:`SIDE` neighbours on each side lie on a straight line within half the threshold (rms)
and the peak stands beyond the bar above that line (a spike stands alone; a rough misfit is structure).

A sharp residual at a reversal of the input or of the latent ``x`` is physics (Coulomb friction's step,
play, the loop's corner), not interference: a run within :func:`reversal_window` samples of one is not
said; one at x's is, when a clear run stands at the same input phase in another experiment (:func:`found`).
With the raw periods of a Recording, the run must also stand in the median over the periods (at least half
its size in the mean): one period's spike moves the mean by 1/N of its size and not the median (that is
:func:`.outliers.outlier_notes`'s case), a locked one moves both.

:func:`bridged` replaces, in every period of the records, the run's samples by the straight line between
their neighbours, so the diagnosis can be read again without them (run.py says both verdicts).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .outliers import OUTLIER_ALPHA, threshold

FloatArray = NDArray[np.float64]

#: Longest run of adjacent samples read as one spike (a longer one is structure, not a glitch).
MAX_RUN = 3
#: Neighbours on each side of a run whose mean |residual| must stay below half the threshold.
SIDE = 4
#: A run's median-over-periods residual must be at least this share of its mean-over-periods one.
LOCKED_SHARE = 0.5


@dataclass(frozen=True)
class Spike:
    """A run of samples ``first .. last`` (0-based, of ``samples``) of experiment ``index``'s averaged period
    standing ``size`` se off every model (the smallest over the models, signed)."""

    index: int
    source: str
    first: int
    last: int
    samples: int
    size: float

    def note(self, limit: float) -> str:
        one = self.first == self.last
        where = f"sample {self.first} stands" if one else f"samples {self.first}..{self.last} stand"
        return (
            f"{self.source} (experiment {self.index + 1}): {where} "
            f"{abs(self.size):.3g} se off every model (beyond {limit:.2g} se, which Gaussian noise "
            f"passes once in the diagnosis with a chance of {OUTLIER_ALPHA:.0%}), alone and away from the "
            "reversals of u: a disturbance locked to the excitation? (a spike at the same phase of "
            "every period: the drive's EMI, a switching transient, a glitch triggered by the encoder)"
        )


def reversal_window(samples: int) -> int:
    """Samples either side of a reversal within which a sharp residual is read as physics."""
    return max(2, int(round(samples / 32)))


def _runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Maximal circular runs ``(first, length)`` of True in ``mask`` (none when it is all True)."""
    p = mask.size
    if mask.all() or not mask.any():
        return []
    start = int(np.argmin(mask))  # a False sample: no run wraps past it
    out, i = [], 0
    while i < p:
        j = (start + i) % p
        if mask[j]:
            n = 0
            while n < p and mask[(j + n) % p]:
                n += 1
            out.append((j, n))
            i += n
        else:
            i += 1
    return out


def _reversals(e: Any, phase: Optional[float]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Samples of the averaged grid at the reversals of the input (its slope changes sign), and of the latent
    ``x = A cos(2 pi j / P - phase)`` (none when the fit gives no phase)."""
    p = int(e.ybar.size)
    u = np.asarray(e.input(), dtype=np.float64)
    du = np.roll(u, -1) - u
    at_u = np.nonzero(np.sign(du) != np.sign(np.roll(du, 1)))[0].astype(np.int64)
    at_x: list[int] = []
    if phase is not None and math.isfinite(phase):
        j0 = phase * p / (2.0 * math.pi)
        at_x = [int(round(j0)) % p, int(round(j0 + p / 2.0)) % p]
    return at_u, np.asarray(at_x, dtype=np.int64)


def _input_phase(e: Any, j: int) -> float:
    """Sample ``j``'s phase of the input's cycle, as a fraction of the period."""
    p = int(e.ybar.size)
    return float(np.mod(j / p + float(e.grid_phase) / (2.0 * math.pi), 1.0))


def _same_phase(a: float, b: float, p: int) -> bool:
    return abs((a - b + 0.5) % 1.0 - 0.5) <= 1.5 / p


def _near(first: int, n: int, at: NDArray[np.int64], p: int, width: int) -> bool:
    for k in range(first, first + n):
        d = np.abs((at - k % p + p // 2) % p - p // 2)
        if d.size and int(d.min()) <= width:
            return True
    return False


def _median_residual(rows: Optional[FloatArray], model: FloatArray, first: int, n: int) -> Optional[float]:
    """The run's largest |median over periods - model|, or None without the raw periods."""
    if rows is None:
        return None
    cols = [(first + k) % model.size for k in range(n)]
    med = np.median(rows[:, cols], axis=0)
    return float(np.max(np.abs(med - model[cols])))


def _z(e: Any, out: Any) -> FloatArray:
    se = math.sqrt(max(float(e.spread_var), float(e.noise_var)) / float(e.periods))
    z: FloatArray = (np.asarray(e.ybar, dtype=np.float64) - np.asarray(out, dtype=np.float64)) / se
    return z


def found(d: Any, rows: Sequence[Optional[FloatArray]] = ()) -> tuple[list[Spike], float]:
    """The locked spikes of diagnosis ``d`` (at most one run per experiment: its largest), and the threshold
    in se. ``rows``: per experiment, its analysed raw periods (periods by samples) or None. A run near a
    reversal of ``x`` (not of u) is kept when a run away from every reversal stands at the same phase of the
    input in another experiment: G moves x's reversals from one frequency to another, not the disturbance."""
    exps = list(d.experiments)
    models = [m for m in (d.plain, d.final) if m is not None and len(m.outputs) == len(exps)]
    if (
        not exps
        or not models
        or any(np.asarray(o).size != e.ybar.size for m in models for e, o in zip(exps, m.outputs))
    ):
        return [], math.nan
    if not all(float(e.periods) > 0 and max(float(e.spread_var), float(e.noise_var)) > 0 for e in exps):
        return [], math.nan
    limit = threshold(sum(int(e.ybar.size) for e in exps))
    fit = getattr(d, "final_fit", None)
    phases = list(getattr(getattr(fit, "params", None), "phases", ())) if fit is not None else []
    clear: dict[int, Spike] = {}
    at_x: list[Spike] = []
    for i, e in enumerate(exps):
        raw = rows[i] if i < len(rows) else None
        for sp in _candidates(i, e, [m.outputs[i] for m in models], raw, limit):
            at_u, at_xs = _reversals(e, float(phases[i]) if i < len(phases) else None)
            n, w = (sp.last - sp.first) % sp.samples + 1, reversal_window(sp.samples)
            if _near(sp.first, n, at_u, sp.samples, w):
                continue
            if _near(sp.first, n, at_xs, sp.samples, w):
                at_x.append(sp)
            elif i not in clear or abs(sp.size) > abs(clear[i].size):
                clear[i] = sp
    for sp in at_x:
        ph = _input_phase(exps[sp.index], sp.first)
        seen = any(_same_phase(ph, _input_phase(exps[c.index], c.first), sp.samples) for c in clear.values())
        if sp.index not in clear and seen:
            clear[sp.index] = sp
    return [clear[i] for i in sorted(clear)], limit


def _alone(z: FloatArray, first: int, n: int, peak: float, limit: float, bar: float) -> bool:
    """Whether a run stands alone: its :data:`SIDE` neighbours each side lie on a straight line within half
    the threshold (rms; a smooth misfit may carry the run, a rough one is structure: the real friction
    damper's residual peaks 20-40 se among neighbours of 15-30), and the peak stands above that line beyond
    ``bar``."""
    p = z.size
    offs = np.array(
        [-k for k in range(SIDE, 0, -1)] + [n - 1 + k for k in range(1, SIDE + 1)], dtype=np.float64
    )
    side = z[(first + offs.astype(np.int64)) % p]
    coef = np.polyfit(offs, side, 1)
    off = float(np.sqrt(np.mean((side - np.polyval(coef, offs)) ** 2)))
    j = float(np.argmax(np.abs(z[[(first + k) % p for k in range(n)]])))
    return off < 0.5 * limit and abs(peak - float(np.polyval(coef, j))) > bar


def _candidates(i: int, e: Any, outs: Sequence[Any], raw: Optional[FloatArray], limit: float) -> list[Spike]:
    """Experiment ``i``'s narrow runs beyond the threshold in every model (``outs``), alone, and standing in
    the median over the periods when ``raw`` gives them."""
    zs = np.array([_z(e, o) for o in outs])
    z = zs[np.argmin(np.abs(zs), axis=0), np.arange(zs.shape[1])]  # the smallest over the models
    p = z.size
    bar = limit * max(1.0, 1.4826 * float(np.median(np.abs(z))))  # a broad misfit raises the bar
    model = np.asarray(outs[-1], dtype=np.float64)
    out = []
    for first, n in _runs(np.abs(z) > bar):
        if n > MAX_RUN:
            continue
        run = [(first + k) % p for k in range(n)]
        top = run[int(np.argmax(np.abs(z[run])))]
        if not _alone(z, first, n, float(z[top]), limit, bar):
            continue
        med = _median_residual(raw, model, first, n)
        if med is not None and med < LOCKED_SHARE * abs(float(e.ybar[top]) - float(model[top])):
            continue  # one period's spike: outlier_notes says it
        out.append(Spike(i, str(e.source), first, (first + n - 1) % p, p, float(z[top])))
    return out


def matched(items: Sequence[Any], d: Any) -> list[Optional[int]]:
    """Per experiment of ``d``, the index in ``items`` of the Recording whose last ``periods`` whole periods
    average to its ``ybar`` (the analysed ones), else None."""
    out: list[Optional[int]] = []
    for e in d.experiments:
        out.append(next((k for k, it in enumerate(items) if _rows(it, e) is not None), None))
    return out


def _rows(it: Any, e: Any) -> Optional[FloatArray]:
    from ..model import Recording

    if not isinstance(it, Recording):
        return None
    p, n, whole = int(it.samples_per_period), int(round(float(e.periods))), int(it.whole_periods)
    if p != e.ybar.size or n < 3 or whole < n:
        return None
    rows = np.asarray(it.y[(whole - n) * p : whole * p], dtype=np.float64).reshape(n, p)
    tol = 1e-9 * float(np.max(np.abs(e.ybar)))
    return rows if np.allclose(rows.mean(axis=0), e.ybar, rtol=1e-9, atol=tol) else None


def analysed_rows(items: Sequence[Any], d: Any) -> list[Optional[FloatArray]]:
    """Per experiment of ``d``, its analysed raw periods (periods by samples) from ``items``, else None."""
    return [None if k is None else _rows(items[k], e) for k, e in zip(matched(items, d), d.experiments)]


def bridged(items: Sequence[Any], d: Any, spikes: Sequence[Spike]) -> Optional[list[Any]]:
    """``items`` with each spike's samples, in every period of its Recording, on the straight line between
    their neighbours; None when a spike's experiment has no Recording among ``items``."""

    out = list(items)
    where = matched(items, d)
    for s in spikes:
        k = where[s.index]
        if k is None:
            return None
        rec = out[k]
        y = np.array(rec.y, dtype=np.float64)
        p, n = s.samples, (s.last - s.first) % s.samples + 1
        for start in range(0, y.size, p):
            idx = [start + s.first + m for m in range(n)]  # a run across the period's end goes on
            lo, hi = idx[0] - 1, idx[-1] + 1
            if any(j >= y.size for j in idx):
                continue
            if lo < 0 or hi >= y.size:
                ends = [j for j in (lo, hi) if 0 <= j < y.size]
                y[idx] = float(np.mean(y[ends]))
                continue
            frac = (np.arange(1, n + 1)) / (n + 1.0)
            y[idx] = y[lo] + frac * (y[hi] - y[lo])
        out[k] = replace(rec, y=y)
    return out


__all__ = [
    "Spike",
    "found",
    "analysed_rows",
    "matched",
    "bridged",
    "reversal_window",
    "MAX_RUN",
    "SIDE",
    "LOCKED_SHARE",
]

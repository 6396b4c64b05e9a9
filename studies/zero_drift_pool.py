"""The pooled decay test of ``diagnosis.zero_drift``: the capped pool (as before and again after the review of
session 30) against the rules tried to leave a slowing minority out, on records written here.

The zero-drift test calls a drift only when, over the recordings whose period means trend, the first halves
are not steeper than the last (Stouffer's pooled z at ``DECAY_LEVEL``), each z capped at the slowing bound
(``capped``, ``zero_drift._pooled``). Session 30 left a minority of slowing ones (beyond the bound) out of
the pool (``minority``); the review found that it called settling sets a drift, and ``rest10``/``rest20``
drop the minority only when the others show no hint of decay (their pool's p at least 0.10 / 0.20), else
pool all, capped. Each rule is computed on the same per-recording numbers and ``detect`` run under it.

Records: 8 Recordings (64 samples a period, 4 settling + 24 periods) of ``tanh(2 cos(wt - 0.4))``, white or
AR(1) (phi 0.7) noise of sd 0.01; a straight line of LINE noise sd over each record (its sign per
recording) and, in the first SLOW recordings, a transient of SIZE sd decaying over a quarter of the record
(the direction that makes its first half steeper). ``--settle SIZE2 TAU``: the review's settling set (no
line; the first SLOW recordings settle fast at SIZE sd over a quarter of the record, the others slowly at
SIZE2 sd over TAU records).

Usage: ``python studies/zero_drift_pool.py --line 3 --slow 0 --draws 400`` (the decay test's null: a drift
that goes on) or ``--line 1 --slow 2 --size 3`` (a slowing minority) or ``--line 0 --slow 8 --size 1.5``
(a settling set: power) or ``--line 0 --slow 2 --size 3 --settle 5 2`` (the review's settling set);
``--ar 0.7`` for AR(1) noise.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import zero_drift as Z
from scipy.special import chdtrc, ndtr, ndtri

TWO_PI = 2.0 * math.pi
SD = 0.01


def _stouffer(p: np.ndarray, cap: float) -> float:
    z = np.minimum(ndtri(1.0 - np.clip(p, 1e-300, 1.0 - 1e-16)), cap)
    return float(ndtr(-float(np.sum(z)) / math.sqrt(p.size)))


def rule(rest_level: float) -> Any:
    """The pool leaving a slowing minority out when the others' pool has p at least ``rest_level`` (0:
    always, session 30's rule; above 1: never, the capped pool)."""

    def pool(decays: Sequence[float]) -> float:
        if not decays:
            return math.nan
        p = np.asarray(decays, dtype=np.float64)
        cap = float(ndtri(1.0 - Z.SLOWING_LEVEL / p.size))
        every = _stouffer(p, cap)
        slow = p < Z.SLOWING_LEVEL / p.size  # as detect() marks them
        if 0 < 2 * int(slow.sum()) < p.size:
            rest = _stouffer(p[~slow], cap)
            return rest if rest >= rest_level else every
        return every

    return pool


RULES = {"capped": rule(2.0), "minority": rule(0.0), "rest10": rule(0.10), "rest20": rule(0.20)}


def records(
    seed: int, line: float, slow: int, size: float, ar: float, settle: Sequence[float] = ()
) -> list[Any]:
    from scipy.signal import lfilter

    rng = np.random.default_rng([seed, 3030])
    p, n = 64, 28 * 64
    out = []
    for i in range(8):
        om = TWO_PI * (0.5 + 0.25 * i)
        t = np.arange(n) * (TWO_PI / om / p)
        y = np.tanh(2.0 * np.cos(om * t - 0.4))
        e = lfilter([1.0], [1.0, -ar], rng.normal(0.0, SD * math.sqrt(1.0 - ar**2), n))
        sign = float(rng.choice([-1.0, 1.0]))
        e = e + sign * line * SD * np.linspace(0.0, 1.0, n)
        if i < slow:
            e = e - (sign if line else 1.0) * size * SD * np.exp(-np.arange(n) / (n / 4.0))
        elif settle:
            e = e - settle[0] * SD * np.exp(-np.arange(n) / (n * settle[1]))
        out.append(bw.Recording(t, np.cos(om * t), y + e, 1.0, om, settle_periods=4))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--line", type=float, default=3.0)
    ap.add_argument("--slow", type=int, default=0)
    ap.add_argument("--size", type=float, default=3.0)
    ap.add_argument("--ar", type=float, default=0.0)
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--settle", type=float, nargs=2, default=())
    a = ap.parse_args()
    capped = Z._pooled
    counts = {k: [0, 0] for k in RULES}
    for seed in range(a.draws):
        items = records(seed, a.line, a.slow, a.size, a.ar, a.settle)
        nums = [Z._numbers(r) for r in items]
        dec = [g[1] for g in nums if isinstance(g, tuple) and float(chdtrc(1, g[0])) < Z.OWN_LEVEL]
        for k, pool in RULES.items():
            counts[k][0] += bool(pool(dec) < Z.DECAY_LEVEL)
            Z._pooled = pool
            try:
                counts[k][1] += Z.detect(items, 0.05 / 20) is not None
            finally:
                Z._pooled = capped
    for k, (rej, found) in counts.items():
        print(f"{k}: {a.draws} draws, decay test p < {Z.DECAY_LEVEL} in {rej}, drift called in {found}")


if __name__ == "__main__":
    main()

"""The pooled decay test of ``diagnosis.zero_drift`` before and after session 30, on records written here.

The zero-drift test calls a drift only when, over the recordings whose period means trend, the first halves
are not steeper than the last (Stouffer's pooled z at ``DECAY_LEVEL``). Before session 30 every trending
recording entered the pool, each z capped at the slowing bound; now a minority of slowing ones (beyond the
bound, which the drift must stand without anyway) is left out. Both pools are computed here on the same
per-recording numbers (``zero_drift._numbers``), and ``detect`` is run under each.

Records: 8 Recordings (64 samples a period, 4 settling + 24 periods) of ``tanh(2 cos(wt - 0.4))``, white or
AR(1) (phi 0.7) noise of sd 0.01; a straight line of LINE noise sd over each record (its sign per
recording) and, in the first SLOW recordings, a transient of SIZE sd decaying over a quarter of the record
(the direction that makes its first half steeper).

Usage: ``python studies/zero_drift_pool.py --line 3 --slow 0 --draws 400`` (the decay test's null: a drift
that goes on) or ``--line 1 --slow 2 --size 3`` (a slowing minority) or ``--line 0 --slow 8 --size 1.5``
(a settling set: power); ``--ar 0.7`` for AR(1) noise.
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


def old_pool(decays: Sequence[float], slow: Sequence[bool] = ()) -> float:
    """The pool before session 30: every trending recording, each z capped at the slowing bound."""
    if not decays:
        return math.nan
    z = ndtri(1.0 - np.clip(np.asarray(decays, dtype=np.float64), 1e-300, 1.0 - 1e-16))
    z = np.minimum(z, float(ndtri(1.0 - Z.SLOWING_LEVEL / len(decays))))
    return float(ndtr(-float(np.sum(z)) / math.sqrt(len(decays))))


def records(seed: int, line: float, slow: int, size: float, ar: float) -> list[Any]:
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
        out.append(bw.Recording(t, np.cos(om * t), y + e, 1.0, om, settle_periods=4))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--line", type=float, default=3.0)
    ap.add_argument("--slow", type=int, default=0)
    ap.add_argument("--size", type=float, default=3.0)
    ap.add_argument("--ar", type=float, default=0.0)
    ap.add_argument("--draws", type=int, default=400)
    a = ap.parse_args()
    new = Z._pooled
    counts = {"before": [0, 0], "after": [0, 0]}
    for seed in range(a.draws):
        items = records(seed, a.line, a.slow, a.size, a.ar)
        nums = [Z._numbers(r) for r in items]
        dec = {j: g[1] for j, g in enumerate(nums) if g and float(chdtrc(1, g[0])) < Z.OWN_LEVEL}
        slowing = [j for j, d in dec.items() if d < Z.SLOWING_LEVEL / len(dec)] if dec else []
        for k, pool in (("before", old_pool), ("after", new)):
            p = pool(list(dec.values()), [j in slowing for j in dec]) if dec else math.nan
            counts[k][0] += bool(p < Z.DECAY_LEVEL)
            Z._pooled = pool  # type: ignore[assignment]
            try:
                counts[k][1] += Z.detect(items, 0.05 / 20) is not None
            finally:
                Z._pooled = new
    for k, (rej, found) in counts.items():
        print(f"{k}: {a.draws} draws, decay test p < {Z.DECAY_LEVEL} in {rej}, drift called in {found}")


if __name__ == "__main__":
    main()

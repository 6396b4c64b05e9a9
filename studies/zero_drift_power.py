"""How often ``diagnosis.zero_drift.detect`` calls a drift, on records written down directly (no simulator).

Two builders, each with its own NumPy loop and noise:

* ``lab``: 8 fixed-rate Measurements at 97.3 samples per period (no whole number), a first-order lag with a
  delay ahead of a saturating loop, white or AR(1) (phi 0.7) noise of sd 0.01, 30 periods, and either a
  straight drift of SIZE noise sd over each record ("drift") or a transient of SIZE sd whose time constant is
  the record's length ("slow"), its sign per measurement;
* ``rec``: 6 Recordings (128 samples per period, 4 settling + 16 periods), ``tanh(2 cos(wt - 0.4))``, white
  noise sd 0.01, a "slow" transient of SIZE sd (time constant the record's length) in every recording
  ("all") or in the first only ("one").

Usage: ``python studies/zero_drift_power.py lab drift white 1 --seeds 200`` or
``python studies/zero_drift_power.py rec all - 3 --seeds 300``; prints how many seeds were called a drift.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import zero_drift

TWO_PI = 2.0 * math.pi
SD = 0.01


def lab(kind: str, seed: int, noise: str, size: float) -> list[Any]:
    from scipy.signal import lfilter

    rng = np.random.default_rng([seed, 31])
    n, spp = int(30 * 97.3), 97.3
    out = []
    for i in range(8):
        om = TWO_PI * (0.4 + 0.3 * i)
        t = np.arange(n) * (TWO_PI / om / spp)
        u = (1.0 + 0.1 * i) * np.cos(om * t) + rng.normal(0.0, 1e-4, n)
        ph = math.atan(om / 2.0) + 0.05 * om
        y = 0.8 * np.tanh(2.5 * np.cos(om * t - ph)) + 0.1 * np.cos(om * t - ph)
        if noise == "white":
            e = rng.normal(0.0, SD, n)
        else:
            e = lfilter([1.0], [1.0, -0.7], rng.normal(0.0, SD * math.sqrt(1.0 - 0.49), n))
        s = float(rng.choice([-1.0, 1.0]))
        if kind == "drift":
            e = e + s * size * SD * np.linspace(0.0, 1.0, n)
        else:
            e = e + s * size * SD * np.exp(-np.arange(n) / n)
        out.append(bw.Measurement(t, u, y + e, nominal_frequency=om, name=f"m{i}"))
    return out


def rec(which: str, seed: int, size: float) -> list[Any]:
    rng = np.random.default_rng([seed, 33])
    p, settle, periods = 128, 4, 16
    n = (settle + periods) * p
    out = []
    for i in range(6):
        om = TWO_PI * (0.5 + 0.25 * i)
        t = np.arange(n) * (TWO_PI / om / p)
        u = (1.0 + 0.2 * i) * np.cos(om * t)
        y = np.tanh(2.0 * np.cos(om * t - 0.4)) + rng.normal(0.0, SD, n)
        s = float(rng.choice([-1.0, 1.0]))
        if which == "all" or i == 0:
            y = y + s * size * SD * np.exp(-np.arange(n) / n)
        out.append(bw.Recording(t, u, y, 1.0 + 0.2 * i, om, settle_periods=settle))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("path", choices=["lab", "rec"])
    ap.add_argument("kind", help="lab: drift or slow; rec: all or one")
    ap.add_argument("noise", help="lab: white or ar1; rec: ignored (-)")
    ap.add_argument("size", type=float, help="noise sd")
    ap.add_argument("--seeds", type=int, default=100)
    args = ap.parse_args()
    hits = 0
    for seed in range(args.seeds):
        items = (
            lab(args.kind, seed, args.noise, args.size)
            if args.path == "lab"
            else rec(args.kind, seed, args.size)
        )
        hits += zero_drift.detect(items, 0.05 / 20) is not None
    print(f"{args.path} {args.kind} {args.noise} size {args.size}: called a drift in {hits}/{args.seeds}")


if __name__ == "__main__":
    main()

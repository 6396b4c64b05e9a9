"""A real output offset, a real asymmetry, and nulls under pink (1/f) noise: what each diagnosis names
(studies/pinkoff46/README.md; the offset and the null are studies/pink46/offset46.py's cases).

    PYTHONPATH=python python studies/pinkoff46/pinkoff46.py KIND FIRST LAST

KIND: ``offset`` (10 noise sd / sqrt(periods)), ``asymmetry`` (delta set so the steady loops move by 10 noise
sd / sqrt(periods) RMS, the bench's size unit), ``null``, or ``white-offset`` / ``white-asymmetry`` /
``white-null`` (the same with white noise of the same sd). Plant: tests/test_dc_only_words.py's plain_plant,
simulated noise-free by bw.simulate (with the asymmetry term when asked); noise from
``np.random.default_rng([46, seed])``. One JSON line per seed and a tally.
"""

from __future__ import annotations

import json
import math
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import bouc_wen_id as bw
import numpy as np

sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
from pink_noise import sum_of_ar1  # noqa: E402
from test_dc_only_words import PERIODS, plain_plant  # noqa: E402

STEADY = slice(15 * 100, None)


def asymmetric(size: float) -> list[bw.Recording]:
    """plain_plant with an asymmetry whose steady loops differ from the plain ones by ``size`` noise sd /
    sqrt(periods) RMS over all recordings (delta by bisection)."""
    plain = plain_plant()
    sd = 0.01 * float(np.max(np.abs(plain[0].y)))

    def recs(delta: float) -> list[bw.Recording]:
        return plain_plant((bw.terms.Asymmetry(delta),))

    def moved(delta: float) -> float:
        d = np.concatenate([(a.y - b.y)[STEADY] for a, b in zip(recs(delta), plain)])
        return float(np.sqrt(np.mean(d**2))) / (sd / math.sqrt(PERIODS))

    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if moved(mid) < size else (lo, mid)
    print(f"# asymmetry delta = {0.5 * (lo + hi):.4g} for {size:g}x", flush=True)
    return recs(0.5 * (lo + hi))


def one(recs: list[bw.Recording], seed: int, offset_sds: float, pink: bool) -> dict[str, object]:
    sd = 0.01 * float(np.max(np.abs(recs[0].y)))
    rng = np.random.default_rng([46, seed])
    off = offset_sds * sd / math.sqrt(PERIODS)

    def noise(n: int) -> np.ndarray:
        return sd * (sum_of_ar1(n, rng) if pink else rng.standard_normal(n))

    noisy = [replace(r, y=r.y + noise(r.y.size) + off) for r in recs]
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(noisy)
    return {
        "seed": seed,
        "status": d.status,
        "named": [t.term for t in d.named],
        "partial": [t.term for t in d.partial],
        "alternatives": sorted({a.rival for a in d.alternatives}),
        "cpu": round(time.process_time() - t0, 1),
        "verdict": d.verdict[:240],
    }


def main(argv: list[str]) -> None:
    kind, first, last = argv[0], int(argv[1]), int(argv[2])
    pink = not kind.startswith("white-")
    what = kind.removeprefix("white-")
    recs = asymmetric(10.0) if what == "asymmetry" else plain_plant()
    rows = []
    for seed in range(first, last):
        row = one(recs, seed, 10.0 if what == "offset" else 0.0, pink)
        rows.append(row)
        print(json.dumps(row), flush=True)
    tally: dict[str, int] = {}
    for r in rows:
        key = "+".join(r["named"]) or r["status"]  # type: ignore[arg-type]
        alt = r["alternatives"]
        key += f" (alternatives {'/'.join(alt)})" if alt else ""  # type: ignore[arg-type]
        tally[key] = tally.get(key, 0) + 1
    print(f"# {kind}, {len(rows)} seeds: {tally}")


if __name__ == "__main__":
    main(sys.argv[1:])

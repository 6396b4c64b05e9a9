"""Pink (1/f) nulls: how often a diagnosis names an output offset, says "at the DC only", warns of a
transient; and the power on a real offset of 10x under the same noise (studies/pink45/README.md, left open).

    PYTHONPATH=python python studies/pink46/offset46.py [FIRST LAST] [--offset]

The plant of tests/test_dc_only_words.py (second-order G, Bouc-Wen 1.2, 0.4, mu 2.5; 8 frequencies 1-8 rad/s,
15 settling + 8 analysed periods of 100 samples), simulated noise-free by bw.simulate, then pink noise
(tests/pink_noise.py's sum of 12 AR(1)s, 1 % of the output's peak) from ``np.random.default_rng([46, seed])``,
plus ``--offset``: an output offset of 10 noise sd / sqrt(periods) (the review's size unit). One line per seed
(status, named, whether the verdict says "at the DC only", TransientWarnings, CPU seconds) and a tally.
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


def one(recs: list[bw.Recording], seed: int, offset_sds: float) -> dict[str, object]:
    sd = 0.01 * float(np.max(np.abs(recs[0].y)))
    rng = np.random.default_rng([46, seed])
    off = offset_sds * sd / math.sqrt(PERIODS)
    noisy = [replace(r, y=r.y + sd * sum_of_ar1(r.y.size, rng) + off) for r in recs]
    t0 = time.process_time()
    with warnings.catch_warnings(record=True) as wl:
        warnings.simplefilter("always")
        d = bw.diagnose(noisy)
    transient = sum(issubclass(w.category, bw.errors.TransientWarning) for w in wl)
    return {
        "seed": seed,
        "offset": off,
        "status": d.status,
        "named": [t.term for t in d.named],
        "dc_only": "at the DC only" in d.verdict,
        "transient": transient,
        "cpu": round(time.process_time() - t0, 1),
        "verdict": d.verdict[:160],
    }


def main(argv: list[str]) -> None:
    nums = [int(a) for a in argv if not a.startswith("--")]
    first, last = (nums[0], nums[1]) if len(nums) == 2 else (100, 130)
    offset_sds = 10.0 if "--offset" in argv else 0.0
    recs = plain_plant()
    rows = []
    for seed in range(first, last):
        row = one(recs, seed, offset_sds)
        rows.append(row)
        print(json.dumps(row), flush=True)
    n = len(rows)
    named = sum("offset" in r["named"] for r in rows)  # type: ignore[operator]
    adequate = sum(r["status"] == "adequate" for r in rows)
    dc_only = sum(bool(r["dc_only"]) for r in rows)
    warned = sum(int(r["transient"]) > 0 for r in rows)  # type: ignore[call-overload]
    print(
        f"# {n} seeds, offset {offset_sds:g}x: offset named {named}, adequate {adequate}, 'at the DC only' "
        f"{dc_only}, a TransientWarning in {warned}"
    )


if __name__ == "__main__":
    main(sys.argv[1:])

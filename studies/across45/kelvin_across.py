"""Review 43's d2f (a Kelvin element on x through a first-order G with a 3 ms delay, AR(1) noise) at two
levels, diagnosed across them: where does the joint structure put the spring and the dashpot? (session 45,
across45)

Run: PYTHONPATH=python:tests python studies/across45/kelvin_across.py [seed ...]
"""

from __future__ import annotations

import sys
import time
import warnings

import bouc_wen_id as bw
from test_place_tie import C, K, _records

if __name__ == "__main__":
    for seed in [int(a) for a in sys.argv[1:]] or [1]:
        levels = [_records(K, C, seed, 0.5), _records(1.5 * K, 1.5 * C, seed + 100, 0.5)]
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = bw.diagnose_across(levels, [1.0, 1.5])
        print(f"seed {seed}: {a.status}: named {a.named}; cpu {time.process_time() - t0:.0f} s")
        print("  ", a.verdict[:600])

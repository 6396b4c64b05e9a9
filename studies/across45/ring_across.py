"""Review 44's design D (a resonant G, zeta 0.05, from rest, 10 settle and 4 averaged periods, AR(1) 0.9) at
two drive levels, and a null set of settled levels (resonant G zeta 0.3 at 5 rad/s with an 8 ms delay, AR(1)
0.5, 20 settle periods), diagnosed across the levels (session 45, across45).

Run: PYTHONPATH=python:tests python studies/across45/ring_across.py ring|null seed ...
"""

from __future__ import annotations

import sys
import time

from test_across_checks import across_quietly, levels

if __name__ == "__main__":
    kind, seeds = sys.argv[1], [int(a) for a in sys.argv[2:]]
    for seed in seeds:
        if kind == "ring":
            groups = levels(6.0, 0.05, 0.003, 10, 4, 0.9, seed, [1.0, 1.5])
        else:
            groups = levels(5.0, 0.3, 0.008, 20, 8, 0.5, seed, [1.0, 1.5])
        t0 = time.process_time()
        a = across_quietly(groups, [1.0, 1.5])
        print(f"{kind} seed {seed}: {a.status}: named {a.named}; cpu {time.process_time() - t0:.0f} s")
        print("   ", a.verdict[:700])

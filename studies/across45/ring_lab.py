"""Review 44's design D as lab Measurements (the same samples, no settle periods given): does diagnose see
the ring-down on the lab path? (session 45, across45)

Run: PYTHONPATH=python:tests python studies/across45/ring_lab.py periods seed ...
"""

from __future__ import annotations

import sys
import time
import warnings

import bouc_wen_id as bw
from test_across_checks import levels

ZETA = float(sys.argv[3]) if len(sys.argv) > 3 else 0.05


def measurements(seed: int, periods: int) -> list[bw.Measurement]:
    recs = levels(6.0, ZETA, 0.003, 0, periods, 0.9, seed, [1.0])[0]
    return [
        bw.Measurement(r.t, r.u, r.y, nominal_frequency=r.frequency, name=f"m{i}") for i, r in enumerate(recs)
    ]


if __name__ == "__main__":
    periods = int(sys.argv[1])
    for seed in [int(sys.argv[2])]:
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(measurements(seed, periods))
        print(
            f"lab seed {seed}: {d.status}: named {[n.term for n in d.named]}; "
            f"cpu {time.process_time() - t0:.0f} s"
        )
        print("   ", d.verdict[:500])
        print("    notes:", [n[:160] for n in d.notes if "ring" in n][:3])

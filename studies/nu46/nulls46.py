"""Session 46 (nu46): plain nulls of review 44 (no effect; sim44.recordings, the config's own noise) under
the full diagnosis: the status, the terms named, and the drift test's p (run with PYTHONPATH at the code to
measure).

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu46/nulls46.py CFG FIRST LAST
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent.parent / "review44"))
import bouc_wen_id as bw  # noqa: E402
import drive44 as dr  # noqa: E402
import sim44 as s  # noqa: E402


def main(argv: list[str]) -> None:
    cfg, first, last = argv[0], int(argv[1]), int(argv[2])
    p, d, _, _ = dr.build("null", 0.0, cfg)
    nz = dr.NOISES[dr.CONFIGS[cfg][2]]
    for seed in range(first, last):
        recs = s.recordings(p, d, nz, seed)
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = bw.diagnose(recs)
        deg = dg.degradation
        row = {
            "case": f"null-0-{cfg}-{seed}",
            "status": dg.status,
            "named": [n.term for n in dg.named],
            "final_p": dg.final.p_value,
            "drift_p": getattr(deg, "p_adjusted", None),
            "drift_gate_p": getattr(deg, "drift_p_value", None),
            "cpu": round(time.process_time() - t0, 1),
        }
        print(json.dumps(row, default=str), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])

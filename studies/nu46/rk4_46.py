"""Session 46 (nu46): strength degradation named on tests/degradation_sim.py's RK4 (not the library's
simulator): value / truth, z, the status (run with PYTHONPATH at the code to measure).

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu46/rk4_46.py 0.005 1,2,3
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent.parent.parent / "tests"))
import bouc_wen_id as bw  # noqa: E402
from degradation_sim import records  # noqa: E402


def main(argv: list[str]) -> None:
    truth = float(argv[0])
    for seed in (int(x) for x in argv[1].split(",")):
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(records(0.01, seed, delta_nu=truth), candidates=["degradation"])
        n = [t for t in d.named if t.term == "degradation"]
        v, se = (n[0].value, n[0].standard_error) if n else (float("nan"), float("nan"))
        row = {"truth": truth, "seed": seed, "ratio": v / truth, "z": (v - truth) / se, "status": d.status}
        row["cpu"] = round(time.process_time() - t0, 1)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])

"""Review 46's G null (50 Hz hum, 2 and 8 rad/s, P = 1000) diagnosed from Recordings, per seed.

PYTHONPATH=python python studies/hum46/seeds.py [FIRST LAST]
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import bouc_wen_id as bw  # noqa: E402
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402


def main(first: int, last: int) -> None:
    sy, pl, nn = dv.base("G")
    runs = s.simulate(sy, pl)
    for seed in range(first, last + 1):
        recs = s.recordings(runs, pl, nn, dv.SD, seed)
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = bw.diagnose(recs)
        said = any("not locked to the input" in x for x in dg.notes)
        row = {"seed": seed, "status": dg.status, "plain_p": dg.plain.p_value, "hum_said": said}
        print(json.dumps({**row, "cpu": round(time.process_time() - t0, 1)}), flush=True)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3])) if len(sys.argv) > 2 else main(1, 6)

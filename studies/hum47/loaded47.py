"""Review 46's G null (50 Hz hum) through ``bw.load`` (CSV files, as the command line reads them) and as
Recordings of the same samples, per seed: status, plain p, whether the hum is said, noise floor.

    PYTHONPATH=python python studies/hum47/loaded47.py [FIRST LAST] [CONFIG]
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import bouc_wen_id as bw  # noqa: E402
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402


def _row(how: str, seed: int, items: object) -> dict[str, object]:
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = bw.diagnose(items)
    said = [x.split(" (p =")[0][-60:] for x in dg.notes if "not locked to the input" in x]
    floor = [float(f"{e.noise_var:.3g}") for e in dg.experiments] if hasattr(dg, "experiments") else []
    out = {"how": how, "seed": seed, "status": dg.status, "plain_p": dg.plain.p_value, "hum_said": bool(said)}
    return {**out, "noise_var": floor, "cpu": round(time.process_time() - t0, 1)}


def main(first: int, last: int, cfg: str) -> None:
    sy, pl, nn = dv.base(cfg)
    runs = s.simulate(sy, pl)
    for seed in range(first, last + 1):
        recs = s.recordings(runs, pl, nn, dv.SD, seed)
        with tempfile.TemporaryDirectory() as d:
            dv.write_csv(recs, d)
            print(json.dumps(_row("bw.load", seed, bw.load(d))), flush=True)
        print(json.dumps(_row("Recordings", seed, recs)), flush=True)


if __name__ == "__main__":
    a = sys.argv[1:]
    main(int(a[0]) if a else 1, int(a[1]) if len(a) > 1 else 4, a[2] if len(a) > 2 else "G")

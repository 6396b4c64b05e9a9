"""An effect under design C's wander, on the seeds whose wander the DC-only test takes (wander47 README).

    PYTHONPATH=python python studies/wander47/power47.py OUT.jsonl EFFECT SIZE SEED [SEED ...]

EFFECT is one of drive45's (``viscous``: viscous damping on u, ``delta``: asymmetry), SIZE its size in
drive45's units (10: the RMS change ten times the averaged noise sd), the seeds sim45's noise seeds (101 106
107 108 112 119 123 125 126 128 took the DC-only wander path in studies/wander46). Default candidates. One
JSON line per seed: the status, the named terms, the effect's own detection limit (50 % and 90 % power), its
fitted value and se at the first step, the truth, and the experiments' noise_var over the true sd^2.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402


def main(argv: list[str]) -> None:
    import bouc_wen_id as bw

    out, eff, size = Path(argv[1]), argv[2], float(argv[3])
    runs, d, nz, truth, got = dv.build(eff, size, "C")
    term = dv.TRUTH_TERM[eff]
    for seed in (int(a) for a in argv[4:]):
        recs = s.recordings(runs, d, nz, seed)
        c0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = bw.diagnose(recs)
        cpu = time.process_time() - c0
        lims = [lim for lim in dg.limits if lim.term == term]
        rec = {"effect": eff, "size": got, "seed": seed, "status": dg.status, "truth": truth, "cpu": cpu}
        rec["named"] = [[n.term, n.value, n.standard_error] for n in dg.named]
        rec["limit"] = [[lim.limit, lim.limit_90, lim.value, lim.standard_error] for lim in lims[:1]]
        rec["var_ratio"] = [e.noise_var / dv.SD**2 for e in dg.experiments]
        rec["headline"] = dg.headline[:160]
        with out.open("a") as f:
            f.write(json.dumps(rec) + "\n")
        print(eff, seed, dg.status, rec["named"], rec["limit"], flush=True)


if __name__ == "__main__":
    main(sys.argv)

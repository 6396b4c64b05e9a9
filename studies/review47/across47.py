"""Review 47: ``bw.diagnose_across`` on three levels of a condition made by sim47 (config J's G and element).

    PYTHONPATH=python python studies/review47/across47.py kelvin|null [SEED] >> across47.jsonl

Three groups (a condition c = 0, 1, 2, e.g. a coil current), each 4 frequencies at one amplitude, white noise
sd 0.01 w_u. ``kelvin``: stiffness@x and viscous@x with k = k0 (1 + 0.5 c), c_x = c0 (1 + c), k0 and c0 each
about 15x on their own at c = 0; ``null``: none. Prints one JSON line: the verdict, named values, the truth.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
import drive47 as dv  # noqa: E402
import sim47 as s  # noqa: E402

PLAN = s.Plan((1.5, 3.0, 6.0, 10.0), (1.0,) * 4, 8, (20,) * 4, (160.0,) * 4)


def main(kind: str, seed: int) -> None:
    import bouc_wen_id as bw

    sy, _, _ = dv.base("J")
    k = 2.5 * sy.el.w_u / float(sorted(abs(sy.g.at(w)) for w in PLAN.omegas)[2])
    pl = replace(PLAN, amps=tuple(k * a for a in PLAN.amps))
    sd = dv.SD * sy.el.w_u
    plain = s.simulate(sy, pl)
    unit = {
        t: dv.size(s.simulate(s.with_effect(sy, t, 1e-3), pl), plain, pl, sd)
        for t in ("stiffness@x", "viscous@x")
    }
    groups, truths = [], []
    for c in (0.0, 1.0, 2.0):
        truth = (
            {}
            if kind == "null"
            else {
                "stiffness@x": 1e-3 * 15.0 / unit["stiffness@x"] * (1 + 0.5 * c),
                "viscous@x": 1e-3 * 15.0 / unit["viscous@x"] * (1 + c),
            }
        )
        runs = s.simulate(replace(sy, terms=tuple(truth.items())), pl)
        groups.append(s.recordings(runs, pl, "white", sd, 100 * seed + int(c)))
        truths.append(truth)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c0 = time.process_time()
        ad = bw.diagnose_across(groups, [0.0, 1.0, 2.0], labels=["c=0", "c=1", "c=2"])
        rec: dict[str, Any] = {
            "id": f"across-{kind}-J-{seed}",
            "truth": truths,
            "cpu_seconds": time.process_time() - c0,
            "warnings": sorted({type(w.message).__name__ for w in caught}),
            "status": ad.status,
            "verdict": ad.verdict,
            "notes": list(ad.notes),
            "terms": [t.to_dict() for t in ad.terms],
            "partial": [t.to_dict() for t in ad.partial],
        }
    print(json.dumps(rec, default=str))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)

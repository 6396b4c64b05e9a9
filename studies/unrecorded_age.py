"""The unrecorded age on our own generator's records (benches/generator.py), the settling hidden.

The generator simulates each experiment from rest through SETTLE = 10 settle periods, during which a
degrading specimen already dissipates, and declares them (``settle_periods``). Here the same records are cut
at the first recorded period and declared 0, as a lab that does not report its settling would hand them over:
each experiment then starts aged by its own energy (10 periods of its own drive). Each case is diagnosed as
cut with the unrecorded age on (``age.ENABLED``) and off, and as generated (declared) with it on.

    PYTHONPATH=python python studies/unrecorded_age.py --cases 3 --sizes 10,30
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))


def _cut(recs: list[Any]) -> list[Any]:
    import bouc_wen_id as bw
    import numpy as np

    out = []
    for r in recs:
        k = int(r.settle_periods) * int(r.samples_per_period)
        t = np.asarray(r.t)[k:] - float(np.asarray(r.t)[k])
        u, y = np.asarray(r.u)[k:], np.asarray(r.y)[k:]
        out.append(
            bw.Recording(t, u, y, r.amplitude, r.frequency, settle_periods=0, metadata=dict(r.metadata))
        )
    return out


def main() -> int:
    import bouc_wen_id as bw
    import diagnosis as bench
    import generator as gen
    from bouc_wen_id.diagnosis import age

    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=3)
    ap.add_argument("--sizes", default="10,30")
    args = ap.parse_args()
    sizes = {float(s) for s in args.sizes.split(",")}
    jobs = bench.new_jobs(argparse.Namespace(quick=False, cases=args.cases, null=0, seed=0))
    jobs = [j for j in jobs if j[1] == "degradation" and j[3] in sizes]
    for kind, name, place, size, seed in jobs:
        case = gen.cached_case(kind, name, place, size, seed, None)
        for label, recs, on in (
            ("declared, age on", case.recordings, True),
            ("cut, age off", _cut(case.recordings), False),
            ("cut, age on", _cut(case.recordings), True),
        ):
            age.ENABLED = on
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = bw.diagnose(recs)
            deg = d.degradation
            ages = [round(a, 1) for a in deg.age_periods] if deg is not None else []
            print(
                f"{name}:{size:g}:{seed} {label}: {d.status}, named {[t.term for t in d.named]}, "
                f"final p {d.final.p_value:.2g}, truth {case.value:.3g}, "
                f"value {deg.value if deg is not None else float('nan'):.3g}, ages {ages}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

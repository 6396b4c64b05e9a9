"""Session 45 (eta45): a drift term's named value and se over noise seeds, on review 44's simulator and the
library's own, before/after (run with PYTHONPATH at the code to measure).

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/eta45/measure45.py EFFECT SIZE CFG SRC \
        FIRST LAST [OUT.jsonl]

EFFECT is ``eta`` (stiffness degradation) or ``nu`` (strength degradation); SRC ``rev`` (sim44.recordings)
or ``lib`` (bw.simulate with the drift term); the noise is the config's own (drive44.CONFIGS), drawn from
``default_rng([44, seed])`` in both. One JSON line per seed; a summary line at the end: named rate, mean
named value / truth, rms z of the named values, the statuses.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent.parent / "review44"))
import bouc_wen_id as bw  # noqa: E402
import drive44 as dr  # noqa: E402
import sim44 as s  # noqa: E402
from bouc_wen_id.terms import Degradation, StiffnessDegradation  # noqa: E402

TERM = {"eta": "stiffness_degradation", "nu": "degradation"}


def lib_recs(p: Any, d: Any, effect: str, truth: float, nz: Any, seed: int) -> list[Any]:
    """The library's simulator on review 44's plant and design, the same noise draw as sim44's."""
    g = p.g
    term = StiffnessDegradation(truth) if effect == "eta" else Degradation(truth)
    plant = bw.WienerPlant(
        bw.TransferFunction(list(g.num), list(g.den), delay=g.delay),
        bw.BoucWen(beta=p.hy.beta, gamma=p.hy.gamma, mu=p.hy.mu, alpha=1.0),
        terms=(term,),
    )
    rng = np.random.default_rng([44, seed])
    out = []
    for w, a in zip(d.omegas, d.amps):
        (r,) = bw.simulate(plant, bw.SinePlan([w], a, d.settle, d.periods, d.samples, noise_sd=0.0, seed=1))
        y = s.noisy(np.asarray(r.y), nz, rng)
        out.append(bw.Recording(np.asarray(r.t), np.asarray(r.u), y, a, w, settle_periods=d.settle))
    return out


def _logged_refine() -> None:
    """ETA45_LOG=1: print the drift-space d and se that ``drift_passes.refine`` gets, and what it returns."""
    from bouc_wen_id.diagnosis import drift_passes

    orig = drift_passes.refine

    def refine(*args: Any) -> Any:
        deg, sc = args[4], args[5]
        out = orig(*args)
        print(
            f"  refine: in {deg.value:.4g} +- {deg.standard_error:.2g} (d {deg.d / sc.y**2:.4g}), "
            f"out {out[0].value:.4g} +- {out[0].standard_error:.2g}",
            flush=True,
        )
        return out

    drift_passes.refine = refine


def main(argv: list[str]) -> None:
    if os.environ.get("ETA45_LOG"):
        _logged_refine()
    effect, size, cfg, src = argv[0], float(argv[1]), argv[2], argv[3]
    first, last = int(argv[4]), int(argv[5])
    out = open(argv[6], "a") if len(argv) > 6 else None
    p, d, truth, _ = dr.build(effect, size, cfg)
    term = TERM[effect]
    tv = truth[term]
    nz = dr.NOISES[dr.CONFIGS[cfg][2]]
    rows = []
    for seed in range(first, last):
        if src == "rev":
            recs = s.recordings(p, d, nz, seed)
        else:
            recs = lib_recs(p, d, effect, tv, nz, seed)
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dg = bw.diagnose(recs, candidates=[term])
        cpu = time.process_time() - t0
        named = [x for x in dg.named if x.term == term]
        v, se = (named[0].value, named[0].standard_error) if named else (math.nan, math.nan)
        row = {
            "case": f"{effect}-{size:g}-{cfg}-{seed}-{src}",
            "truth": tv,
            "value": v,
            "se": se,
            "ratio": v / tv,
            "z": (v - tv) / se,
            "status": dg.status,
            "as_recorded": any("used as recorded" in n for n in dg.notes),
            "hedged": any("first-order estimate" in n for n in dg.notes),
            "cpu": round(cpu, 1),
        }
        rows.append(row)
        print(json.dumps(row), flush=True)
        if out:
            out.write(json.dumps(row) + "\n")
    nm = [r for r in rows if math.isfinite(r["value"])]
    zs = np.array([r["z"] for r in nm])
    summary = {
        "summary": f"{effect}-{size:g}-{cfg}-{src}",
        "seeds": f"{first}..{last - 1}",
        "named": f"{len(nm)}/{len(rows)}",
        "mean_ratio": round(float(np.mean([r["ratio"] for r in nm])), 3) if nm else None,
        "rms_z": round(float(np.sqrt(np.mean(zs**2))), 2) if nm else None,
        "status": {k: sum(r["status"] == k for r in rows) for k in sorted({r["status"] for r in rows})},
    }
    print(json.dumps(summary), flush=True)
    if out:
        out.write(json.dumps(summary) + "\n")
        out.close()


if __name__ == "__main__":
    main(sys.argv[1:])

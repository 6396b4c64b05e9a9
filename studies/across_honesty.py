"""The diagnosis across conditions beside the per-condition diagnoses on three simulated multi-condition sets
(issue 18, "nothing false said"; diagnosis/across_said.py): a negative stiffness on u at every condition
(``negk``), one frequency with six amplitudes and a spring on x (``onefreq``), viscous damping on u with two
of five inputs clipped at the middle condition (``clipin``); each term's value moves with the condition.

The plants are simulated by reviewer 34's own simulator (``sim.py``, written apart from the library's; not in
this repository: ``--sim-dir``, default /work/review34). Prints one JSON object per case: each condition's
verdict and the across verdict.

    PYTHONPATH=python python studies/across_honesty.py negk onefreq clipin [--sim-dir DIR] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np

G = {"fo_delay": ([4.0], [1.0, 4.0], 0.05), "res_delay": ([36.0], [1.0, 1.2, 36.0], 0.03)}
F5 = ([1.0, 2.0, 3.5, 5.0, 7.0], [1.0] * 5, [10] * 5)
F1A6 = ([3.0] * 6, [0.2, 0.4, 0.6, 0.8, 1.0, 1.4], [10] * 6)
SD = 0.01
CASES: dict[str, dict[str, Any]] = {
    # reviewer 34's negku: k_u = -0.0447 at -10x; here -0.03, -0.045, -0.06
    "negk": dict(g="fo_delay", des=F5, key="k_u", vals=[-0.03, -0.045, -0.06], clip=None, seed=11),
    # reviewer 34's kx_f1a6: k_x = 0.0671 at 10x; here 0.06, 0.09, 0.12
    "onefreq": dict(g="fo_delay", des=F1A6, key="k_x", vals=[0.06, 0.09, 0.12], clip=None, seed=12),
    # review 33's clip_cu: c_u = 0.006044, inputs 0 and 3 clipped; here at the middle condition only
    "clipin": dict(
        g="res_delay",
        des=F5,
        key="c_u",
        vals=[0.004, 0.006, 0.008],
        clip={1: [0.9, None, None, 0.85, None]},
        seed=13,
    ),
}


def build(sim: Any, cid: str, k: int) -> list[Any]:
    """Condition ``k`` of case ``cid``: Recordings, or Measurements where the input is clipped."""
    c = CASES[cid]
    num, den, d = G[c["g"]]
    oms, amps, pers = c["des"]
    p = sim.Plant(num, den, d, 1.0, 0.3, 1.5, 1.0, {c["key"]: c["vals"][k]})
    clip = (c["clip"] or {}).get(k)
    ts, us, ys, _ = sim.simulate(p, oms, amps, np.array(pers), 12, P=128, sub=3, clip=clip)
    rng = np.random.default_rng(c["seed"] * 10 + k)
    recs: list[Any] = []
    for i, (t, u, y) in enumerate(zip(ts, us, ys)):
        yn = sim.noise("white", y, SD, rng, 128, oms[i])
        if clip is not None and clip[i] is not None:
            recs.append(bw.Measurement(t, u, yn, nominal_frequency=oms[i], name=f"c{k}e{i}"))
        else:
            recs.append(bw.Recording(t, u, yn, amplitude=amps[i], frequency=oms[i], settle_periods=12))
    return recs


def run(sim: Any, cid: str) -> dict[str, Any]:
    c = CASES[cid]
    groups = [build(sim, cid, k) for k in range(len(c["vals"]))]
    t0 = time.time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g) for g in groups]
        a = bw.diagnose_across(groups, c["vals"], per_condition=own)
    return {
        "case": cid,
        "key": c["key"],
        "values": c["vals"],
        "per_condition": [d.verdict for d in own],
        "across": a.verdict,
        "across_named": list(a.named),
        "across_status": a.status,
        "across_values": {
            t.term: [[v, se] for v, se in zip(t.values, t.standard_errors)] for t in (*a.terms, *a.partial)
        },
        "seconds": round(time.time() - t0, 1),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", choices=sorted(CASES))
    ap.add_argument("--sim-dir", default="/work/review34")
    ap.add_argument("--out", default="", help="a folder for CASE.json (default: print only)")
    args = ap.parse_args(argv)
    sys.path.insert(0, args.sim_dir)
    import sim  # type: ignore[import-not-found]

    for cid in args.cases:
        res = run(sim, cid)
        print(json.dumps(res, indent=1), flush=True)
        if args.out:
            Path(args.out).mkdir(parents=True, exist_ok=True)
            (Path(args.out) / f"{cid}.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

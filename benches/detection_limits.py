"""Calibration of the diagnosis's detection limits (diagnosis/limits.py) on benches/generator.py's data.

Per plant (seeded, benches/generator.py: G solved exactly, its own RK4, its own noise) and library term at
its place: the diagnosis of a null recording of the plant reports the term's detection limit L (50 % power)
and L90 (90 %). The generator's value for L is found by scaling (a diagnosis at 30x reads the library's
value per generator unit: 1 for a sensor lag in seconds). Cases are then drawn at 0.5x, 1x and 2x L (and
at L90) with fresh noise, and counted: the term's own first-step F-test passing at its level (what the
limit promises), the term named (the F-test and the held-out, share and law tests), and any detection
(status not "adequate").

Usage: ``python benches/detection_limits.py [--quick] [--plants N] [--noise N] [--workers 2] [--seed S]``
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Optional

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: (generator name, place, the library's code name): a sensor lag and viscous damping on x.
TERMS = (("sensor_lag", "", "sensor_lag"), ("viscous", "x", "viscous@x"))
MULTIPLES = (0.5, 1.0, 2.0)


def _diagnose(recs: list[Any]) -> Any:
    import bouc_wen_id as bw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


def _limit(d: Any, kind: str) -> tuple[float, float]:
    for lim in d.limits:
        if lim.term == kind:
            return lim.limit, lim.limit_90
    return math.nan, math.nan


def _trial_value(d: Any, kind: str) -> float:
    for tr in d.steps[0].trials if d.steps else ():
        if tr.term == kind and tr.fit is not None:
            i = tr.fit.params.terms.index(kind)
            s = d.settings["scale"]
            from bouc_wen_id.diagnosis.fitting import Scale

            return float(tr.fit.params.values[i]) * Scale(s["y"], s["u"]).factor(kind, tr.fit.params.mu)
    return math.nan


def _outcome(d: Any, kind: str) -> dict[str, bool]:
    f_pass = False
    if d.steps:
        st = d.steps[0]
        level = (0.5 if st.targeted else 1.0) * float(d.settings["alpha"])
        f_pass = any(
            t.term == kind and math.isfinite(t.p_adjusted) and t.p_adjusted < level for t in st.trials
        )
    return {"f": f_pass, "named": kind in d.named_terms, "detected": d.status != "adequate"}


def plant_job(job: tuple[str, str, str, int, int]) -> dict[str, Any]:
    """One plant and term: its limit from a null recording, then cases at multiples of it."""
    import generator as gen

    name, place, kind, seed, noise = job
    p = gen.make_plant(seed)
    b = gen.base(p)
    y0 = gen.run(p, gen.Effect(), shared=b)[0]
    d0 = _diagnose(gen.recordings(p, y0, 10**6 + seed))
    lim, lim90 = _limit(d0, kind)
    row: dict[str, Any] = {"term": kind, "seed": seed, "shape": p.shape, "limit": lim, "limit_90": lim90}
    if not (math.isfinite(lim) and lim > 0):
        return row
    # Library units per generator unit: a diagnosis at 30x the averaged noise reads the term's value.
    v30, _, y30 = gen._calibrate(p, name, place, 30.0, b)
    ratio = abs(_trial_value(_diagnose(gen.recordings(p, y30, 2 * 10**6 + seed)), kind)) / v30
    row["ratio"] = ratio
    out: dict[str, list[dict[str, bool]]] = {}
    for mult in (*MULTIPLES, "90"):
        target = lim90 if mult == "90" else float(mult) * lim
        y = gen.run(p, gen.Effect(name, place, np.array([target / ratio])), shared=b)[0]
        out[str(mult)] = [
            _outcome(_diagnose(gen.recordings(p, y, 3 * 10**6 + 1000 * seed + j)), kind) for j in range(noise)
        ]
    row["cases"] = out
    return row


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2 plants x 3 noise draws per multiple")
    ap.add_argument("--plants", type=int, default=8)
    ap.add_argument("--noise", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=9100)
    args = ap.parse_args(argv)
    if args.quick:
        args.plants, args.noise = 2, 3
    jobs = [(n, pl, k, args.seed + i, args.noise) for n, pl, k in TERMS for i in range(args.plants)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(plant_job, jobs))
    print(
        f"{'term':<12} {'plants':>6} {'ratio':>6} {'mult':>5} {'n':>4} {'F-test':>7} {'named':>6} "
        f"{'detect':>7}"
    )
    for _, _, kind in TERMS:
        rs = [r for r in rows if r["term"] == kind and "cases" in r]
        undefined = sum(1 for r in rows if r["term"] == kind and "cases" not in r)
        ratio = float(np.median([r["ratio"] for r in rs])) if rs else math.nan
        for mult in (*MULTIPLES, "90"):
            cs = [c for r in rs for c in r["cases"][str(mult)]]
            rate = {
                k: float(np.mean([c[k] for c in cs])) if cs else math.nan for k in ("f", "named", "detected")
            }
            label = "L90" if mult == "90" else f"{mult:g}L"
            print(
                f"{kind:<12} {len(rs):>6} {ratio:6.3f} {label:>5} {len(cs):>4} {rate['f']:7.2f} "
                f"{rate['named']:6.2f} {rate['detected']:7.2f}"
            )
        if undefined:
            print(f"{kind:<12} {undefined} plants with no finite limit")
    for r in rows:
        print(
            f"  {r['term']:<12} seed {r['seed']} {r['shape']:<9} L = {r['limit']:.3g}  "
            f"L90 = {r['limit_90']:.3g}  ratio {r.get('ratio', math.nan):.3g}"
        )
    print(f"{time.perf_counter() - t0:.0f} s wall on {args.workers} workers (under load)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Diagnosis on concealed effects: detection, naming and held-out gain, against the issue's targets.

Prints one table from one seeded run (design.md 10.5; generator in ``benches/concealed.py``):

- every library term hidden at 3x, 10x and 30x the averaged output's noise sd (``--cases`` each);
- null cases, the plain model (``--null``);
- physics outside the library: pinching, a hysteretic force fed back into a mass-spring.

Degradation is a library term fitted in drift space (design.md 10.6): its held-out ratio is that of the
block-resolved deviations from the mean period, ``sqrt(sum_j C_j(d_-j))`` of the chosen model (d = 0 when
degradation is not named) over the true structure's (degradation fitted), one experiment left out at a time.

Per row: detection rate (the plain model rejected), correct-name rate (the hidden term named, alone or as
an alternative), wrong-name rate (a term named that is not the hidden one), the held-out NRMSE of the
chosen model over that of the true structure fitted to the same data (median), the seconds per
diagnosis, and "left": what the plain model cannot absorb of the term (median RMS of the refined plain
fit's residual on the case's noise-free twin, in the same noise-sd units as the size; a sensor lag is a
delay in G to first order, so its 10x leaves ~0.15). Targets: at 10x and 30x the right term in >= 95 %;
null: any name in <= 5 %; outside: "unexplained" in >= 90 % and a wrong name in <= 10 %; held-out ratio
within 10 % (<= 1.10).

Usage: ``python benches/diagnosis.py [--cases 20] [--null 60] [--workers 2] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Optional

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

SIZES = (3.0, 10.0, 30.0)
OUTSIDE = ("pinching", "feedback")


def _held_out_ratio(d: Any, term: Optional[str]) -> float:
    """Held-out NRMSE of the chosen model over the true structure's, on the same data."""
    from bouc_wen_id.diagnosis.fitting import Scale, carry_through_g, fit_with, scaled
    from bouc_wen_id.diagnosis.select import held_out

    if term == "degradation":
        deg = d.degradation
        if deg is None or not deg.held_out_after:
            return math.nan
        chosen_cost = deg.held_out_after if "degradation" in d.named_terms else deg.held_out_before
        return math.sqrt(sum(chosen_cost) / sum(deg.held_out_after))
    chosen = d.final_fit
    truth_terms = () if term is None else (term,)
    if tuple(chosen.params.terms) == truth_terms:
        return 1.0
    s = d.settings["scale"]
    sx = carry_through_g(
        scaled(list(d.experiments), Scale(s["y"], s["u"])), d.plain_fit, d.settings["substeps"]
    )
    true_fit = d.plain_fit if term is None else fit_with(sx, d.plain_fit, term, d.settings["substeps"])
    if true_fit is None:
        return math.nan
    ho = held_out(sx, chosen, true_fit, d.settings["substeps"])
    if ho is None:
        return math.nan
    return float(np.mean(ho.nrmse_before) / np.mean(ho.nrmse_after))


def run_case(job: tuple[str, Optional[str], float, int]) -> dict[str, Any]:
    import warnings

    import bouc_wen_id as bw
    import concealed as C

    kind, term, size, seed = job
    if kind == "outside":
        assert term is not None
        recs = C.outside_case(term, seed)
    else:
        recs, _ = C.library_case(term, size, seed)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            d = bw.diagnose(recs)
        except bw.BoucWenIdError as exc:
            return {
                "kind": kind,
                "term": term,
                "size": size,
                "seed": seed,
                "error": f"{type(exc).__name__}: {exc}",
            }
    secs = time.perf_counter() - t0
    named = list(d.named_terms)
    alts = {a.rival for a in d.alternatives} | {a.term for a in d.alternatives}
    truth = term if kind == "library" else None
    correct = truth is not None and (truth in named or (truth in alts and any(n in alts for n in named)))
    wrong = any(n != truth and not (truth in alts and n in alts) for n in named)
    ratio = _held_out_ratio(d, truth) if kind != "outside" else math.nan
    left = C.left_size(term, size, seed) if kind == "library" and term is not None else math.nan
    return {
        "kind": kind,
        "term": term,
        "size": size,
        "seed": seed,
        "status": d.status,
        "named": named,
        "partial": [t.term for t in d.partial],
        "detected": d.status != "adequate",
        "correct": bool(correct),
        "wrong": bool(wrong),
        "unexplained": d.status == "unexplained",
        "ratio": ratio,
        "left": left,
        "seconds": secs,
        "verdict": d.verdict,
    }


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--null", type=int, default=60)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--terms",
        default="offset,stiffness,viscous,inertia,coulomb,sensor_lag,asymmetry,play,degradation,distortion",
    )
    ap.add_argument("--outside", default=",".join(OUTSIDE))
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)

    jobs: list[tuple[str, Optional[str], float, int]] = []
    for term in [t for t in args.terms.split(",") if t]:
        for size in SIZES:
            jobs += [("library", term, size, 1000 + s) for s in range(args.cases)]
    jobs += [("null", None, 0.0, 5000 + s) for s in range(args.null)]
    for kind in [k for k in args.outside.split(",") if k]:
        jobs += [("outside", kind, 0.0, 9000 + s) for s in range(args.cases)]

    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        rows = list(pool.map(run_case, jobs, chunksize=1))
    wall = time.perf_counter() - t0

    groups: dict[tuple[str, str, float], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["kind"], r["term"] or "plain", r["size"]), []).append(r)
    head = (
        f"{'case':<26} {'n':>3} {'detect':>7} {'correct':>8} {'wrong':>6} {'unexpl':>7} {'HO ratio':>9} "
        f"{'err':>4} {'s/diag':>7} {'left':>6}  target"
    )
    print(head)
    print("-" * len(head))
    for (kind, term, size), rs in groups.items():
        ok = [r for r in rs if "error" not in r]
        n = len(rs)

        def rate(key: str, ok: list[dict[str, Any]] = ok) -> float:
            return float(np.mean([r[key] for r in ok])) if ok else math.nan

        ratios = [r["ratio"] for r in ok if math.isfinite(r["ratio"])]
        med = float(np.median(ratios)) if ratios else math.nan
        secs = float(np.mean([r["seconds"] for r in ok])) if ok else math.nan
        lefts = [r["left"] for r in ok if math.isfinite(r.get("left", math.nan))]
        left = float(np.median(lefts)) if lefts else math.nan
        label = f"{term} {size:g}x" if kind == "library" else (term if kind == "outside" else "null (plain)")
        if kind == "library":
            target = "correct >= 0.95, ratio <= 1.10" if size >= 10 else "(reported)"
        elif kind == "null":
            target = "any name (wrong) <= 0.05"
        else:
            target = "unexplained >= 0.90, wrong <= 0.10"
        print(
            f"{label:<26} {n:>3} {rate('detected'):7.2f} {rate('correct'):8.2f} {rate('wrong'):6.2f} "
            f"{rate('unexplained'):7.2f} {med:9.3f} {n - len(ok):>4} {secs:7.2f} {left:6.2f}  {target}"
        )
    print(f"\n{len(rows)} diagnoses in {wall:.0f} s wall on {args.workers} workers")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

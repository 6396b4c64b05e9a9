"""Are the diagnosis bench's misses a power limit? Per row, from a saved run (benches/diagnosis.py --json).

For each case the bench records what the plain model CANNOT absorb of the effect (``unabsorbed``, RMS in
averaged-noise sd, refitted on the case's noise-free records) and the size at which a one-parameter test at
the targeted step's level reaches 50 % power (``det_limit``). Their ratio squared times that test's
critical value is the non-centrality ``lam`` the effect gives ANY test of the plain model. This script turns
it into the best detection any test of the diagnosis could reach:

- ``p_one``: a candidate that took up ALL of ``lam`` with one parameter, tested at the targeted step's level
  (alpha / 2 over the candidates; an upper bound: outside physics is taken up only in part);
- ``p_glob``: the global adequacy test at alpha / 2 over the residual dof (chi2 approximation);
- ``bound``: either (``1 - (1 - p_one)(1 - p_glob)``), against the row's observed detection;
- ``meets``: the row's main rate (right name at its place; outside rows: unexplained or family);
- ``lam95``: the non-centrality the targeted test needs for 95 % power, and the size (in the row's units)
  at which the row's median case would reach it (lam grows with the size squared).

Then every missed case ("adequate"): whether what it left unseen lies below what its verdict now quotes
(diagnosis/resolution.py): the true value below the true term's 90 %-power limit (the bench's
``below_limit_90``, library terms in the library's units), and the unabsorbed RMS below the adequacy test's
90 %-power resolution (the bench's 50 % ``global_limit`` scaled by sqrt(lam_90 / lam_50)).

Usage::

    python studies/power_limits.py /work/fb10/sensor_lag.json /work/fb10/iwan.json ... [--candidates K]
"""

from __future__ import annotations

import argparse
import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import brentq  # type: ignore[import-untyped]
from scipy.stats import chi2, ncx2  # type: ignore[import-untyped]

ALPHA = 0.05
#: Residual dof lost to the plain model's parameters (3 Bouc-Wen, 2 per experiment for 10 experiments).
PLAIN_PARAMS = 23


def _candidates() -> int:
    from bouc_wen_id.diagnosis.run import ALL_CANDIDATES

    return len(ALL_CANDIDATES)


def case_power(unabs: float, det: float, lam_one: float) -> tuple[float, float, float]:
    """(lam, p_one, p_glob) of one case."""
    n = lam_one / det**2
    lam = lam_one * (unabs / det) ** 2
    dof = max(int(round(n)) - PLAIN_PARAMS, 1)
    p_one = float(ncx2.sf(lam_one, 1, lam))
    p_glob = float(ncx2.sf(chi2.isf(0.5 * ALPHA, dof), dof, lam))
    return lam, p_one, p_glob


def rows_of(paths: list[Path], lam_one: float) -> list[dict[str, Any]]:
    groups: dict[tuple[str, str, str, float], list[dict[str, Any]]] = defaultdict(list)
    for p in paths:
        for r in json.loads(p.read_text())["rows"]:
            if r.get("kind") in ("library", "outside") and math.isfinite(r.get("unabsorbed") or math.nan):
                groups[(r["kind"], r["term"], r.get("place") or "", float(r["size"]))].append(r)
    lam95 = float(brentq(lambda x: ncx2.sf(lam_one, 1, x) - 0.95, 0.0, 1e4))
    out = []
    for (kind, term, place, size), rs in sorted(groups.items()):
        got = [case_power(r["unabsorbed"], r["det_limit"], lam_one) for r in rs]
        lam = np.array([g[0] for g in got])
        bound = np.array([1 - (1 - g[1]) * (1 - g[2]) for g in got])
        ok = [r["right_place"] if kind == "library" else r["unexplained"] or r["family"] for r in rs]
        out.append(
            {
                "row": f"{kind[:3]} {term}{' on ' + place if place else ''} {size:g}x",
                "n": len(rs),
                "detect": float(np.mean([r["detected"] for r in rs])),
                "meets": float(np.mean(ok)),
                "lam_min": float(lam.min()),
                "lam_med": float(np.median(lam)),
                "p_one": float(np.mean([g[1] for g in got])),
                "p_glob": float(np.mean([g[2] for g in got])),
                "bound": float(bound.mean()),
                "size95": size * math.sqrt(lam95 / float(np.median(lam))),
                "lam95": lam95,
            }
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--candidates", type=int, default=0, help="candidates of the targeted step (0: all)")
    args = ap.parse_args()
    k = args.candidates or _candidates()
    lam_one = float(chi2.isf(0.5 * ALPHA / k, 1))
    rows = rows_of(args.runs, lam_one)
    print(
        f"targeted step: {k} candidates, chi2_1 critical value {lam_one:.2f}; 95 % power needs lam >= "
        f"{rows[0]['lam95'] if rows else math.nan:.1f}"
    )
    head = f"{'row':34s} {'n':>3s} {'detect':>6s} {'meets':>5s} {'lam_min':>7s} {'lam_med':>7s} "
    print(head + f"{'p_one':>6s} {'p_glob':>6s} {'bound':>6s} {'size95':>7s}")
    for r in rows:
        print(
            f"{r['row']:34s} {r['n']:3d} {r['detect']:6.2f} {r['meets']:5.2f} {r['lam_min']:7.1f} "
            f"{r['lam_med']:7.1f} {r['p_one']:6.2f} {r['p_glob']:6.2f} {r['bound']:6.2f} {r['size95']:6.1f}x"
        )
    misses(args.runs)


def misses(paths: list[Path]) -> None:
    """One line per missed case: the true value against the quoted 90 % limit, the unabsorbed RMS against
    the quoted resolution."""
    from bouc_wen_id.diagnosis.resolution import unseen_lambda

    print(
        "missed cases (adequate): unabsorbed RMS vs the adequacy test's 90 % resolution (averaged-noise sd)"
    )
    for p in paths:
        for r in json.loads(p.read_text())["rows"]:
            if r.get("detected", True) or not math.isfinite(r.get("unabsorbed") or math.nan):
                continue
            n = float(chi2.isf(0.5 * ALPHA / _candidates(), 1)) / r["det_limit"] ** 2
            dof = max(int(round(n)) - PLAIN_PARAMS, 1)
            nd = 20 * dof  # the bench's noise dof (19200 for 10 experiments) hardly moves F's tail here
            res = r["global_limit"] * math.sqrt(
                unseen_lambda(dof, nd, 0.025) / unseen_lambda(dof, nd, 0.025, 0.5)
            )
            below = r.get("below_limit_90")
            print(
                f"  {r['kind'][:3]} {r['term']} {r['size']:g}x seed {r['seed']}: "
                f"unabsorbed {r['unabsorbed']:.3f} < {res:.3f}: {r['unabsorbed'] < res}; "
                f"true value below its 90 % limit: {below}"
            )


if __name__ == "__main__":
    main()

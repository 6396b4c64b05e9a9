"""Where the stated 90 % detection limit loses its power (docs/diagnosis.md, "Coverage of the 90 % value").

For one design and term of studies/named_rate.py (reviewer 34's simulator): the limit is read from the null
recording's diagnosis (seed 1000), as studies/limit_coverage.py does; then, on that diagnosis's own averaged
experiments (weights, grid) with the averaged period replaced by the simulator's noise-free output with the
term at the stated 90 % value:

- ``at_null_fit``: the plain model refitted to the null's fitted model plus the term at that value (what the
  limit's own refits solve for ``t90``);
- ``noise_free_lam``: the plain model refitted to it (from the null's fit): the noncentrality the term really
  gives, against the target ``t90`` the limit was solved for;
- ``F``: Gaussian noise at each experiment's weight added to that averaged period (bypassing the recording's
  preprocessing), the plain model and the plain model plus the term fitted, the nested F statistic; ``pass``
  the share above the test's threshold (90 % promised).

Usage: ``python studies/limit_truth.py DESIGN TERM [--draws 12] [--sim /work/review34]`` (TERM as in
named_rate.py: k_x, m_u, ...). Prints one JSON line.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import named_rate  # noqa: E402


def averaged(des: str, eff: dict[str, float]) -> list[Any]:
    """The simulator's noise-free averaged periods (after the settling ones), scaled by the null's max."""
    named_rate.recordings(des, eff, 0)
    _, _, ys, _ = named_rate._CACHE[(des, tuple(sorted(eff.items())))]
    p = named_rate.SAMPLES
    out = [y[named_rate.SETTLE * p :].reshape(-1, p).mean(axis=0) for y in ys]
    named_rate._CACHE.setdefault(("sy", des), max(float(np.max(np.abs(o))) for o in out))
    return [o / named_rate._CACHE[("sy", des)] for o in out]


def main() -> None:
    from bouc_wen_id.diagnosis import limits
    from bouc_wen_id.diagnosis.fitting import fit_from, fit_with

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("design", choices=sorted(named_rate.DES))
    ap.add_argument("term", choices=sorted(named_rate.CODE))
    ap.add_argument("--draws", type=int, default=12)
    ap.add_argument("--sim", default="/work/review34", help="folder holding reviewer 34's sim.py")
    a = ap.parse_args()
    sys.path.insert(0, a.sim)
    code = named_rate.CODE[a.term]
    seen: dict[str, Any] = {}
    orig = limits._refined

    def keep(profile: Any, term: str, v1: float, targets: Any) -> tuple[float, float]:
        out = orig(profile, term, v1, targets)
        if term == code:
            seen.update(profile=profile, targets=targets, v90=out[1])
        return out

    limits._refined = keep  # type: ignore[assignment]
    d0 = named_rate.diagnose(named_rate.recordings(a.design, {}, 1000))
    limits._refined = orig  # type: ignore[assignment]
    lim = next((x for x in d0.limits if x.term == code), None)
    if lim is None or "profile" not in seen or not math.isfinite(lim.limit_90):
        print(json.dumps({"design": a.design, "term": a.term, "limit_90": None}))
        return
    profile, (t50, t90) = seen["profile"], seen["targets"]
    exps, sub, start = profile.exps, profile.substeps, profile.base.params
    y1 = averaged(a.design, {a.term: lim.limit_90})
    free = fit_from([replace(e, ybar=y) for e, y in zip(exps, y1)], start, sub)
    rng = np.random.default_rng(7)
    stats = []
    for _ in range(a.draws):
        noisy = [y + rng.standard_normal(y.size) / math.sqrt(e.weight) for e, y in zip(exps, y1)]
        ex = [replace(e, ybar=y) for e, y in zip(exps, noisy)]
        plain = fit_from(ex, start, sub)
        if plain is None:
            continue
        with_term = fit_with(ex, plain, code, sub)
        if with_term is None:
            continue
        dof = sum(e.ybar.size for e in ex) - len(with_term.params.values) - 3 - 2 * len(ex)
        stats.append((plain.cost - with_term.cost) / (with_term.cost / dof))
    row = {
        "design": a.design,
        "term": a.term,
        "limit_90": lim.limit_90,
        "t50": t50,
        "t90": t90,
        "at_null_fit": profile.exact(code, seen["v90"]) if math.isfinite(seen["v90"]) else None,
        "noise_free_lam": None if free is None else free.cost,
        "F": [round(f, 2) for f in stats],
        "mean_F": float(np.mean(stats)) if stats else None,
        "pass": float(np.mean(np.array(stats) > t50)) if stats else None,
    }
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()

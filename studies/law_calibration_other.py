"""The law test's and the adequacy test's false refusals of a TRUE term, on generators other than ours.

``studies/law_calibration.py`` measures the truth's law p on ``benches/generator.py``'s cases. This does the
same on data made another way: ``benches/blind.py``'s generator (its own G realisations, path-integrated
Bouc-Wen, white / AR(1) / ADC / drifting noise, its own designs), and, with ``--review-sim DIR``, a
reviewer's simulator directory holding ``run34.py`` and ``sim.py`` (the session-34 review's own RK4 with an
exact sensor lag and Spencer's series dashpot; not shipped with the package). For each case it runs the
diagnosis's own preparation, fits the plain model and then plain + the TRUE term (as the first step fits a
candidate, ``select.memo_fit_with``), and records the true term's ``select.element_law_test`` p and the true
model's adequacy p (as ``benches/oracle.py``): under the truth both should be uniform, so that a true term
is refused at ``LAW_ALPHA`` (1 %) and a true model rejected at ``alpha`` (5 %).

Usage::

    python studies/law_calibration_other.py blind sensor_lag --cases 100 [--seed 4242] [--json F]
    python studies/law_calibration_other.py review series_dashpot --review-sim DIR --g fo_delay --design f5

One JSON line per case on stdout; the summary (shares below 0.01 / 0.05 / 0.1 and a KS p) on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "benches"))
sys.path.insert(0, str(HERE))


def truth_tests(recordings: Any, truth: str) -> dict[str, float]:
    """The true term's law p (``element_p``) and the true model's adequacy p (``truth_p``)."""
    import law_calibration as lc
    from bouc_wen_id.diagnosis import free_dc
    from bouc_wen_id.diagnosis.fitting import fit_plain, scale_of, scaled, substeps_for
    from bouc_wen_id.diagnosis.locate import adequacy_p
    from bouc_wen_id.diagnosis.select import element_law_test, memo_fit_with

    exps = lc._prepared(recordings)
    s = scale_of(exps)
    sx = scaled(exps, s)
    substeps = substeps_for([e.ybar.size for e in sx])
    plain = fit_plain(exps, sx, s, substeps)
    f = memo_fit_with(sx, substeps)(plain, truth)
    if f is None:
        return {"element_p": math.nan, "truth_p": math.nan, "no_fit": 1.0}
    noise_dof = sum(int(e.noise_dof) for e in exps)
    dof = sum(a.ybar.size for a in sx) - free_dc.spent(sx) - (3 + len(f.params.terms) + 2 * len(sx))
    return {
        "element_p": element_law_test(sx, f, truth, substeps),
        "truth_p": adequacy_p(f.cost, dof, noise_dof),
    }


def blind_recordings(term: str, size: float, index: int, seed: int) -> tuple[Any, dict[str, Any]]:
    """``benches/blind.py``'s case ``term`` at ``size`` (its own seed scheme with base ``seed``), read back
    from its CSV files as a user would."""
    import blind
    import bouc_wen_id as bw

    tag = (blind.LIBRARY + blind.OUTSIDE + ("null",)).index(term)
    s = int(np.random.SeedSequence([seed, tag, int(size), index]).generate_state(1)[0])
    made = blind.make_case(blind.Case(term, size, index, s))
    info = {k: made["info"][k] for k in ("plant", "design", "noise")}
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, (e, u, y) in enumerate(zip(made["exps"], made["u"], made["y"])):
            paths.append(Path(tmp) / f"run_{i:02d}.csv")
            blind.write_csv(paths[-1], e, u, y)
        return bw.load(paths), info


_MEMO: dict[tuple[str, str], float] = {}


def review_recordings(term: str, size: float, seed: int, g: str, design: str) -> tuple[Any, dict[str, Any]]:
    """The review simulator's case: ``term`` at ``size`` on its G ``g`` and design ``design``, white
    noise, noise draw ``seed`` (its effect calibrated once per case)."""
    import run34 as rc

    key = {"sensor_lag": "lag", "series_dashpot": "dashpot"}[term]
    cid = f"{term}_{g}_{design}_{size:g}"
    if cid not in rc.CASES:
        rc.case(cid, g, design, "white", {key: size}, term)
        cal = rc.calibrate

        def memo(base: Any, k: str, *a: Any, **kw: Any) -> float:
            if (cid, k) not in _MEMO:
                _MEMO[(cid, k)] = float(cal(base, k, *a, **kw))
            return _MEMO[(cid, k)]

        rc.calibrate = memo
    rc.CASES[cid]["seed"] = seed
    recs, eff = rc.build(cid)
    return recs, {"g": g, "design": design, "value": float(eff[key])}


def summary(rows: list[dict[str, Any]], key: str) -> str:
    from scipy.stats import kstest  # type: ignore[import-untyped]

    ps = [float(r[key]) for r in rows if math.isfinite(float(r.get(key, math.nan)))]
    if not ps:
        return f"{key}: no p"
    below = " / ".join(f"{sum(p < a for p in ps)}" for a in (0.01, 0.05, 0.1))
    return (
        f"{key}: n {len(ps)} of {len(rows)}; below 0.01 / 0.05 / 0.1: {below}; min {min(ps):.3g}; "
        f"KS p {kstest(ps, 'uniform').pvalue:.2f}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("generator", choices=("blind", "review"))
    ap.add_argument("term")
    ap.add_argument("--size", type=float, default=10.0)
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--first", type=int, default=0, help="first case index (blind) or noise seed (review)")
    ap.add_argument("--seed", type=int, default=4242, help="blind.py's base seed")
    ap.add_argument("--review-sim", type=Path, help="directory holding the review's run34.py and sim.py")
    ap.add_argument("--g", default="fo_delay")
    ap.add_argument("--design", default="f5")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.generator == "review":
        if args.review_sim is None:
            ap.error("review needs --review-sim DIR")
        sys.path.insert(0, str(args.review_sim))
    rows = []
    for k in range(args.first, args.first + args.cases):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if args.generator == "blind":
                recs, info = blind_recordings(args.term, args.size, k, args.seed)
            else:
                recs, info = review_recordings(args.term, args.size, k, args.g, args.design)
            row: dict[str, Any] = {"generator": args.generator, "term": args.term, "case": k, **info}
            row.update(truth_tests(recs, args.term))
        row["seconds"] = round(time.perf_counter() - t0, 1)
        rows.append(row)
        print(json.dumps(row), flush=True)
    for key in ("element_p", "truth_p"):
        print(summary(rows, key), file=sys.stderr)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

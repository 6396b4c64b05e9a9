"""Calibration of the diagnosis's law test (issue 18: "every statistic is valid or says why not").

A term is named only if its law holds: one value for every experiment (``select.element_law_test``). Under
the truth (the true term present, data from the bench's generator, ``benches/generator.py``, made another
way than the library) its p-value should be uniform on (0, 1), so that a true term is refused at rate alpha.

For every library row of ``benches/diagnosis.py`` (the same cases, the same seeds; ``--cache DIR`` reuses
the bench's stored cases) this fits the TRUE structure (the plain model, then the true term at its place,
as the diagnosis's forward step fits a candidate) and records the true term's law p. Per row it prints the
share of p below 0.01 / 0.05 / 0.1 and a Kolmogorov-Smirnov p against uniform; "nan" counts the cases
without a p (the fit of plain + truth failed, ``no_fit`` in the JSON, or the law test returned NaN).

Usage: ``python studies/law_calibration.py [--quick] [--cases N] [--sizes 10,30] [--only a,b]
[--seed S] [--workers 2] [--cache DIR] [--json out.json] [--table run.json ...]``; ``--quick``: 3 cases
per row at 30x (under a minute). Rows skipped: the drift terms (degradation, stiffness degradation), fitted
in drift space and not tested by the steady law.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

BENCHES = Path(__file__).resolve().parent.parent / "benches"
sys.path.insert(0, str(BENCHES))


class _Captured(Exception):
    """Carries the checked experiments out of ``run._diagnose_set`` (the diagnosis's own preparation)."""

    def __init__(self, exps: Any) -> None:
        super().__init__("captured")
        self.exps = exps


def _prepared(recordings: Any) -> Any:
    """The diagnosis's checked experiments of ``recordings`` (its own trimming, averaging, noise floors)."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import run

    def capture(exps: Any, setup: Any, notes: Any) -> Any:
        raise _Captured(exps)

    saved = run._diagnose_set
    run._diagnose_set = capture
    try:
        bw.diagnose(recordings)
    except _Captured as c:
        return c.exps
    finally:
        run._diagnose_set = saved
    raise RuntimeError("the diagnosis did not reach its selection")


def truth_law_p(recordings: Any, truth: str) -> dict[str, float]:
    """The true term's law p (``element_law_test`` and the plain ``law_test``) at the fit of the plain
    model plus the true term, as the diagnosis's first step fits it."""
    from bouc_wen_id.diagnosis.fitting import fit_plain, scale_of, scaled, substeps_for
    from bouc_wen_id.diagnosis.select import element_law_test, law_test, memo_fit_with

    exps = _prepared(recordings)
    s = scale_of(exps)
    sx = scaled(exps, s)
    substeps = substeps_for([e.ybar.size for e in sx])
    plain = fit_plain(exps, sx, s, substeps)
    f = memo_fit_with(sx, substeps)(plain, truth)
    if f is None:  # the fit of plain + truth failed (the diagnosis's step records a failed trial too)
        return {"law_p": math.nan, "element_p": math.nan, "no_fit": 1.0}
    return {
        "law_p": law_test(sx, f, truth, substeps),
        "element_p": element_law_test(sx, f, truth, substeps),
    }


def run_case(job: tuple[str, str, str, float, int], cache: Optional[Path]) -> dict[str, Any]:
    import diagnosis as bench
    import generator as gen

    kind, name, place, size, seed = job
    row: dict[str, Any] = {"term": name, "place": place, "size": size, "seed": seed}
    t0 = time.perf_counter()
    try:
        case = gen.cached_case(kind, name, place, size, seed, cache)
        lib = bench.library_effects()
        truth = lib[name].kind if name in lib else bench.true_kind(name, place)
        row["truth"] = truth
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            row.update(truth_law_p(case.recordings, truth))
    except Exception as exc:  # reported per case, never fatal
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["seconds"] = time.perf_counter() - t0
    return row


def jobs_of(args: argparse.Namespace) -> list[tuple[str, str, str, float, int]]:
    """The bench's library rows (its seeds), filtered by ``--only`` and ``--sizes``."""
    import diagnosis as bench
    from bouc_wen_id.diagnosis.drift import DRIFT_TERMS

    ns = argparse.Namespace(quick=False, cases=args.cases, null=0, seed=args.seed)
    sizes = {float(v) for v in args.sizes.split(",")}
    keep = set(args.only.split(",")) if args.only else None
    out = []
    for kind, name, place, size, seed in bench.new_jobs(ns):
        if name is None or bench.scored_kind(kind, name) != "library" or size not in sizes:
            continue
        if name in DRIFT_TERMS:  # fitted in drift space (design.md 10.6): no steady law to test
            continue
        if keep is not None and name not in keep:
            continue
        out.append((kind, name, place, size, seed))
    return out


def _finite(rows: list[dict[str, Any]], key: str) -> FloatArray:
    v = [r.get(key, math.nan) for r in rows]
    return np.array([p for p in v if isinstance(p, float) and math.isfinite(p)])


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (term, place, size): n, the shares of the element's law p below 0.01 / 0.05 / 0.1, its smallest
    p, the KS p of both (the element's law p, ``element_law_test``, and the law test alone, ``law_test``:
    they differ for a two-claim element, Dahl friction and pinching, whose Bonferroni min(1, 2 min p)
    is conservative by construction) against uniform; a last line pools every row."""
    from scipy.stats import kstest

    groups: dict[tuple[str, str, float], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["term"], r["place"], r["size"]), []).append(r)
    out = []
    for (term, place, size), rs in [*groups.items(), (("all rows", "", math.nan), rows)]:
        a, law = _finite(rs, "element_p"), _finite(rs, "law_p")
        line: dict[str, Any] = {
            "row": f"{term}{'@' + place if place else ''}",
            "size": size,
            "n": int(a.size),
        }
        line["nan"] = len(rs) - a.size
        for lv in (0.01, 0.05, 0.1):
            line[f"<{lv:g}"] = float(np.mean(a < lv)) if a.size else math.nan
        line["min"] = float(a.min()) if a.size else math.nan
        line["ks_p"] = float(kstest(a, "uniform").pvalue) if a.size else math.nan
        line["ks_law"] = float(kstest(law, "uniform").pvalue) if law.size else math.nan
        out.append(line)
    return out


def print_summary(lines: list[dict[str, Any]]) -> None:
    head = ("row", "size", "n", "nan", "<.01", "<.05", "<.1", "min p", "KS p", "KS law")
    print("{:22s} {:>4s} {:>4s} {:>3s} {:>5s} {:>5s} {:>5s} {:>8s} {:>6s} {:>6s}".format(*head))
    for ln in lines:
        print(
            f"{ln['row']:22s} {ln['size']:4.0f} {ln['n']:4d} {ln['nan']:3d} {ln['<0.01']:5.3f} "
            f"{ln['<0.05']:5.3f} {ln['<0.1']:5.3f} {ln['min']:8.2g} {ln['ks_p']:6.3f} {ln['ks_law']:6.3f}"
        )


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 cases per row at 30x")
    ap.add_argument("--cases", type=int, default=None)
    ap.add_argument("--sizes", default=None)
    ap.add_argument("--only", default="")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=None)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument(
        "--table", type=Path, nargs="+", default=None, help="re-print the table of saved --json runs"
    )
    args = ap.parse_args(argv)
    if args.table:
        print_summary(summary([r for f in args.table for r in json.loads(f.read_text())["rows"]]))
        return 0
    args.cases = args.cases if args.cases is not None else (3 if args.quick else 20)
    args.sizes = args.sizes or ("30" if args.quick else "10,30")
    jobs = jobs_of(args)
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        futs = [ex.submit(run_case, j, args.cache) for j in jobs]
        for k, fu in enumerate(futs):
            r = fu.result()
            rows.append(r)
            err = f" ERROR {r['error']}" if "error" in r else ""
            print(
                f"[{k + 1}/{len(jobs)}] {r['term']}@{r['place']} {r['size']:g}x seed {r['seed']}: "
                f"p = {r.get('element_p', math.nan):.3g} ({r['seconds']:.1f} s){err}",
                file=sys.stderr,
            )
    print_summary(summary(rows))
    print(f"\n{len(rows)} cases in {time.perf_counter() - t0:.0f} s wall on {args.workers} workers")
    if args.json:
        args.json.write_text(json.dumps({"rows": rows}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Why a bench case missed: how much of the hidden effect the plain model absorbs, and whether the true
model itself fits the noisy data (docs/diagnosis.md, "Misses at 10x").

Per case of ``benches/generator.py`` (library row ``ROW`` at size ``SIZE``, the given seeds; ``--cache DIR``
reads the bench's cached cases), on the diagnosis's own weights (its noise estimates):

- ``lambda``: the plain model refitted to the generator's NOISE-FREE output; its chi2 is what any test of
  the plain model can see of the effect (the rest is absorbed by Bouc-Wen and each experiment's |G| and
  phase), beside the raw chi2 of the effect (its noise-free contribution before any refit);
- ``power``: of a one-sided 1-dof test at the targeted step's level (alpha/2 over the candidates) at that
  noncentrality;
- ``truth clean``: plain + the true term fitted to the noise-free output (0: the library's term is the
  generator's);
- ``noise``: chi2 of the noise alone (noisy minus noise-free averaged periods), ``truth noisy``: plain + the
  true term fitted to the noisy data (the diagnosis's candidate fit), and the truth's law p there.

Usage: ``python studies/unabsorbed.py ROW SIZE SEED [SEED ...] [--place x] [--cache DIR]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))


def measure(row: str, place: str, size: float, seed: int, cache: Any) -> str:
    """One case's line (module docstring)."""
    import bouc_wen_id as bw
    import diagnosis as bench  # benches/diagnosis.py
    import generator as gen  # benches/generator.py
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.fitting import Scale, fit_plain, fit_with, scaled
    from bouc_wen_id.diagnosis.select import ALPHA, law_test
    from scipy.stats import norm  # type: ignore[import-untyped]

    lib = bench.library_effects()
    truth = bench.true_kind(lib[row].base_kind if row in lib else row, place)
    case = gen.cached_case("library", row, place, size, seed, cache)
    p = gen.make_plant(seed)
    b = gen.base(p)
    value, _, y = gen._calibrate(p, row, place, size, b)
    plain_y = gen.run(p, gen.Effect(), shared=b)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
        noisy = list(d.experiments)
        s = Scale(d.settings["scale"]["y"], d.settings["scale"]["u"])
        sub = d.settings["substeps"]
        clean = [
            replace(e, ybar=c.ybar) for e, c in zip(noisy, prepare(gen.recordings(p, y, seed, noise_sd=0.0)))
        ]
        pl = prepare(gen.recordings(p, plain_y, seed, noise_sd=0.0))
        raw = sum(e.weight * float(np.sum((e.ybar - q.ybar) ** 2)) for e, q in zip(clean, pl))
        noise = sum(e.weight * float(np.sum((e.ybar - c.ybar) ** 2)) for e, c in zip(noisy, clean))
        csx = scaled(clean, s)
        f0 = fit_plain(clean, csx, s, sub)
        f1 = fit_with(csx, f0, truth, sub)
        nsx = scaled(noisy, s)
        fn = fit_with(nsx, d.plain_fit, truth, sub)
    lam = f0.cost
    n_cand = max(len(d.steps[0].trials), 1) if d.steps else 16
    z = float(norm.isf(0.5 * ALPHA / n_cand))
    power = float(norm.sf(z - math.sqrt(max(lam, 0.0))))
    lim = next((x for x in d.limits if x.term == truth), None)
    lims = "" if lim is None else f" limit {lim.limit:.3g} limit_90 {lim.limit_90:.3g}"
    n = sum(e.ybar.size for e in noisy)
    tc = math.nan if f1 is None else f1.cost
    tn = math.nan if fn is None else fn.cost
    lp = math.nan if fn is None else law_test(nsx, fn, truth, sub)
    return (
        f"{seed} {case.shape:8s} {d.status:17s} value {value:.4g}{lims}; raw chi2 {raw:.4g}, "
        f"lambda {lam:.1f} (power {power:.2f}); truth clean {tc:.1f}; noise {noise:.1f} over {n} samples; "
        f"truth noisy {tn:.1f} (plain {d.plain_fit.cost:.1f}), law p {lp:.2g}"
    )


def main(argv: Any = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("row")
    ap.add_argument("size", type=float)
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--place", default="", help="the effect's place (x for the Dahl row)")
    ap.add_argument("--cache", type=Path, default=None, help="the bench's --cache DIR")
    args = ap.parse_args(argv)
    for seed in args.seeds:
        print(measure(args.row, args.place, args.size, seed, args.cache), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

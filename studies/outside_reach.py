"""Why an outside effect at 10x passes the plain model's adequacy test: absorbed, or a test without power?

Per case of ``benches/generator.py`` (outside row ``ROW`` at size ``SIZE``, the given seeds), on the
diagnosis's own weights (its noise estimates), the plain model (G free per experiment) is refitted to the
generator's NOISE-FREE output from the diagnosis's plain fit. Its cost ``lam`` is the non-centrality the
effect gives any test of the plain model (what Bouc-Wen and each experiment's |G| and phase did not
absorb). Printed:

- where ``lam`` sits: its share in the largest experiment and in harmonics <= 7 and <= 15;
- the power at ``lam``'s pattern of tests that might see it, each at the global test's level ``alpha / 2``:
  ``global`` (the diagnosis's own: chi-square of every sample against the noise floor, F(dof, noise dof));
  ``odd3-15`` (only the odd harmonics 3-15, pooled over experiments: a test that presumes an odd-symmetric
  loop's residual and knows the band, chosen after seeing where ``lam`` sits: an upper bound of what a band
  test could gain); ``max-exp`` (each experiment's own chi-square, Sidak over the experiments);
  ``oracle`` (a 1-dof test taking up ALL of ``lam``, at the targeted step's level alpha/2 over the
  candidates: only a library term of exactly this shape would reach it);
- ``held-out lam``: one experiment left out at a time, the shared parameters fitted on the others, the
  left-out one given only its own |G| and phase: the non-centrality of a held-out cross-check of the
  plain model, summed over the folds (the in-sample ``lam`` is its lower end: if the held-out one is not
  much larger, a held-out check adds no power);
- the diagnosis's status and, for the step-0 candidates that took most, their drop in chi-square.

Usage: ``python studies/outside_reach.py ROW SIZE SEED [SEED ...]`` (e.g. ``iwan 10 58003 58004``; the
seeds of ``benches/diagnosis.py``'s rows: pi_u 10x 62000-62019, iwan 10x 58000-58019).
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


def _powers(h: Any, lam: float, dof: int, noise_dof: int, level: float, n_cand: int) -> dict[str, float]:
    """Power of the tests of the module docstring at the non-centralities ``h`` (experiments x harmonics)."""
    from scipy.stats import chi2, ncf, ncx2  # type: ignore[import-untyped]
    from scipy.stats import f as f_dist

    def chi_power(nc: float, k: int, a: float) -> float:
        return float(ncx2.sf(chi2.isf(a, k), k, nc)) if nc > 0 else a

    m = h.shape[0]
    odd = h[:, 3:16:2]
    per_exp = 1.0 - (1.0 - level) ** (1.0 / m)  # Sidak
    samples = dof // m + 1
    none_seen = np.prod([1.0 - chi_power(float(x), samples, per_exp) for x in h.sum(axis=1)])
    return {
        "global": float(ncf.sf(f_dist.isf(level, dof, noise_dof), dof, noise_dof, lam)),
        "odd3-15": chi_power(float(odd.sum()), 2 * odd.size, level),
        "max-exp": float(1.0 - none_seen),
        "oracle": chi_power(lam, 1, level / max(n_cand, 1)),
    }


def measure(row: str, size: float, seed: int) -> str:
    """One case's lines (module docstring)."""
    import bouc_wen_id as bw
    import diagnosis as bench  # benches/diagnosis.py
    import generator as gen  # benches/generator.py
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.fitting import Scale, fit_from, fit_own, scaled, subset

    case = gen.cached_case("outside", row, "", size, seed, None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
        exps = list(d.experiments)
        clean = {e.source: e for e in prepare(bench._clean_recordings("outside", row, "", size, seed))}
        s = Scale(d.settings["scale"]["y"], d.settings["scale"]["u"])
        sub = d.settings["substeps"]
        sx = [replace(e, ybar=clean[x.source].ybar / s.y) for e, x in zip(scaled(exps, s), exps)]
        fit = fit_from(sx, d.plain_fit.params, sub)
        assert fit is not None
        h = np.zeros((len(sx), 16))
        for i, (e, out) in enumerate(zip(sx, fit.outputs)):
            c = np.fft.rfft((e.ybar - out) * math.sqrt(e.weight)) / e.ybar.size
            h[i, 0] = e.ybar.size * c[0].real ** 2
            h[i, 1:] = 2 * e.ybar.size * np.abs(c[1:16]) ** 2
        held = 0.0
        for i in range(len(sx)):
            keep = [k for k in range(len(sx)) if k != i]
            others, start = subset(sx, fit.params, keep)
            f_i = fit_from(others, start, sub)
            if f_i is None:
                held = math.nan
                break
            g_i, ph_i = float(fit.params.gains[i]), float(fit.params.phases[i])
            held += fit_own(sx[i], f_i.params, g_i, ph_i, sub)[0]
    lam = float(fit.cost)
    n = sum(e.ybar.size for e in sx)
    dof = n - (3 + 2 * len(sx))
    noise_dof = max(sum(int(e.noise_dof) for e in exps), 1)
    level = 0.5 * float(d.settings["alpha"])
    pw = _powers(h, lam, dof, noise_dof, level, len(d.settings["candidates"]))
    lam_global = dof * (float(_f_isf(level, dof, noise_dof)) - 1.0)
    top = sorted(d.steps[0].trials, key=lambda t: t.cost)[:3] if d.steps else []
    return (
        f"{row} {size:g}x {seed} ({case.shape} G): {d.status}"
        f"{' ' + ', '.join(d.named_terms) if getattr(d, 'named_terms', None) else ''}\n"
        f"  lam {lam:.1f} (global 50 % point {lam_global:.0f}; RMS {math.sqrt(lam / n):.3f} sd); "
        f"largest experiment {h.sum(axis=1).max() / max(h.sum(), 1e-300):.2f} of it, harmonics <= 7 "
        f"{h[:, :8].sum() / lam:.2f}, <= 15 {h.sum() / lam:.2f}; held-out lam {held:.1f}\n"
        f"  power: " + ", ".join(f"{k} {v:.2f}" for k, v in pw.items()) + "\n"
        "  step 0 best: " + ", ".join(f"{t.term} -{t.improvement:.1f}" for t in top)
    )


def _f_isf(level: float, dof: int, noise_dof: int) -> float:
    from scipy.stats import f as f_dist  # type: ignore[import-untyped]

    return float(f_dist.isf(level, dof, noise_dof))


def main(argv: Any = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("row")
    ap.add_argument("size", type=float)
    ap.add_argument("seeds", type=int, nargs="+")
    args = ap.parse_args(argv)
    for seed in args.seeds:
        print(measure(args.row, args.size, seed), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

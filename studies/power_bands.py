"""Where a missed effect's unabsorbed part sits, by harmonic, and what a targeted band test would have seen.

For cached cases of the diagnosis bench (benches/diagnosis.py --cache DIR; benches/generator.py's records),
it diagnoses the case as the bench does and prints one JSON line per case: the plain fit's global p, the
plain residual's chi-square per harmonic 0..15 on the noisy data (``noisy_h``, weighted by each experiment's
noise floor; under an adequate model harmonic k > 0 is chi2 with 2 dof per experiment), the same on the
noise-free records refitted from the plain fit (``clean_h``: the non-centrality each harmonic carries;
``lam`` their total), the noise-free gain of chosen candidate terms (``TERMS=a,b``), the first step's four
best trials, and the p-values of two band tests on the noisy residual: harmonics 1-5 and the odd
harmonics 3-15 (the tests issue 18's idea proposed; a band test would run at alpha / 4 beside the global
test at alpha / 4 to keep the gate's size).

Usage::

    TERMS=sensor_lag python studies/power_bands.py library sensor_lag "" 10 35014 35019 --cache /work/fb7cache
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

KMAX = 15


def band_stats(sx: list[Any], fit: Any) -> Any:
    """Weighted chi-square of the residual per harmonic 0..KMAX."""
    from bouc_wen_id.augmented import augmented_output

    st = np.zeros(KMAX + 1)
    for i, e in enumerate(sx):
        r = e.ybar - np.asarray(augmented_output(e, fit.params, i, substeps=e.substeps))
        c = np.fft.rfft(r)[: KMAX + 1] / r.size
        st[0] += e.weight * r.size * c[0].real ** 2
        st[1:] += e.weight * 2 * r.size * np.abs(c[1:]) ** 2
    return st


def run(
    kind: str, name: Optional[str], place: str, size: float, seed: int, cache: Path, terms: list[str]
) -> Any:
    import bouc_wen_id as bw
    import diagnosis as bench
    import generator as gen
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.fitting import Scale, fit_from, fit_with, scaled
    from scipy.stats import chi2  # type: ignore[import-untyped]

    case = gen.cached_case(kind, name, place, size, seed, cache)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(case.recordings)
    exps = list(d.experiments)
    s = Scale(d.settings["scale"]["y"], d.settings["scale"]["u"])
    sub = d.settings["substeps"]
    sx = scaled(exps, s)
    st = band_stats(sx, d.plain_fit)
    m = len(sx)
    out: dict[str, Any] = {
        "seed": seed,
        "status": d.status,
        "p_global": d.plain.p_value,
        "noisy_h": st.round(1).tolist(),
        "p_h1_5": float(chi2.sf(st[1:6].sum(), 10 * m)),
        "p_odd3_15": float(chi2.sf(st[3:16:2].sum(), 14 * m)),
    }
    if name is not None:
        clean = {e.source: e for e in prepare(bench._clean_recordings(kind, name, place, size, seed))}
        cx = [replace(e, ybar=clean[x.source].ybar / s.y) for e, x in zip(sx, exps)]
        f = fit_from(cx, d.plain_fit.params, sub)
        if f is not None:
            out["lam"] = f.cost
            out["clean_h"] = band_stats(cx, f).round(2).tolist()
            for t in terms:
                g = fit_with(cx, f, t, sub)
                out["clean_gain_" + t] = None if g is None else f.cost - g.cost
    if d.steps:
        st0 = d.steps[0]
        best = sorted(st0.trials, key=lambda t: -t.improvement)[:4]
        out["step0"] = {
            "targeted": st0.targeted,
            "chosen": st0.chosen,
            "best": [[t.term, round(t.improvement, 1), float(t.p_adjusted)] for t in best],
        }
    return out


def main() -> None:
    args = sys.argv[1:]
    cache = Path("/work/fb7cache")
    if "--cache" in args:
        i = args.index("--cache")
        cache = Path(args[i + 1])
        del args[i : i + 2]
    kind, name, place, size = args[0], args[1], args[2], float(args[3])
    terms = [x for x in os.environ.get("TERMS", "").split(",") if x]
    for sd in args[4:]:
        row = run(kind, None if name == "none" else name, place, size, int(sd), cache, terms)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()

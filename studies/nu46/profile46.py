"""Session 46 (nu46): strength degradation's two costs along d on one review 44 case, the steady cost taken
at its own fixed point (the virgin fit re-corrected with itself until it settles; commit abdd0dd's
``drift_passes.fixed_point``, which this script carries itself so that it runs on main's code).

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu46/profile46.py nu 10 A rev 2 \
        0.96,0.97,0.98,0.99,1.0,1.01,1.02
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent.parent / "review44"))
sys.path.insert(0, str(Path(__file__).parent.parent / "eta45"))
import bouc_wen_id as bw  # noqa: E402
import drive44 as dr  # noqa: E402
import sim44 as s  # noqa: E402
from bouc_wen_id.diagnosis import drift_passes as dp  # noqa: E402
from bouc_wen_id.diagnosis.drift import DEGRADATION, _sums, corrected  # noqa: E402
from bouc_wen_id.diagnosis.fitting import fit_from  # noqa: E402
from measure45 import lib_recs  # noqa: E402


def fixed_point(exps: Any, sx: Any, fit: Any, d: float, sc: Any, substeps: int) -> Any:
    """The virgin fit corrected at d with itself, pass after pass, until its chi2 moves by < 0.1."""
    for _ in range(dp.MAX_CORRECTION_PASSES):
        _, fsx = corrected(exps, sx, fit, d, sc.y, substeps, DEGRADATION)
        new = fit_from(fsx, fit.params, substeps, max_iter=50)
        if new is None:
            return fit
        done = abs(new.cost - fit.cost) < 0.1
        fit = new
        if done:
            break
    return fit


def main(argv: list[str]) -> None:
    eff, size, cfg, src, seed = argv[0], float(argv[1]), argv[2], argv[3], int(argv[4])
    grid = [float(x) for x in argv[5].split(",")]
    p, d, truth, _ = dr.build(eff, size, cfg)
    tv = truth["degradation"]
    nz = dr.NOISES[dr.CONFIGS[cfg][2]]
    recs = s.recordings(p, d, nz, seed) if src == "rev" else lib_recs(p, d, eff, tv, nz, seed)
    orig = dp.refine

    def refine(exps: Any, sx: Any, fit: Any, data: Any, deg: Any, sc: Any, substeps: int) -> Any:
        sums = [_sums(dd, deg.term) for dd in data]
        print(f"drift-space d / truth {deg.d / sc.y**2 / tv:.4f}, se / truth {deg.standard_error / tv:.4f}")
        f = fit
        for r in grid:
            dv = r * tv * sc.y**2
            f = fixed_point(exps, sx, f, dv, sc, substeps)
            cd = sum(c0 - 2.0 * dv * nm + dv * dv * dn for c0, nm, dn in sums)
            tot = f.cost + cd
            print(f"d/truth {r:.3f}  C_steady {f.cost:.2f}  C_drift {cd:.2f}  sum {tot:.2f}", flush=True)
        return orig(exps, sx, fit, data, deg, sc, substeps)

    dp.refine = refine
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = bw.diagnose(recs, candidates=["degradation"])
    named = [(round(n.value / tv, 4), round(n.standard_error / tv, 4)) for n in dg.named]
    print("named / truth:", named, dg.status)


if __name__ == "__main__":
    main(sys.argv[1:])

"""Session 47 (nu47): the joint fit ``ybar_i = steady_i(theta) + [sim_i(theta, d) - sim_i(theta, 0)]`` of the
averaged periods on the state the degradation stage hands its refinement (captured as probe47.py does), by
scipy's least squares with a numeric Jacobian, against the library's own value and final chi2.

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu47/joint47.py NOISE DELTA_NU SEED
"""

from __future__ import annotations

import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares  # type: ignore[import-untyped]

sys.path.insert(0, str(Path(__file__).parent.parent.parent / "tests"))
sys.path.insert(0, str(Path(__file__).parent))
import bouc_wen_id as bw  # noqa: E402
from bouc_wen_id.augmented import augmented_output  # noqa: E402
from bouc_wen_id.diagnosis.drift import DEGRADATION, corrected  # noqa: E402
from degradation_sim import records  # noqa: E402
from probe47 import CAP, capture  # noqa: E402


def residuals(exps: Any, sx: Any, par: Any, d: float, sy: float, substeps: int) -> np.ndarray:
    """Weighted residuals of the joint model at (par, d) over every averaged period."""
    fit = bw.augmented.AugFit.__new__(bw.augmented.AugFit)
    object.__setattr__(fit, "params", par)
    _, fsx = corrected(exps, sx, fit, d, sy, substeps, DEGRADATION)
    out = []
    for i, a in enumerate(fsx):
        y = augmented_output(a, par, i, substeps=substeps)
        out.append(np.sqrt(a.weight) * (a.ybar - y))
    return np.concatenate(out)


def main(argv: list[str]) -> None:
    noise, truth, seed = float(argv[0]), float(argv[1]), int(argv[2])
    capture()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = bw.diagnose(records(noise, seed, delta_nu=truth), candidates=["degradation"])
    exps, sx, fit, data, deg, s, substeps = CAP["args"]
    deg2, fit2 = CAP["out"]
    m = len(sx)
    dof = sum(a.ybar.size for a in sx) - 4 - 2 * m
    f = dg.final
    print(f"library: {dg.status}, d/truth {deg2.value / truth:.4f}, final chi2 {f.cost:.1f} dof {f.dof}")
    p0 = fit2.params
    sy2 = s.y**2

    def unpack(x: np.ndarray) -> tuple[Any, float]:
        par = replace(p0, beta=x[0], gamma=x[1], mu=x[2], gains=x[3 : 3 + m], phases=x[3 + m : 3 + 2 * m])
        return par, x[-1] * truth * sy2

    from bouc_wen_id.diagnosis.drift import _sums

    sums = [_sums(dd, deg.term) for dd in data]
    num, den = sum(c[1] for c in sums), sum(c[2] for c in sums)
    with_drift = len(argv) > 3 and argv[3] == "drift"
    se0 = 1 / np.sqrt(den) / sy2 / truth
    print(f"drift-space d/truth (passes' data) {num / den / sy2 / truth:.4f}, se/truth {se0:.4f}")

    def fun(x: np.ndarray) -> np.ndarray:
        par, d = unpack(x)
        r = residuals(exps, sx, par, d, s.y, substeps)
        return np.append(r, np.sqrt(den) * (d - num / den)) if with_drift else r

    x0 = np.concatenate([[p0.beta, p0.gamma, p0.mu], p0.gains, p0.phases, [deg2.value / truth]])
    r0 = fun(x0)
    print(f"joint chi2 at the library's (theta, d): {r0 @ r0:.1f}")
    t1 = time.process_time()
    for _ in range(5):
        fun(x0 * (1 + 1e-7 * np.arange(x0.size)))
    print(f"cpu per evaluation (18 sims + 9 steady) {(time.process_time() - t1) / 5:.3f}")
    for k in range(m):
        n = sx[k].ybar.size
        print(f"  exp {k}: {r0[k * n : (k + 1) * n] @ r0[k * n : (k + 1) * n]:.1f}", end="")
    print()
    t0 = time.process_time()
    res = least_squares(fun, x0, diff_step=1e-6, x_scale="jac", max_nfev=60)
    par, d = unpack(res.x)
    jac = res.jac
    cov = np.linalg.pinv(jac.T @ jac)
    chi2 = float(res.fun @ res.fun)
    se = float(np.sqrt(cov[-1, -1] * max(1.0, chi2 / dof)))
    print(
        f"joint fit: chi2 {chi2:.1f} dof {dof}, d/truth {res.x[-1]:.4f} se/truth {se:.4f} "
        f"z {(res.x[-1] - 1) / se:.2f}, nfev {res.nfev}, cpu {time.process_time() - t0:.1f}"
    )
    print(f"  beta {par.beta:.4f} gamma {par.gamma:.4f} mu {par.mu:.4f} gains {np.round(par.gains, 4)}")
    rr = res.fun
    for k in range(m):
        n = sx[k].ybar.size
        print(f"  exp {k}: {rr[k * n : (k + 1) * n] @ rr[k * n : (k + 1) * n]:.1f}", end="")
    print()


if __name__ == "__main__":
    main(sys.argv[1:])

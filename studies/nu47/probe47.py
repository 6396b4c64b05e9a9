"""Session 47 (nu47): what the degradation stage hands its refinement, captured on tests/degradation_sim.py's
RK4 records, and the joint model ``ybar = mean_sim(theta, d)`` evaluated on it.

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu47/probe47.py NOISE DELTA_NU SEED
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent.parent.parent / "tests"))
import bouc_wen_id as bw  # noqa: E402
from bouc_wen_id.diagnosis import drift_passes as dp  # noqa: E402
from degradation_sim import records  # noqa: E402

CAP: dict[str, Any] = {}


def capture() -> None:
    orig = dp.refine

    def refine(*args: Any) -> Any:
        out = orig(*args)
        CAP["args"], CAP["out"] = args, out
        return out

    dp.refine = refine


def main(argv: list[str]) -> None:
    noise, truth, seed = float(argv[0]), float(argv[1]), int(argv[2])
    capture()
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = bw.diagnose(records(noise, seed, delta_nu=truth), candidates=["degradation"])
    cpu = time.process_time() - t0
    named = [(n.term, n.value / truth, (n.value - truth) / n.standard_error) for n in dg.named]
    print(f"noise {noise} seed {seed}: {dg.status}, named {named}, cpu {cpu:.1f}")
    f = dg.final
    print(f"  final chi2 {f.cost:.1f} dof {f.dof} p {f.p_value:.3g}; {dg.verdict[:160]}")
    if "args" in CAP:
        exps, sx, fit, data, deg, s, substeps = CAP["args"]
        deg2, fit2 = CAP["out"]
        dof = sum(a.ybar.size for a in sx) - 3 - 2 * len(sx)
        print(f"  s.y {s.y:.4g} drift d/truth {deg.value / truth:.4f} refine {deg2.value / truth:.4f}")
        print(f"  steady chi2 in {fit.cost:.1f} out {fit2.cost:.1f} dof {dof}")
        p = fit2.params
        print(f"  beta {p.beta:.4f} gamma {p.gamma:.4f} mu {p.mu:.4f} gains {np.round(p.gains, 4)}")


if __name__ == "__main__":
    main(sys.argv[1:])

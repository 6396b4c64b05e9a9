"""Session 46 (cseed46): is the plain model's adequacy p uniform on nulls of design C (unequal periods)?

    PYTHONPATH=python python studies/cseed46/calib46.py OUT.jsonl DESIGN SEED0 SEED1 [NOISE [all]]

DESIGN is ``uneq`` (review 45's C: 4 f x 2 U, 6 or 30 periods alternating), ``eq6`` or ``eq30`` (the same
frequencies and amplitudes, every experiment 6 or 30 periods: the equal-periods controls). The plant is C's
(first-order G, delay 0.131 s, gamma < 0, no effect); the noise (``white`` by default, or ``wander``) is drawn
by review 45's sim45 with seeds SEED0..SEED1-1 (``default_rng([45, seed, experiment])``). One JSON line per
seed: the plain model's p, its statistic over dof, and per experiment the residual's chi-square against the
true noise variance (sd 0.01 / periods) and against the diagnosis' own ``noise_var``. The candidates are
``offset`` alone unless ``all`` is given: on white noise the plain model's p is the same (seeds 100-107 run
both ways), the status is not the default diagnosis'; under a wander the common centre's level (alpha over
the candidates) changes the path, so the wander runs use ``all``.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402

PERIODS = {"uneq": (6, 30, 6, 30, 30, 6, 30, 6), "eq6": (6,) * 8, "eq30": (30,) * 8}


def main(argv: list[str]) -> None:
    import bouc_wen_id as bw

    out, design, s0, s1 = Path(argv[1]), argv[2], int(argv[3]), int(argv[4])
    kind = argv[5] if len(argv) > 5 else "white"
    # The plain model's p does not depend on the candidates: one candidate keeps each run to seconds.
    cands = None if len(argv) > 6 and argv[6] == "all" else ("offset",)
    p, d, _ = dv.scaled("C")
    d = replace(d, periods=PERIODS[design])
    runs = s.run(p, d)
    nz = s.Noise(kind, dv.SD)
    for seed in range(s0, s1):
        recs = s.recordings(runs, d, nz, seed)
        c0 = time.process_time()
        dg = bw.diagnose(recs, candidates=cands)
        cpu = time.process_time() - c0
        rows = []
        for e, y in zip(dg.experiments, dg.plain.outputs):
            r = np.asarray(e.ybar, dtype=float) - np.asarray(y, dtype=float)
            ss = float(r @ r)
            rows.append(
                {
                    "periods": e.periods,
                    "chi2_true": ss * e.periods / dv.SD**2,
                    "chi2_own": ss * e.periods / e.noise_var,
                    "var_ratio": e.noise_var / dv.SD**2,
                    "noise_dof": e.noise_dof,
                }
            )
        rec = {"design": design, "noise": kind, "seed": seed, "plain_p": dg.plain.p_value}
        rec |= {"stat": dg.before.statistic, "dof": dg.before.dof, "status": dg.status, "cpu": cpu}
        rec |= {"headline": dg.headline[:100], "exps": rows}
        with out.open("a") as f:
            f.write(json.dumps(rec) + "\n")
        print(design, seed, f"{dg.plain.p_value:.4f}", dg.status, flush=True)


if __name__ == "__main__":
    main(sys.argv)

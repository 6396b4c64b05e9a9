"""Does the diagnosis *name* what a detection plan promises? The README's example, drawn and diagnosed.

``bouc-wen-id plan --budget 300 --band 1 10 --max-amplitude 1 --noise 0.05 --sample-rate 100
--settle-periods 10 --detect sensor_lag=0.01`` plans sine experiments for the power of the sensor lag's
F-test; the diagnosis names the lag only if that test passes *and* the lag improves the held-out fit (leave
one experiment out). This script plans with ``--min-experiments``, scales the plan to its stated 90 % budget
(:meth:`DetectionPlan.scaled`; ``--time T``: every experiment's periods scaled to about T s instead), draws
``--draws`` recordings with the library's simulator (the demo plant plus the lag; seeded white noise, seed
``1000 k + i`` for draw k, experiment i) and diagnoses each: the lag's first-step F-test passing at its
level, the lag named, any other physics named ("wrong"). Also prints each fold's refitted non-centrality
(the design less one experiment), what the held-out test leans on. docs/power.md, "Plans for naming".

Usage: ``python benches/plan_naming.py [--draws 12] [--min-experiments 3] [--time T]``
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))

LAB: dict[str, Any] = dict(
    band=(1.0, 10.0), max_amplitude=1.0, noise_sd=0.05, sample_rate=100.0, settle_periods=10
)
TERM, SIZE, BUDGET = "sensor_lag", 0.01, 300.0


def _at_time(exps: list[Any], target: float) -> list[Any]:
    """``exps`` with every experiment's periods scaled by one factor so the test time is about ``target``."""
    settle = sum(e.duration - e.periods * 2.0 * math.pi / e.frequency for e in exps)
    run = sum(e.periods * 2.0 * math.pi / e.frequency for e in exps)
    f = max((target - settle) / run, 1e-9)
    return [replace(e, periods=max(1, math.ceil(f * e.periods))) for e in exps]


def main(argv: Optional[list[str]] = None) -> int:
    import bouc_wen_id as bw
    from bouc_wen_id.planning import detection_power
    from bouc_wen_id.terms import TERMS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=12)
    ap.add_argument("--min-experiments", type=int, default=3)
    ap.add_argument("--time", type=float, default=None, help="scale the plan to about this test time, s")
    a = ap.parse_args(argv)
    prior = bw.demo_plant()
    plan = bw.plan_detection(prior, BUDGET, {TERM: SIZE}, min_experiments=a.min_experiments, **LAB)
    exps = _at_time(list(plan.experiments), a.time) if a.time else list(plan.scaled(0.9))
    noise = float(LAB["noise_sd"])
    pred = detection_power(prior, exps, TERM, SIZE, noise_sd=noise)
    print(
        f"min_experiments={a.min_experiments}: {[(round(e.frequency, 2), e.periods) for e in exps]} "
        f"time {pred.total_time:.0f} s, F-power {pred.power:.3f} (lam refit {pred.lam:.1f})"
    )
    for j in range(len(exps)):
        if len(exps) > 1:
            fold = detection_power(prior, exps[:j] + exps[j + 1 :], TERM, SIZE, noise_sd=noise)
            print(
                f"  fold without experiment {j}: lam refit {fold.lam:.2f} (first order {fold.lam_linear:.2f})"
            )
    truth = bw.WienerPlant(prior.linear, prior.hysteresis, (TERMS[TERM](SIZE),))
    f_k = n_k = wrong = 0
    for k in range(a.draws):
        recs = []
        for i, e in enumerate(exps):
            recs += bw.simulate(truth, e.plan(noise, seed=1000 * k + i))
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        st = d.steps[0] if d.steps else None
        level = (0.5 if st is not None and st.targeted else 1.0) * 0.05
        fp = st is not None and any(
            t.term == TERM and math.isfinite(t.p_adjusted) and t.p_adjusted < level for t in st.trials
        )
        other = [t for t in d.named_terms if t != TERM]
        f_k += fp
        n_k += TERM in d.named_terms
        wrong += bool(other)
        print(f"  draw {k}: F {fp}, {d.status}, named {d.named_terms} ({time.perf_counter() - t0:.1f} s)")
    print(f"F passed {f_k}/{a.draws}, named {n_k}/{a.draws}, wrong physics named {wrong}/{a.draws}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Review 48's check: Radau's resampled dense output against a fixed-step RK4 (64 steps a sample) of the same
right-hand side; a play case against RK4 in time (the Radau path runs the element along the played x).

    PYTHONPATH=python python studies/review48/check48.py > studies/review48/check48.txt

Per config: the plain plant on its first and last experiments; on configs A and B (the delayed and the
third-order G) each state-carrying effect at 10 times its driver's first value on the first experiment.
Printed: max |dy| over the recorded samples (in w_u and in the config's noise sd) and the largest over every
sample, settling included.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import drive48 as dv  # noqa: E402
import sim48 as s  # noqa: E402

EFFECTS = ("play", "lag", "delta", "pinch", "nu", "eta", "rho", "drift")


def gap(p: s.Plant, d: s.Design, idx: list[int]) -> tuple[float, float]:
    worst_rec, worst_all = 0.0, 0.0
    for i in idx:
        a = s.output(p, d, i, s.states(p, d, i))[2]
        b = s.output(p, d, i, s.rk4_states(p, d, i))[2]
        cut = d.settles[i] * d.samples
        worst_rec = max(worst_rec, float(np.max(np.abs(a[cut:] - b[cut:]))))
        worst_all = max(worst_all, float(np.max(np.abs(a - b))))
    return worst_rec, worst_all


def main() -> None:
    print("config effect value: max|dy| recorded (w_u, noise sd) | max|dy| all samples (w_u)")
    for cfg in dv.CONFIGS:
        p, d, nn = dv.base(cfg)
        sd = dv.noise_sd(nn, dv.plain_of(cfg), p.w_u)[2]
        rec, every = gap(p, d, [0, len(d.omegas) - 1])
        print(f"{cfg} plain: {rec:.2e} ({rec / sd:.3f} sd) | {every:.2e}", flush=True)
        for eff in EFFECTS if cfg in "AB" else ():
            v = 10 * dv.start(eff, p, d)
            v = min(v, 0.9) if eff == "pinch" else v
            rec, every = gap(p.with_(dv.KEY[eff], v), d, [0])
            print(f"{cfg} {eff} {v:.3g}: {rec:.2e} ({rec / sd:.3f} sd) | {every:.2e}", flush=True)


if __name__ == "__main__":
    main()

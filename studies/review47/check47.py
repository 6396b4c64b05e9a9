"""Review 47: the trapezoidal simulator against a fine RK4 of the same right-hand side (64 steps a sample).

    PYTHONPATH=python python studies/review47/check47.py > studies/review47/check47.txt

Per config and a few effects (10 times the driver's first value; pinching 0.5): max |dy| / w_u over every
sample of every experiment (noise-free, settling included), and the RMS of dy over the recorded samples in the
driver's size units (sd / sqrt(periods)): what the integration error would weigh as an effect.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import drive47 as dv  # noqa: E402
import sim47 as s  # noqa: E402

EFFECTS = ("null", "nu", "eta", "pinch", "delta", "rate", "dahl2")


def one(cfg: str, eff: str) -> str:
    sy, pl, _ = dv.base(cfg)
    if eff != "null":
        key, v = dv.start(eff, sy, pl)
        sy = s.with_effect(sy, key, 10.0 * v if eff != "pinch" else 0.5)
        if eff == "rate":
            sy = s.with_effect(sy, "vref", float(max(pl.amps) * max(pl.omegas)))
        if eff == "dahl2":
            sy = s.with_effect(sy, "dahl_fc", 0.05 * sy.el.w_u)
    c0 = time.process_time()
    trap = s.simulate(sy, pl)
    fine = [s.measured(sy, pl, i, s.trajectory(sy, pl, i, check=True, sub=64)) for i in range(len(pl.omegas))]
    worst = max(float(np.max(np.abs(a[2] - b[2]))) for a, b in zip(trap, fine))
    as_size = dv.size(trap, fine, pl, dv.SD * sy.el.w_u)
    return (
        f"{cfg} {eff:6s} max|dy|/w_u {worst / sy.el.w_u:.2e}, RMS over the recorded samples in size units "
        f"{as_size:.2f}  ({time.process_time() - c0:.1f} s cpu)"
    )


def main() -> None:
    for cfg in dv.CONFIGS:
        for eff in EFFECTS if cfg in "JKM" else ("null",):
            print(one(cfg, eff), flush=True)


if __name__ == "__main__":
    main()

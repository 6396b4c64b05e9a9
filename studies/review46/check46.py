"""Review 46: sim46 (VODE, Adams, rtol 1e-9) against a fixed-step RK4 of the same right-hand side.

    PYTHONPATH=python python studies/review46/check46.py > studies/review46/check46.txt

Per config (its G, element and scaled amplitudes; the first two experiments, 3 settling and 2 recorded
periods) and per effect: max |y_vode - y_rk4| / w_u, RK4 at 32 steps per sample, and the CPU seconds.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402

#: (label, the effect set, its value: play and slack in units of w_u); nu and eta are set together.
EFFECTS = [("plain", "", 0.0), ("play", "play", 0.2), ("slack", "slack", 0.2), ("nu+eta", "nu eta", 0.05)]
EFFECTS += [("pinch", "pinch", 0.6), ("delta", "delta", 0.2), ("rate", "rate", 1.0), ("lag", "lag", 0.02)]
EFFECTS += [("pi_u", "pi_u", 0.05)]


def main() -> None:
    for cfg in dv.CONFIGS:
        sy, pl, _ = dv.base(cfg)
        pl = replace(pl, omegas=pl.omegas[:2], amps=pl.amps[:2], periods=2, settle=3)
        wu = sy.el.w_u
        for name, keys, v in EFFECTS:
            q = sy
            for k in keys.split():
                q = s.with_effect(q, k, v * (wu if k in ("play", "slack") else 1.0))
            errs, c0 = [], time.process_time()
            for i in range(2):
                y1 = s.measured(q, pl, i, s.trajectory(q, pl, i))[2]
                y2 = s.measured(q, pl, i, s.rk4(q, pl, i))[2]
                errs.append(float(np.max(np.abs(y1 - y2))))
            print(
                f"{cfg} {name:7s} max|dy|/w_u = {max(errs) / wu:.1e}  ({time.process_time() - c0:.1f} s cpu)"
            )


if __name__ == "__main__":
    main()

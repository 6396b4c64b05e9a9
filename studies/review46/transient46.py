"""Review 46: is the diagnosis's "still transient" true? The noise-free sim46 output, per experiment.

    PYTHONPATH=python python studies/review46/transient46.py E H

For each experiment: the RMS over a period of (recorded period k minus the last period), k = 1..3, in noise
sd, and in the noise sd of a period's mean over its samples (sd / sqrt(P)); and the lightly damped mode's
decay factor per period exp(-zeta wn T) against which the diagnosis's "falls by a factor ... a period" reads.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402

MODES = {"iso": (4.0, 0.05), "iso5": (5.0, 0.05)}


def main(cfgs: list[str]) -> None:
    for cfg in cfgs:
        sy, pl, _ = dv.base(cfg)
        wn, zeta = MODES.get(dv.CONFIGS[cfg][1], (float("nan"), float("nan")))
        for i, (_, _, y) in enumerate(s.simulate(sy, pl)):
            per = y[pl.settle * pl.samples :].reshape(pl.periods, pl.samples)
            rms = [float(np.sqrt(np.mean((per[k] - per[-1]) ** 2))) for k in range(3)]
            decay = math.exp(-zeta * wn * 2 * math.pi / pl.omegas[i])
            cells = ", ".join(f"{r / dv.SD:.3f} sd ({r / (dv.SD / math.sqrt(pl.samples)):.1f})" for r in rms)
            print(
                f"{cfg} x{i} w {pl.omegas[i]:g} U {pl.amps[i]:.3g}: period 1-3 minus last: {cells}; "
                f"mode decay/period {decay:.2f}"
            )


if __name__ == "__main__":
    main(sys.argv[1:])

"""Review 45, failure 1's cause: under pink (1/f) noise the mean of an experiment's 8 analysed periods
scatters more than the period-to-period spread of its period means says (the se that a DC test would take).

    python studies/review45/pink_dc45.py

Config B's record: 23 periods of 200 samples, the last 8 analysed; 2000 draws of sim45's pink noise.
Prints the ratio var(8-period mean) / mean(sample var of the period means / 8); 1 for white noise.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import sim45 as s  # noqa: E402

for kind in ("white", "pink"):
    rng = np.random.default_rng([45, 7])
    means, se2 = [], []
    for _ in range(2000):
        e = s.noise(s.Noise(kind, 0.01), 23 * 200, 0.01, rng)[15 * 200 :].reshape(8, 200).mean(axis=1)
        means.append(e.mean())
        se2.append(e.var(ddof=1) / 8)
    print(f"{kind}: var(record DC) / (period-mean spread / 8) = {np.var(means) / np.mean(se2):.2f}")

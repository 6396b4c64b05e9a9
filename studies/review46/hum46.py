"""Review 46: where does config G's null false alarm come from? The 50 Hz hum, per frequency.

    PYTHONPATH=python python studies/review46/hum46.py [SEED]

G's null (pure gain, mu = 4, hum: white sd plus a 50 Hz sine of RMS sd) diagnosed on its 2 rad/s records
only, on its 8 rad/s records only, and on all four with the hum's frequency moved to 47.3 Hz; per run the
status, the plain p and whether a disturbance line is said. At 2 rad/s 50 Hz is 157.08 cycles a period (0.08
from a harmonic), at 8 rad/s 39.27.
"""

from __future__ import annotations

import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402


def one(label: str, recs: list[Any]) -> None:
    import bouc_wen_id as bw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dg = bw.diagnose(recs)
    said = any("not locked to the input" in x for x in [*dg.details, *dg.notes])
    print(
        json.dumps(
            {
                "run": label,
                "status": dg.status,
                "plain_p": dg.plain.p_value,
                "hum_said": said,
                "headline": dg.headline,
            }
        )
    )


def main(seed: int) -> None:
    import tempfile

    import bouc_wen_id as bw

    sy, pl, nn = dv.base("G")
    runs = s.simulate(sy, pl)
    recs = s.recordings(runs, pl, nn, dv.SD, seed)
    one("all four, as Recordings (drive46)", recs)
    one(
        "all four, Recordings with settle_periods = 0",
        [bw.Recording(r.t, r.u, r.y, r.amplitude, r.frequency) for r in recs],
    )
    with tempfile.TemporaryDirectory() as d:  # as the command line reads them
        dv.write_csv(recs, d)
        one("all four, the CSV files through bw.load", bw.load(d))
    one("w 2 only", [r for r, w in zip(recs, pl.omegas) if w == 2.0])
    one("w 8 only", [r for r, w in zip(recs, pl.omegas) if w == 8.0])
    moved = []
    for i, (t, u, y) in enumerate(runs):  # the same draws, the hum at 47.3 Hz
        rng = np.random.default_rng([46, seed, i])
        w = rng.normal(0.0, dv.SD, t.size)
        hum = dv.SD * math.sqrt(2.0) * np.sin(2 * math.pi * 47.3 * t + rng.uniform(0.0, 2.0 * math.pi))
        moved.append((t, u, y + w + hum))
    one(
        "hum at 47.3 Hz",
        [
            bw.Recording(
                t - 0.5 * math.pi / pl.omegas[i], u, y, pl.amps[i], pl.omegas[i], settle_periods=pl.settle
            )
            for i, (t, u, y) in enumerate(moved)
        ],
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 4)

"""Session 46: replay one bench case of ``benches/diagnosis.py`` from its cache and print what was said.

Usage: ``python studies/bench46/replay46.py CACHE KIND NAME PLACE SIZE SEED [SEED ...]`` (e.g. ``bcache
library sensor_lag "" 10 35004``). Per seed: the plant, the true value, the diagnosis's summary (verdict,
selection steps with each candidate's F, p and law p), the sensor-lag detection limits, the oracle's cause.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))

import bouc_wen_id as bw  # noqa: E402
import generator as gen  # noqa: E402
import oracle  # noqa: E402


def main(argv: list[str]) -> None:
    cache, kind, name, place, size = Path(argv[0]), argv[1], argv[2], argv[3], float(argv[4])
    for seed in (int(s) for s in argv[5:]):
        case = gen.cached_case(kind, name, place, size, seed, cache)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(case.recordings)
        print(f"===== seed {seed}: shape {case.shape}, value {case.value:.6g}, achieved {case.achieved:.3g}")
        print(d.summary())
        for lim in d.limits:
            if "lag" in str(lim.term):
                print("limit:", lim)
        row = dict(oracle.truth_lr(d, "sensor_lag" if name == "sensor_lag" else name))
        row["cause"] = oracle.cause(row, float(d.settings.get("alpha", 0.05)))
        print("oracle:", {k: row[k] for k in sorted(row)})


if __name__ == "__main__":
    main(sys.argv[1:])

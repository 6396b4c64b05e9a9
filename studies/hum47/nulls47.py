"""Lines the search reports on review 46's nulls, per config: AR(2) E and H (no line), G (50 Hz hum).

    PYTHONPATH=python python studies/hum47/nulls47.py [SEEDS] [CONFIGS] [load]

``load``: the recordings written to CSV files and read back by ``bw.load`` (Measurements, as the command
line reads them) before the search.

Runs only :func:`bouc_wen_id.diagnosis.lines.removed` (the search and the fit), as hum46's ``nulls.py``, on
more seeds; one JSON line per config: how many diagnoses report a line, which seeds, the frequencies said.
"""

from __future__ import annotations

import json
import re
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402
from bouc_wen_id import load  # noqa: E402
from bouc_wen_id.diagnosis import lines  # noqa: E402


def _items(recs: list[object], files: bool) -> object:
    if not files:
        return recs
    with tempfile.TemporaryDirectory() as d:
        dv.write_csv(recs, d)
        return load(d)


def main(seeds: int, configs: list[str], files: bool = False) -> None:
    for cfg in configs:
        sy, pl, nn = dv.base(cfg)
        runs = s.simulate(sy, pl)
        hit, freqs, cpu = [], [], 0.0
        for seed in range(1, seeds + 1):
            recs = _items(s.recordings(runs, pl, nn, dv.SD, seed), files)
            t0 = time.process_time()
            _out, notes = lines.removed(recs)
            cpu += time.process_time() - t0
            if notes:
                hit.append(seed)
            freqs += [float(m) for n in notes for m in re.findall(r"sinusoid at ([0-9.e+-]+) cycles", n)]
        out = {
            "config": cfg,
            "files": files,
            "noise": nn,
            "seeds": seeds,
            "with a line": len(hit),
            "which": hit,
        }
        print(json.dumps({**out, "freqs": freqs, "cpu": round(cpu, 2)}), flush=True)


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 16
    main(n, sys.argv[2].split(",") if len(sys.argv) > 2 else ["H", "E", "G"], "load" in sys.argv[3:])

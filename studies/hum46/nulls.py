"""Lines the search reports on review 46's nulls (no hum: white Gw, AR(2) E and H; hum: G), per seed.

    PYTHONPATH=python python studies/hum46/nulls.py [SEEDS]

Runs only :func:`bouc_wen_id.diagnosis.lines.removed` (the search and the fit), not the diagnosis; one JSON
line per config: how many of the seeds' diagnoses report a line, and the frequencies said.
"""

from __future__ import annotations

import json
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402
from bouc_wen_id.diagnosis import lines  # noqa: E402


def main(seeds: int) -> None:
    for cfg in ("Gw", "E", "H", "G"):
        sy, pl, nn = dv.base(cfg)
        runs = s.simulate(sy, pl)
        said, freqs, cpu = 0, [], 0.0
        for seed in range(1, seeds + 1):
            recs = s.recordings(runs, pl, nn, dv.SD, seed)
            t0 = time.process_time()
            _out, notes = lines.removed(recs)
            cpu += time.process_time() - t0
            said += bool(notes)
            freqs += [float(m) for n in notes for m in re.findall(r"sinusoid at ([0-9.e+-]+) cycles", n)]
        out = {"config": cfg, "noise": nn, "seeds": seeds, "with a line": said, "freqs": freqs, "cpu": cpu}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 8)

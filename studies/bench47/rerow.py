"""Session 47: rerun some cases of a saved ``benches/diagnosis.py --json`` run on the current code (e.g. after
a scoring fix) and write the run back with those rows replaced and its table re-made.

Usage: ``python studies/bench47/rerow.py RUN.json CACHE SEED [SEED ...]``. Each replaced row keeps its job
(kind, term, place, size, seed) and gains ``"rerun": "bench47"``; the table is printed.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))

import diagnosis as bench  # noqa: E402


def main(argv: list[str]) -> None:
    path, cache, seeds = Path(argv[0]), Path(argv[1]), {int(s) for s in argv[2:]}
    run = json.loads(path.read_text())
    rows = run["rows"]
    for k, r in enumerate(rows):
        if r["seed"] in seeds:
            job = (r["kind"], r["term"], r["place"], float(r["size"]), int(r["seed"]))
            rows[k] = bench.run_new_case(job, cache) | {"rerun": "bench47"}
    run["table"] = bench.summarise(rows)
    path.write_text(json.dumps(run, indent=1, default=float))
    bench.print_table(run["table"])


if __name__ == "__main__":
    main(sys.argv[1:])

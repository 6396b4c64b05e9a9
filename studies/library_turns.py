"""A few rows of the library bench (``benches/diagnosis.py``'s generator and cases) with each case's CPU, for
comparing two versions of the package at the same load (docs/diagnosis-speed.md, session 46).

Two runs of this script, one per version (``PYTHONPATH`` naming each one's ``python/``), take turns case by
case through a lock file, so only one diagnoses at a time and both see the same load. One JSON line per case
(the bench's row plus ``cpu``, ``time.process_time`` of the case), in a fixed order that reaches every row
early. Compare the two files by their ``(kind, term, place, size, seed)``.

Usage: ``OMP_NUM_THREADS=1 PYTHONPATH=python python studies/library_turns.py out.jsonl [--sizes 10,30]
[--cases 6] [--lock /tmp/turns.lock] [--cache DIR]``.
"""

from __future__ import annotations

import argparse
import fcntl
import json
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "benches"))

#: The rows: viscous damping at both places, dry friction on x, strength degradation (and the nulls).
ROWS = (("viscous", "u"), ("viscous", "x"), ("coulomb", "x"), ("degradation", ""))


def main(argv: list[str] | None = None) -> int:
    import diagnosis as bench

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--sizes", default="10,30")
    ap.add_argument("--cases", type=int, default=6)
    ap.add_argument("--lock", type=Path, default=Path("/tmp/library_turns.lock"))
    ap.add_argument("--cache", type=Path, default=None)
    args = ap.parse_args(argv)
    sizes = {float(v) for v in args.sizes.split(",")}
    ns = argparse.Namespace(cases=args.cases, null=args.cases, seed=0, quick=False)
    jobs = [j for j in bench.new_jobs(ns) if j[0] == "null" or ((j[1], j[2]) in ROWS and j[3] in sizes)]
    jobs.sort(key=lambda j: (j[4] % 1000, j[1] or "", j[2], j[3]))  # every row early in a partial run
    with args.out.open("w") as f, args.lock.open("w") as lock:
        for j in jobs:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                c = time.process_time()
                r = bench.run_new_case(j, cache=args.cache)
                r["cpu"] = time.process_time() - c
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)
            time.sleep(0.2)  # the other run's turn
            f.write(json.dumps(r, default=float) + "\n")
            f.flush()
            print(j, r.get("status"), r.get("named"), f"{r['cpu']:.1f} s", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Session 48: one bench row's run against an earlier run of the same cases (``benches/diagnosis.py
--json``): how many statuses and verdicts are identical, each case that changed (both verdicts' starts),
and the median CPU seconds per diagnosis of each run (``cpu_seconds``: ``time.process_time``).

Usage: ``python studies/bench48/compare.py OLD.json NEW.json``.
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path
from typing import Any


def _rows(path: str) -> dict[tuple[Any, ...], dict[str, Any]]:
    rows = json.loads(Path(path).read_text())["rows"]
    return {(r["term"], r.get("place", ""), r["size"], r["seed"]): r for r in rows}


def _cpu(rows: list[dict[str, Any]]) -> str:
    got = [float(r["cpu_seconds"]) for r in rows if "cpu_seconds" in r]
    return f"{statistics.median(got):.2f} s (sum {sum(got):.0f} s)" if got else "not measured"


def main(argv: list[str]) -> None:
    old, new = _rows(argv[0]), _rows(argv[1])
    both = [k for k in new if k in old]
    status = sum(old[k].get("status") == new[k].get("status") for k in both)
    verdict = sum(old[k].get("verdict") == new[k].get("verdict") for k in both)
    print(f"{len(both)} cases in both runs: status identical {status}, verdict identical {verdict}")
    cpu_old, cpu_new = _cpu([old[k] for k in both]), _cpu([new[k] for k in both])
    print(f"CPU per diagnosis, median: old {cpu_old}, new {cpu_new}")
    for k in both:
        a, b = old[k], new[k]
        if a.get("verdict") != b.get("verdict"):
            print(f"- seed {k[3]}: {a.get('status')} -> {b.get('status')}")
            print(f"    old: {str(a.get('verdict', a.get('error', '')))[:240]}")
            print(f"    new: {str(b.get('verdict', b.get('error', '')))[:240]}")


if __name__ == "__main__":
    main(sys.argv[1:])

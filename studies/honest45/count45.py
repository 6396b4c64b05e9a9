"""Counts of nulls45.py's rows: per group (own nulls, review 44's nulls, controls), how many sets had a record
left out, a drift clause, a drift said as a fact, a status other than adequate / explained.

    python studies/honest45/count45.py OUT.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict


def main(path: str) -> None:
    groups: dict[str, list[dict[str, object]]] = defaultdict(list)
    for line in open(path):
        row = json.loads(line)
        kind = str(row["id"]).split("-")[0]
        groups[kind].append(row)
    for kind, rows in groups.items():
        n = len(rows)
        left = sum(bool(r["left_out"]) for r in rows)
        said = sum(bool(r["drift_said"]) for r in rows)
        fact = sum(bool(r["drifts_as_fact"]) for r in rows)
        off = sum(r["status"] not in ("adequate", "explained") for r in rows)
        print(
            f"{kind:7s} n={n:2d} left_out={left} drift_clause={said} drifts_as_fact={fact} status_other={off}"
        )


if __name__ == "__main__":
    main(sys.argv[1])

"""Summary of studies/backlash48's runs (the JSON lines of output48.py): per group, named terms, status,
play@output within 3 se, CPU seconds per diagnosis.

    python studies/backlash48/summarise48.py /tmp/bl48/out.jsonl /tmp/bl48/play.jsonl /tmp/bl48/null.jsonl
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import Counter


def main() -> None:
    for path in sys.argv[1:]:
        rows = [json.loads(line) for line in open(path)]
        names = Counter(",".join(sorted(r["named"])) or "-" for r in rows)
        status = Counter(r["status"] for r in rows)
        pair = sum(any("dwell after each reversal" in w for w in r["readings"]) for r in rows)
        within = [r["within_3se"] for r in rows if "within_3se" in r]
        cpu = [r["cpu"] for r in rows]
        print(
            f"{path}: {len(rows)} cases; named {dict(names)}; status {dict(status)}; the other play offered "
            f"{pair}/{len(rows)}; play@output within 3 se {sum(within)}/{len(within)}; CPU/diagnosis median "
            f"{statistics.median(cpu):.2f} s (mean {statistics.mean(cpu):.2f})"
        )


if __name__ == "__main__":
    main()

"""Before/after of two saved diagnosis bench runs (benches/diagnosis.py --json) on the same cached cases.

Per case (size, seed) the status, named terms, alternatives, right place and wrong name must agree; for
the "adequate" verdicts of the after run, how many quote their limits at 90 % power and the adequacy test's
resolution (diagnosis/resolution.py).

Usage: ``python studies/power_compare.py BEFORE.json AFTER.json [BEFORE2.json AFTER2.json ...]``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any


def _key(r: dict[str, Any]) -> tuple[Any, ...]:
    return (
        r.get("status"),
        tuple(r.get("named", [])),
        tuple(r.get("alternatives", [])),
        r.get("right_place"),
        r.get("wrong"),
    )


def compare(before: Path, after: Path) -> int:
    """Print the comparison; the number of cases that differ."""
    a = {(r["size"], r["seed"]): r for r in json.loads(before.read_text())["rows"]}
    b = {(r["size"], r["seed"]): r for r in json.loads(after.read_text())["rows"]}
    common = sorted(set(a) & set(b))
    diff = [k for k in common if _key(a[k]) != _key(b[k])]
    for k in diff:
        print(f"  differs {k}: {_key(a[k])} -> {_key(b[k])}")
    ad = [b[k] for k in common if b[k].get("status") == "adequate"]
    q90 = sum("90 % power" in r["verdict"] for r in ad)
    res = sum("goes unseen below an RMS" in r["verdict"] for r in ad)
    print(
        f"{after.stem}: {len(common) - len(diff)} of {len(common)} cases alike; adequate {len(ad)}, "
        f"quoting 90 % limits {q90}, the adequacy test's resolution {res}"
    )
    return len(diff)


def main() -> None:
    paths = [Path(p) for p in sys.argv[1:]]
    if len(paths) < 2 or len(paths) % 2:
        raise SystemExit(__doc__)
    bad = sum(compare(paths[i], paths[i + 1]) for i in range(0, len(paths), 2))
    raise SystemExit(1 if bad else 0)


if __name__ == "__main__":
    main()

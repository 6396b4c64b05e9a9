"""Session 48: strength degradation's named value against the generator's truth, per case of a bench run
(``benches/diagnosis.py --json``; the value and its standard error read from the verdict's
``delta_nu = V ± SE``): ratio to the truth and z = (V - truth) / SE, and the medians per size.

Usage: ``python studies/bench48/nu_values.py RUN.json``.
"""

from __future__ import annotations

import json
import re
import statistics
import sys
from pathlib import Path

VALUE = re.compile(r"delta_nu = ([-+0-9.eE]+) ± ([-+0-9.eE]+)")


def main(argv: list[str]) -> None:
    rows = json.loads(Path(argv[0]).read_text())["rows"]
    per: dict[float, list[tuple[float, float]]] = {}
    for r in rows:
        m = VALUE.search(str(r.get("verdict", "")))
        if m is None:
            print(f"{r['size']:g}x {r['seed']}: {r.get('status')}, no delta_nu in the verdict")
            continue
        v, se = float(m.group(1)), float(m.group(2))
        ratio, z = v / r["value"], (v - r["value"]) / se
        per.setdefault(r["size"], []).append((ratio, z))
        print(f"{r['size']:g}x {r['seed']} {r['shape']}: {r['status']}, ratio {ratio:.4f}, z {z:+.2f}")
    for size, got in sorted(per.items()):
        ratios, zs = [a for a, _ in got], [b for _, b in got]
        print(
            f"{size:g}x: {len(got)} named; ratio median {statistics.median(ratios):.4f} "
            f"({min(ratios):.4f}-{max(ratios):.4f}); z median {statistics.median(zs):+.2f} "
            f"({min(zs):+.2f} to {max(zs):+.2f}); |z| > 3 in {sum(abs(z) > 3 for z in zs)}"
        )


if __name__ == "__main__":
    main(sys.argv[1:])

"""Session 47: one line per case of saved ``benches/diagnosis.py --json`` runs (status, names, what the plain
model cannot absorb and the global test's power there, the oracle's cause, CPU seconds, the verdict's start).

Usage: ``python studies/bench47/cases.py RUN.json [RUN.json ...] [--misses]`` (``--misses``: only cases
that are not good for their row: a library row's truth not right at its place or a wrong name; an outside
row's not "unexplained" or family-caveated; a null not "adequate").
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any


def good(r: dict[str, Any]) -> bool:
    if r["kind"] == "null":
        return r.get("status") == "adequate"
    if r.get("scored_as") in ("library", "structure"):
        return bool(r.get("right_place")) and not r.get("wrong")
    return (bool(r.get("unexplained")) or bool(r.get("family"))) and not r.get("wrong")


def line(r: dict[str, Any]) -> str:
    unabs = r.get("unabsorbed")
    pw = r.get("global_power", float("nan"))
    extra = f" unabs {unabs:.3f} sd pwG {pw:.2f}" if unabs is not None else ""
    flags = " ".join(k for k in ("wrong", "family") if r.get(k))
    return (
        f"{r['term'] or 'null'} {r['size']:g}x {r['seed']} {r.get('shape', '')}: {r.get('status')} {flags} "
        f"{r.get('named', [])}{extra} cause '{r.get('cause', '')}' "
        f"cpu {r.get('cpu_seconds', float('nan')):.1f} s | {str(r.get('verdict', r.get('error', '')))[:160]}"
    )


def main(argv: list[str]) -> None:
    only_misses = "--misses" in argv
    for path in (Path(a) for a in argv if a != "--misses"):
        for r in json.loads(path.read_text())["rows"]:
            if not (only_misses and good(r)):
                print(line(r))


if __name__ == "__main__":
    main(sys.argv[1:])

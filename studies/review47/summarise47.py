"""Review 47: classify each case of results47.jsonl (review 45's outcome words) and print the tables.

python studies/review47/summarise47.py studies/review47/results47.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parent.parent / "review45"))
from drive47 import CONFIGS, TRUTH_TERM  # noqa: E402
from summarise45 import caveated, cell  # noqa: E402

#: Outside physics whose nearest library relative is a fair reading (Dahl exponent 2 read as Dahl).
NEAR = {"dahl2": ("dahl", "dahl_sigma")}


def mu_said(r: dict[str, Any]) -> bool:
    """The verdict says the loops may be softer than mu = 1 allows (true on the mu = 0.75 plant)."""
    return r.get("bw") == "mu.75" and any("softer than mu = 1" in x for x in [r["headline"], *r["details"]])


def _outcome(r: dict[str, Any]) -> str:
    eff, st = r["effect"], r["status"]
    names = [n["term"] for n in r["named"]]
    if eff == "null":
        quiet = {"adequate": "ok-null"}.get(st, "false alarm")
        loud = "FALSE NAME" if st == "explained" and not caveated(r) else "false name (caveated)"
        return loud if names else quiet
    want = TRUTH_TERM[eff]
    if want is None:
        if names and set(names) <= set(NEAR.get(eff, ())):
            return "near (same family)" + ("" if st == "explained" else f" [{st}]")
        if names and st == "explained":
            return "WRONG" if not caveated(r) else "named with caveat"
        return "partly" if names else st
    if want in names + r["alternatives"]:
        z = next((n.get("z") for n in r["named"] if n["term"] == want), "absent")
        word = "right as alternative" if z == "absent" else "right"
        word += " (value off)" if isinstance(z, float) and abs(z) > 3 else ""
        word += "" if st == "explained" else f" [{st}]"
        others = [n for n in names if n != want]
        return word + (" + extra " + ",".join(others) if others else "")
    if names:
        return "WRONG" if st == "explained" and not caveated(r) else "wrong (caveated)"
    return "missed"


def outcome(r: dict[str, Any]) -> str:
    if "error" in r:
        return "timeout" if r["error"].startswith("timeout") else "error"
    oc = _outcome(r)
    return oc + " (mu < 1 said)" if mu_said(r) else oc


def per_case(rows: list[dict[str, Any]]) -> None:
    print("| case | size | outcome | verdict (first line, cut) | named: value ± se (truth, z) | s (cpu) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        said = " ".join((r.get("headline") or r.get("error", "")).replace("|", "/").split())
        said = said[:107] + "..." if len(said) > 110 else said
        cells = [r["id"], f"{r.get('size', 0):.0f}", outcome(r), said, cell(r)]
        cells.append(f"{r.get('seconds', 0):.0f} ({r.get('cpu_seconds', 0):.0f})")
        print("| " + " | ".join(cells) + " |")


def kind(r: dict[str, Any]) -> str:
    return "null" if r["effect"] == "null" else ("lib" if TRUTH_TERM[r["effect"]] else "out")


def row(rs: list[dict[str, Any]]) -> list[str]:
    """A config's cells: library terms right, within 3 se, wrong confident names, outside physics, nulls
    adequate, errors, seconds (median, max)."""
    got = [(r, outcome(r), kind(r)) for r in rs]
    right = [r for r, o, k in got if k == "lib" and o.startswith("right")]
    z = [n.get("z") for r in right for n in r["named"] if n["term"] == TRUTH_TERM[r["effect"]]]
    z = [v for v in z if v is not None]
    nulls = [o for _, o, k in got if k == "null"]
    wall = sorted(r.get("seconds") or 0.0 for r in rs)
    return [
        f"{len(right)} / {sum(k == 'lib' for _, _, k in got)}",
        f"{sum(abs(v) <= 3 for v in z)} / {len(z)}",
        str(sum(o.startswith(("WRONG", "FALSE NAME")) for _, o, _ in got)),
        ", ".join(f"{r['effect']} {o}" for r, o, k in got if k == "out") or "-",
        f"{sum(o.startswith('ok-null') for o in nulls)} / {len(nulls)}",
        str(sum(o in ("error", "timeout") for _, o, _ in got)),
        f"{wall[len(wall) // 2]:.0f}, {wall[-1]:.0f}",
    ]


def main(src: str) -> None:
    rows = [json.loads(x) for x in Path(src).read_text().splitlines() if x.strip()]
    per_case(rows)
    cols = "config|library terms right|value within 3 se|wrong confident names|outside physics|nulls adequate"
    print(f"\n| {cols.replace('|', ' | ')} | errors / timeouts | s median, max |\n" + "|---" * 8 + "|")
    for cfg, parts in CONFIGS.items():
        if rs := [r for r in rows if r["config"] == cfg]:
            print(f"| {cfg} {'/'.join(parts)} | " + " | ".join(row(rs)) + " |")
    tally = Counter(outcome(r) for r in rows)
    print("\noutcomes:", ", ".join(f"{k} {n}" for k, n in sorted(tally.items())))


if __name__ == "__main__":
    main(sys.argv[1])

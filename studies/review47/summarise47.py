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
        if names:
            return "FALSE NAME" if st == "explained" and not caveated(r) else "false name (caveated)"
        return "ok-null" if st == "adequate" else "false alarm"
    want = TRUTH_TERM[eff]
    if want is None:
        if names and set(names) <= set(NEAR.get(eff, ())):
            return "near (same family)" + ("" if st == "explained" else f" [{st}]")
        if names and st == "explained":
            return "WRONG" if not caveated(r) else "named with caveat"
        return "partly" if names else st
    if want in names or want in r["alternatives"]:
        zs = [n.get("z") for n in r["named"] if n["term"] == want]
        parts = ["right" if zs else "right as alternative"]
        parts += [" (value off)"] if zs and zs[0] is not None and abs(zs[0]) > 3 else []
        parts += [] if st == "explained" else [f" [{st}]"]
        extra = ",".join(n for n in names if n != want)
        return "".join(parts) + (f" + extra {extra}" if extra else "")
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
        head = (r.get("headline") or r.get("error", "")).replace("|", "/").replace("\n", " ")
        head = head if len(head) <= 110 else head[:107] + "..."
        secs = f"{r.get('seconds', 0):.0f} ({r.get('cpu_seconds', 0):.0f})"
        print(f"| {r['id']} | {r.get('size', 0):.0f} | {outcome(r)} | {head} | {cell(r)} | {secs} |")


def group_cells(rs: list[dict[str, Any]]) -> list[str]:
    oc = {r["id"]: outcome(r) for r in rs}
    kind = {
        r["id"]: "null" if r["effect"] == "null" else ("lib" if TRUTH_TERM[r["effect"]] else "out")
        for r in rs
    }
    lib_right = [r for r in rs if kind[r["id"]] == "lib" and oc[r["id"]].startswith("right")]
    zs = [
        n["z"]
        for r in lib_right
        for n in r["named"]
        if n["term"] == TRUTH_TERM[r["effect"]] and n.get("z") is not None
    ]
    outs = ", ".join(f"{r['effect']} {oc[r['id']]}" for r in rs if kind[r["id"]] == "out") or "-"
    nulls = [oc[r["id"]] for r in rs if kind[r["id"]] == "null"]
    secs = sorted(r.get("seconds") or 0 for r in rs)
    return [
        f"{len(lib_right)} / {list(kind.values()).count('lib')}",
        f"{sum(abs(z) <= 3 for z in zs)} / {len(zs)}",
        str(sum(o.startswith(("WRONG", "FALSE NAME")) for o in oc.values())),
        outs,
        f"{sum(o.startswith('ok-null') for o in nulls)} / {len(nulls)}",
        str(sum(o in ("error", "timeout") for o in oc.values())),
        f"{secs[len(secs) // 2]:.0f}, {secs[-1]:.0f}",
    ]


def per_config(rows: list[dict[str, Any]]) -> None:
    head = ["config", "library terms right", "value within 3 se", "wrong confident names", "outside physics"]
    head += ["nulls adequate", "errors / timeouts", "s median, max"]
    print("| " + " | ".join(head) + " |\n" + "|---" * len(head) + "|")
    for cfg, parts in CONFIGS.items():
        rs = [r for r in rows if r["config"] == cfg]
        if rs:
            print("| " + " | ".join([f"{cfg} {'/'.join(parts)}", *group_cells(rs)]) + " |")
    counts = Counter(outcome(r) for r in rows)
    print("\noutcomes:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))


def main(src: str) -> None:
    rows = [json.loads(x) for x in Path(src).read_text().splitlines() if x.strip()]
    per_case(rows)
    print()
    per_config(rows)


if __name__ == "__main__":
    main(sys.argv[1])

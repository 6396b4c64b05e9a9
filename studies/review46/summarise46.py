"""Review 46: classify each case of results46.jsonl (review 45's outcome words) and print the tables.

python studies/review46/summarise46.py studies/review46/results46.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parent.parent / "review45"))
from drive46 import CONFIGS, TRUTH_TERM  # noqa: E402
from summarise45 import cell  # noqa: E402
from summarise45 import outcome as outcome45  # noqa: E402


def twin(term: str) -> str:
    return term[:-2] if term.endswith("@x") else term + "@x"


def outcome(r: dict[str, Any]) -> str:
    """Review 45's words; on a pure gain without delay (u = x) a term named at the other place is right."""
    oc = outcome45(r)
    want = TRUTH_TERM.get(r["effect"])
    if (
        r.get("g") == "gain"
        and want
        and oc.startswith("wrong")
        and twin(want) in [n["term"] for n in r["named"]]
    ):
        return "right at its twin (u = x)" + ("" if r["status"] == "explained" else f" [{r['status']}]")
    return oc


def per_case(rows: list[dict[str, Any]]) -> None:
    print("| case | size | outcome | verdict (first line, cut) | named: value ± se (truth, z) | s (cpu) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        head = (r.get("headline") or r.get("error", "")).replace("|", "/").replace("\n", " ")
        head = head if len(head) <= 110 else head[:107] + "..."
        secs = f"{r.get('seconds', 0):.0f} ({r.get('cpu_seconds', 0):.0f})"
        print(f"| {r['id']} | {r.get('size', 0):.0f} | {outcome(r)} | {head} | {cell(r)} | {secs} |")


def group_cells(rs: list[dict[str, Any]]) -> list[str]:
    """One config's row: library terms right, values within 3 se, wrong names, outside physics, nulls,
    errors, seconds."""
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
        f"{nulls.count('ok-null')} / {len(nulls)}",
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

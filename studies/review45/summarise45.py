"""Review 45: classify each case of results45.jsonl; print the per-case table, the per-group outcome table
(markdown) and write a JSON digest.

    python studies/review45/summarise45.py studies/review45/results45.jsonl studies/review45/results45.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
from drive45 import TRUTH_TERM  # noqa: E402

SIBLING = {"dahl_x": "dahl_sigma@x"}


def caveated(r: dict[str, Any]) -> bool:
    return r["status_text"] != r["status"] or bool(r["details"]) or bool(r["alternatives"])


def mu_said(r: dict[str, Any]) -> bool:
    """The verdict says the loops may be softer than mu = 1 allows (true on the mu = 0.7 plants)."""
    return r.get("bw") == "mu.7" and any("softer than mu = 1" in x for x in [r["headline"], *r["details"]])


def outcome(r: dict[str, Any]) -> str:
    """right / right (value off) / right + extra / missed / WRONG / false alarm / ok-null / unexplained ...;
    a miss or an alarm on a mu = 0.7 plant whose verdict says "softer than mu = 1" gets " (mu < 1 said)"."""
    if "error" in r:
        return "timeout" if r["error"].startswith("timeout") else "error"
    oc = _outcome(r)
    return oc + " (mu < 1 said)" if mu_said(r) and not oc.startswith(("right", "ok")) else oc


def _outcome(r: dict[str, Any]) -> str:
    eff, st = r["effect"], r["status"]
    names = [n["term"] for n in r["named"]]
    if eff == "null":
        if names:
            return "FALSE NAME" if st == "explained" and not caveated(r) else "false name (caveated)"
        return "ok-null" if st == "adequate" else "false alarm"
    want = TRUTH_TERM[eff]
    if want is None:  # physics outside the library
        if names and st == "explained":
            return "WRONG" if not caveated(r) else "named with caveat"
        return "partly" if names else st
    if want in names or want in r["alternatives"]:
        zs = [n.get("z") for n in r["named"] if n["term"] == want]
        parts = ["right" if zs else "right as alternative"]
        parts += [" (value off)"] if zs and zs[0] is not None and abs(zs[0]) > 3 else []
        parts += [] if st == "explained" else [f" [{st}]"]
        extra = ",".join(n for n in names if n not in (want, SIBLING.get(eff)))
        return "".join(parts) + (f" + extra {extra}" if extra else "")
    if names:
        return "WRONG" if st == "explained" and not caveated(r) else "wrong (caveated)"
    return "missed"


def cell(r: dict[str, Any]) -> str:
    return "; ".join(
        f"{n['term']} {n['value']:.3g}±{n['se']:.2g}"
        + (f" (truth {n['truth']:.3g}, z {n['z']:.1f})" if n.get("z") is not None else "")
        for n in r.get("named", [])
    )


def main(src: str, dst: str) -> None:
    rows = [json.loads(x) for x in Path(src).read_text().splitlines() if x.strip()]
    print("| case | size | outcome | verdict (first line, cut) | named: value ± se (truth, z) | s |")
    print("|---|---|---|---|---|---|")
    digest = []
    for r in rows:
        oc = outcome(r)
        head = (r.get("headline") or r.get("error", "")).replace("|", "/").replace("\n", " ")
        head = head if len(head) <= 110 else head[:107] + "..."
        print(
            f"| {r['id']} | {r.get('size', 0):.0f} | {oc} | {head} | {cell(r)} | {r.get('seconds', 0):.0f} |"
        )
        digest.append(
            {k: r.get(k) for k in ("id", "status", "headline", "named", "alternatives", "truth")}
            | {"outcome": oc}
        )
    Path(dst).write_text(json.dumps(digest, indent=1, default=str) + "\n")
    print()
    print(
        "| config | library terms: right name and place | value within 3 se | wrong confident names "
        "| outside physics | nulls adequate | crashes / timeouts | seconds (median, max) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for cfg in sorted({r["config"] for r in rows}):
        rs = [r for r in rows if r["config"] == cfg]
        lib = [r for r in rs if r["effect"] != "null" and TRUTH_TERM[r["effect"]] is not None]
        out = [r for r in rs if r["effect"] != "null" and TRUTH_TERM[r["effect"]] is None]
        nul = [r for r in rs if r["effect"] == "null"]
        ocs = {r["id"]: outcome(r) for r in rs}
        right = [r for r in lib if ocs[r["id"]].startswith("right")]
        hits = [
            n
            for r in right
            for n in r["named"]
            if n.get("z") is not None and n["term"] == TRUTH_TERM[r["effect"]]
        ]
        within = sum(abs(n["z"]) <= 3 for n in hits)
        wrong = sum(ocs[r["id"]].startswith(("WRONG", "FALSE NAME")) for r in rs)
        outs = ", ".join(f"{r['effect']} {ocs[r['id']]}" for r in out) or "-"
        ok = sum(ocs[r["id"]] == "ok-null" for r in nul)
        bad = sum(ocs[r["id"]] in ("error", "timeout") for r in rs)
        secs = sorted(r["seconds"] for r in rs if r.get("seconds") is not None)
        sec = f"{secs[len(secs) // 2]:.0f}, {secs[-1]:.0f}" if secs else "-"
        print(
            f"| {cfg} | {len(right)} / {len(lib)} | {within} / {len(hits)} | {wrong} | {outs} "
            f"| {ok} / {len(nul)} | "
            f"{bad} | {sec} |"
        )
    counts: dict[str, int] = {}
    for d in digest:
        counts[d["outcome"]] = counts.get(d["outcome"], 0) + 1
    print()
    print("outcomes:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

"""Review 44: classify each case of results44.jsonl and print the FINDINGS table (markdown) and a JSON digest.

python studies/review44/summarise44.py studies/review44/results44.jsonl studies/review44/results44.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
from drive44 import TRUTH_TERM as LIBRARY  # noqa: E402  (the effects the library has a term for)

ALPHA = 0.05


def outcome(r: dict[str, Any]) -> str:
    """right / right-value-off / partly / missed / WRONG / false-alarm / ok-null / caveated / ..."""
    if "error" in r:
        return "error"
    eff, st = r["effect"], r["status"]
    names = [n["term"] for n in r["named"]]
    caveat = r["status_text"] != r["status"] or bool(r["details"])
    if eff == "null":
        if names:
            return "FALSE NAME"
        return "ok-null" if st == "adequate" or "may remain" in r["headline"] else "false alarm"
    if eff == "feedback":
        if r["structure_named"]:
            return "right"
        if names and st == "explained":
            return "WRONG" if not caveat else "wrong (caveated)"
        return "missed" if st in ("adequate", "unexplained") else "partly"
    if eff in LIBRARY:
        want = LIBRARY[eff]
        if want in names or want in r["alternatives"]:
            hit = next((n for n in r["named"] if n["term"] == want), None)
            tag = "right" if hit is not None else "right as alternative"
            if hit is not None and hit.get("z") is not None and abs(hit["z"]) > 3:
                tag += " (value off)"
            if st != "explained":
                tag += f" [{st}]"
            extra = [n for n in names if n != want and not (eff == "dahl" and n == "dahl_sigma")]
            if extra:
                tag += " + extra " + ",".join(extra)
            return tag
        if names:
            return "WRONG" if st == "explained" and not caveat else "wrong (partly/caveated)"
        return "missed"
    # physics outside the library
    if names and st == "explained" and not caveat:
        return "WRONG"
    if names:
        return "named with caveat" if st == "explained" else "partly"
    return "unexplained" if st == "unexplained" else st


def flags(r: dict[str, Any]) -> list[str]:
    out = []
    if r.get("status") == "explained" and r.get("final_p", 1.0) < ALPHA:
        out.append(f"explained with final p={r['final_p']:.2g}")
    for n in r.get("named", []):
        if n.get("z") is not None and abs(n["z"]) > 3:
            out.append(f"{n['term']} z={n['z']:.1f}")
    return out


def main(src: str, dst: str) -> None:
    rows = [json.loads(line) for line in Path(src).read_text().splitlines() if line.strip()]
    digest = []
    print(
        "| case | design | G | noise | size | outcome | verdict (first line, cut) "
        "| named: value ± se (truth, z) | s |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        oc = outcome(r)
        fl = flags(r)
        named = "; ".join(
            f"{n['term']} {n['value']:.3g}±{n['se']:.2g}"
            + (f" (truth {n['truth']:.3g}, z {n['z']:.1f})" if n.get("z") is not None else "")
            for n in r.get("named", [])
        )
        head = (r.get("headline") or r.get("error", "")).replace("|", "/")
        if len(head) > 110:
            head = head[:107] + "..."
        print(
            f"| {r['id']} | {r.get('design', '')} | {r.get('g', '')} | {r.get('noise', '')} | "
            f"{r.get('size', 0):.0f} | {oc}{' ' + ', '.join(fl) if fl else ''} | {head} | {named} | "
            f"{r.get('seconds', 0):.0f} |"
        )
        digest.append(
            {
                k: r.get(k)
                for k in (
                    "id",
                    "status",
                    "status_text",
                    "headline",
                    "named",
                    "alternatives",
                    "final_p",
                    "seconds",
                )
            }
            | {"outcome": oc, "flags": fl, "truth": r.get("truth")}
        )
    Path(dst).write_text(json.dumps(digest, indent=1, default=str) + "\n")
    counts: dict[str, int] = {}
    for d in digest:
        counts[d["outcome"]] = counts.get(d["outcome"], 0) + 1
    print()
    print("outcomes:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    secs = sorted(r["seconds"] for r in rows if "seconds" in r)
    if secs:
        print(f"seconds per diagnosis: median {secs[len(secs) // 2]:.0f}, max {secs[-1]:.0f}, n {len(secs)}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

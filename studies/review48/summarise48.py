"""Review 48: each case of results48.jsonl put in words (review 45's outcome words), and the tables.

python studies/review48/summarise48.py studies/review48/results48.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parent.parent / "review45"))
from drive48 import CONFIGS, TRUTH_TERM  # noqa: E402
from summarise45 import caveated, cell  # noqa: E402

#: Outside physics and the library relative that is a fair reading of it: Dahl of exponent 0.5 read as the
#: library's Dahl (exponent 1); a second Bouc-Wen element with mu = 1 read as Dahl on x (Dahl is Bouc-Wen with
#: mu = 1, gamma = 0).
NEAR = {"dahl_half": {"dahl", "dahl_sigma"}, "bw2": {"dahl@x", "dahl_sigma@x"}}


def word(r: dict[str, Any]) -> str:
    """ok-null / false alarm / FALSE NAME / right ... / missed / WRONG / partly / near / error / timeout."""
    if "error" in r:
        return "timeout" if r["error"].startswith("timeout") else "error"
    st, eff = r["status"], r["effect"]
    names = [n["term"] for n in r["named"]]
    confident = st == "explained" and not caveated(r)
    if eff == "null":
        if names:
            return "FALSE NAME" if confident else "false name (caveated)"
        return "ok-null" if st == "adequate" else f"false alarm [{st}]"
    want = TRUTH_TERM[eff]
    if want is None:
        if names and set(names) <= NEAR.get(eff, set()):
            return f"near (same family) [{st}]"
        if names:
            return "WRONG" if confident else f"named with caveat [{st}]"
        return st
    if want in names or want in r["alternatives"]:
        z = next((n.get("z") for n in r["named"] if n["term"] == want), None)
        out = "right" if want in names else "right as alternative"
        out += " (value off)" if z is not None and abs(z) > 3 else ""
        extra = [n for n in names if n != want]
        return (
            out + ("" if st == "explained" else f" [{st}]") + (" + extra " + ",".join(extra) if extra else "")
        )
    if names:
        return "WRONG" if confident else f"wrong (caveated) [{st}]"
    return f"missed [{st}]"


def group(r: dict[str, Any]) -> str:
    return "null" if r["effect"] == "null" else ("lib" if TRUTH_TERM[r["effect"]] else "out")


def table(rows: list[dict[str, Any]]) -> None:
    print("| case | size | outcome | verdict (first line, cut) | named: value ± se (truth, z) | s (cpu) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        said = " ".join((r.get("headline") or r.get("error", "")).replace("|", "/").split())
        said = said if len(said) <= 110 else said[:107] + "..."
        secs = f"{r.get('seconds') or 0:.0f} ({r.get('cpu_seconds') or 0:.0f})"
        print(f"| {r['id']} | {r.get('size', 0):.0f} | {word(r)} | {said} | {cell(r)} | {secs} |")


def by_config(rows: list[dict[str, Any]]) -> None:
    heads = "library terms right, value within 3 se, wrong confident names, outside physics, nulls adequate"
    print(f"\n| config | {heads.replace(', ', ' | ')} | errors / timeouts | s median, max |")
    print("|---" * 8 + "|")
    per: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        per[r["config"]].append(r)
    for cfg, parts in CONFIGS.items():
        rs = per.get(cfg)
        if not rs:
            continue
        w = [(r, word(r), group(r)) for r in rs]
        lib = [(r, o) for r, o, g in w if g == "lib"]
        good = [r for r, o in lib if o.startswith("right")]
        zs = [
            n["z"]
            for r in good
            for n in r["named"]
            if n["term"] == TRUTH_TERM[r["effect"]] and n.get("z") is not None
        ]
        nulls = [o for _, o, g in w if g == "null"]
        secs = sorted(r.get("seconds") or 0.0 for r in rs)
        wrong = [o for _, o, _ in w if o.startswith(("WRONG", "FALSE NAME"))]
        outside = [f"{r['effect']}-{r['size_target']:.0f}: {o}" for r, o, g in w if g == "out"]
        cells = [f"{len(good)} / {len(lib)}", f"{sum(abs(z) <= 3 for z in zs)} / {len(zs)}", str(len(wrong))]
        cells += [", ".join(outside) or "-", f"{nulls.count('ok-null')} / {len(nulls)}"]
        cells += [
            str(sum(o in ("error", "timeout") for _, o, _ in w)),
            f"{secs[len(secs) // 2]:.0f}, {secs[-1]:.0f}",
        ]
        print(f"| {cfg} {'/'.join(parts)} | " + " | ".join(cells) + " |")


def main(src: str) -> None:
    rows = [json.loads(x) for x in Path(src).read_text().splitlines() if x.strip()]
    table(rows)
    by_config(rows)
    print(
        f"\n{len(rows)} cases; outcomes:",
        ", ".join(f"{k} {n}" for k, n in sorted(Counter(map(word, rows)).items())),
    )


if __name__ == "__main__":
    main(sys.argv[1])

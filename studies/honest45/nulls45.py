"""Honest45's count: how often a null set (no drift, no degradation) gets a record left out as drifting, a
drift clause, or a status other than the truth's; and whether real drifts (a decaying centre, a drifting
output gain) are still caught.

    PYTHONPATH=python python studies/honest45/nulls45.py OUT.jsonl [nulls|controls|all] [first [last]]

Nulls: 24 sets from tests/drift_null_sim.py (own RK4: white, AR(1) 0.5 and 0.8 noise, 8-12 experiments,
20 periods) and 12 from review 44's sim44.py (configs A, B, E, effect null, seeds 0-3). Controls:
drift_null_sim.py with a decaying offset or a drifting gain on three experiments.
"""

from __future__ import annotations

import json
import re
import sys
import time
import warnings
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1] / "review44"))
sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))

import drift_null_sim as sim45  # noqa: E402

OWN = [(0.0, 10), (0.5, 8), (0.8, 12), (0.0, 12), (0.5, 10), (0.8, 8)]
DRIFT = re.compile(r"[^.;]*\bdrift[^.;]*", re.IGNORECASE)


def cases(which: str) -> list[str]:
    nulls = [f"own-{k}" for k in range(24)] + [f"r44-{c}-{s}" for c in "ABE" for s in range(4)]
    controls = [f"{kind}-{k}" for kind in ("offset", "gain1", "gain3") for k in range(3)]
    return {"nulls": nulls, "controls": controls, "all": nulls + controls}[which]


def build(cid: str) -> list[Any]:
    kind, *rest = cid.split("-")
    if kind == "own":
        k = int(rest[0])
        phi, n = OWN[k % len(OWN)]
        return sim45.recordings(k, n_exp=n, phi=phi)
    if kind == "r44":
        import drive44 as d44
        import sim44

        cfg, seed = rest[0], int(rest[1])
        p, d, _, _ = d44.build("null", 0.0, cfg)
        return list(sim44.recordings(p, d, d44.NOISES[d44.CONFIGS[cfg][2]], seed))
    k = int(rest[0])
    phi = (0.0, 0.5, 0.8)[k]
    which = (1, 4, 7)
    if kind == "offset":
        return sim45.recordings(100 + k, phi=phi, offset=(0.02, which))
    return sim45.recordings(100 + k, phi=phi, gain=(0.01 if kind == "gain1" else 0.03, which))


def run(cid: str) -> dict[str, Any]:
    import bouc_wen_id as bw

    recs = build(cid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.process_time()
        d = bw.diagnose(recs)
        cpu = time.process_time() - t0
    said = [m.strip() for text in (d.verdict, *d.notes) for m in DRIFT.findall(text)]
    return {
        "id": cid,
        "status": d.status,
        "verdict": d.verdict,
        "left_out": list(d.settings.get("left_out", ())),
        "drift_said": said,
        "drifts_as_fact": [s for s in said if re.search(r"\bstill drifts\b|\bdrifts from\b", s)],
        "n": len(recs),
        "cpu": cpu,
    }


def main(argv: list[str]) -> None:
    out, which = Path(argv[1]), argv[2] if len(argv) > 2 else "all"
    todo = cases(which)
    first = int(argv[3]) if len(argv) > 3 else 0
    last = int(argv[4]) if len(argv) > 4 else len(todo)
    with out.open("a") as fh:
        for cid in todo[first:last]:
            row = run(cid)
            fh.write(json.dumps(row) + "\n")
            fh.flush()
            print(
                cid, row["status"], row["left_out"], len(row["drift_said"]), f"{row['cpu']:.1f}s", flush=True
            )


if __name__ == "__main__":
    main(sys.argv)

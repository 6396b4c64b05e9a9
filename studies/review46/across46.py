"""Review 46: ``bw.diagnose_across`` on two amplitude levels made by sim46 (config H's G, element and noise).

    PYTHONPATH=python python studies/review46/across46.py kelvin|null [SEED] >> across46.jsonl

The same Kelvin element on x (stiffness@x and viscous@x, each about 20x on its own) at both levels, or
none (``null``). The groups are H's experiments at the lower and the higher amplitude (4 frequencies each).
Prints one JSON line: the verdict, each condition's named values and the truth.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402


def kelvin(sy: s.System, pl: s.Plan) -> dict[str, float]:
    """stiffness@x and viscous@x values that each give a size of 20."""
    plain = s.simulate(sy, pl)
    out = {}
    for term in ("stiffness@x", "viscous@x"):
        got = dv.size(s.simulate(s.with_effect(sy, term, 1e-3), pl), plain, pl)
        out[term] = 1e-3 * 20.0 / got
    return out


def main(kind: str, seed: int) -> None:
    import bouc_wen_id as bw

    sy, pl, nn = dv.base("H")
    truth = kelvin(sy, pl) if kind == "kelvin" else {}
    sy = replace(sy, terms=tuple(truth.items()))
    recs = s.recordings(s.simulate(sy, pl), pl, nn, dv.SD, seed)
    half = len(recs) // 2
    groups = [recs[:half], recs[half:]]
    levels = [pl.amps[0], pl.amps[half]]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c0 = time.process_time()
        ad = bw.diagnose_across(groups, levels, labels=["low U", "high U"])
        cpu = time.process_time() - c0
    rec: dict[str, Any] = {
        "id": f"across-{kind}-H-{seed}",
        "truth": truth,
        "levels": levels,
        "cpu_seconds": cpu,
    }
    rec |= {"warnings": sorted({type(w.message).__name__ for w in caught})}
    rec |= {"status": ad.status, "verdict": ad.verdict, "notes": list(ad.notes)}
    rec |= {"terms": [t.to_dict() for t in ad.terms], "partial": [t.to_dict() for t in ad.partial]}
    print(json.dumps(rec, default=str))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)

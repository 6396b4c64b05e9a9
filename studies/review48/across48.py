"""Review 48: ``bw.diagnose_across`` on three levels of a condition made by sim48 (config E's lead G, e1).

    PYTHONPATH=python python studies/review48/across48.py grow|null [SEED] >> across48.jsonl

Three groups (a condition c = 0, 1, 2, e.g. a temperature), each 3 frequencies x 2 amplitudes, white noise
sd 0.01 w_u, no DC offset. ``grow``: stiffness on u and Coulomb friction on x with k = k0 (1 + 0.5 c),
f = f0 (1 + c), k0 and f0 each about 15x on their own at c = 0; ``null``: none. One JSON line out.
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
import drive48 as dv  # noqa: E402
import sim48 as s  # noqa: E402


def main(kind: str, seed: int) -> None:

    p, d, _ = dv.base("E")
    d = replace(d, dc=0.0)
    sd = dv.SD * p.w_u
    plain = s.simulate(p, d)
    unit = {t: dv.size(s.simulate(p.with_(t, 1.0), d), plain, d, sd) for t in ("stiffness", "coulomb@x")}
    groups, truths = [], []
    for c in (0.0, 1.0, 2.0):
        truth = {} if kind == "null" else {"stiffness": 15.0 / unit["stiffness"] * (1 + 0.5 * c)}
        truth |= {} if kind == "null" else {"coulomb@x": 15.0 / unit["coulomb@x"] * (1 + c)}
        q = p
        for name, v in truth.items():
            q = q.with_(name, v)
        groups.append(s.recordings(s.simulate(q, d), d, "white", sd, 1.0, 100 * seed + int(c)))
        truths.append(truth)
    print(json.dumps(judged(groups) | {"id": f"across-{kind}-E-{seed}", "truth": truths}, default=str))


def judged(groups: list[list[Any]]) -> dict[str, Any]:
    """diagnose_across on the three groups: its status, verdict, notes, terms (shared and partial), the
    warning classes it raised and its CPU seconds."""
    import bouc_wen_id as bw

    c0 = time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ad = bw.diagnose_across(groups, [0.0, 1.0, 2.0], labels=["c=0", "c=1", "c=2"])
    out: dict[str, Any] = dict(status=ad.status, verdict=ad.verdict, notes=list(ad.notes))
    out |= {key: [t.to_dict() for t in getattr(ad, key)] for key in ("terms", "partial")}
    return out | dict(
        warnings=sorted({type(w.message).__name__ for w in caught}), cpu=time.process_time() - c0
    )


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)

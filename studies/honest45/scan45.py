"""The leave-out decision alone on many null sets (tests/drift_null_sim.py): each experiment's trend-test p
(settling.trend_p), Bonferroni over the experiments (main before session 45) and Holm (settling.drift_p),
without the rest of diagnose (the decision reads only these p).

    PYTHONPATH=python python studies/honest45/scan45.py OUT.jsonl FIRST LAST
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))

import drift_null_sim  # noqa: E402

OWN = [(0.0, 10), (0.5, 8), (0.8, 12), (0.0, 12), (0.5, 10), (0.8, 8)]


def main(argv: list[str]) -> None:
    from bouc_wen_id.diagnosis.data import prepare
    from bouc_wen_id.diagnosis.settling import _settled, drift_p, trend_p

    with Path(argv[1]).open("a") as fh:
        for k in range(int(argv[2]), int(argv[3])):
            phi, n = OWN[k % len(OWN)]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                exps = prepare(_settled(drift_null_sim.recordings(k, n_exp=n, phi=phi))[0])
            raw = [trend_p(e) for e in exps]
            row = {"seed": k, "phi": phi, "n": n, "raw": raw, "holm": drift_p(exps)}
            fh.write(json.dumps(row) + "\n")
            fh.flush()
            print(k, phi, n, f"{min(raw) * n:.3g}", flush=True)


if __name__ == "__main__":
    main(sys.argv)

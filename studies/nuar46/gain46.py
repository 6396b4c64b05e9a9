"""The proposed share fix's risk where the drift is not degradation: H's null plant (AR(2) noise, sim46) with
the output's gain drifting linearly over every record (a sensor, review 34's reading: ``gain`` per record,
e.g. 0.02 = 2 %), diagnosed as the library stands and with the fix (trace46._share_fix, a monkeypatch).

    PYTHONPATH=python python studies/nuar46/gain46.py GAIN SEED [fix]
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
sys.path.insert(0, str(Path(__file__).parent))
import bouc_wen_id as bw  # noqa: E402
import drive46  # noqa: E402
import sim46  # noqa: E402
import trace46  # noqa: E402


def main(argv: list[str]) -> None:
    gain, seed = float(argv[1]), int(argv[2])
    if "fix" in argv[3:]:
        trace46._share_fix()
    runs, pl, *_ = drive46.build("null", 0.0, "H")
    recs = sim46.recordings(runs, pl, "ar2", drive46.SD, seed)
    recs = [replace(r, y=r.y * (1.0 + gain * (r.t - r.t[0]) / (r.t[-1] - r.t[0]))) for r in recs]
    c0 = time.process_time()
    dg = bw.diagnose(recs)
    named = ", ".join(f"{n.term} {n.value:.3g} +- {n.standard_error:.2g}" for n in dg.named) or "-"
    tag = "fix" if "fix" in argv[3:] else "as is"
    cpu = time.process_time() - c0
    print(f"gain {gain:g} seed {seed} {tag}: {dg.status} ({cpu:.1f} s cpu); named {named}")
    print(f"   {dg.headline[:160]}")


if __name__ == "__main__":
    main(sys.argv)

"""The line search alone on the real data sets' groups (as ``studies/diagnose_real.py`` diagnoses them):
which lines it takes out of their Measurements (none were searched before session 47).

    BOUC_WEN_ID_REAL_DATA=/work/shared/data/real PYTHONPATH=python python studies/hum47/real47.py
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1]))
import diagnose_real as dr  # noqa: E402
from bouc_wen_id.diagnosis import lines  # noqa: E402


def main() -> None:
    data = Path(os.environ.get("BOUC_WEN_ID_REAL_DATA", "../shared/data/real"))
    for dataset, label, ms in dr.groups(data, ["mr-damper", "friction-damper", "wire-rope", "bh-microwire"]):
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            _out, notes = lines.removed(list(ms))
        said = [n.split(" (p =")[0].split("sinusoid at ")[1][:200] for n in notes]
        row = {"dataset": dataset, "group": label, "items": len(ms), "lines": said}
        print(json.dumps({**row, "cpu": round(time.process_time() - t0, 1)}), flush=True)


if __name__ == "__main__":
    main()

"""What diagnose's notes say of the ring-down check on one real data set (session 46, ring46): the note on
the segments too short for the check is said only where the diagnosis read a drift (ring_unchecked.py);
the segments are in the settings either way. Run on main and on the branch to compare.

Run: BOUC_WEN_ID_REAL_DATA=/work/shared/data/real PYTHONPATH=python python studies/ring46/notes_real.py
[friction|wire] (one data set; the whole real-data diagnosis is studies/diagnose_real.py's)
"""

from __future__ import annotations

import importlib.util
import os
import sys
import time
import warnings
from pathlib import Path

import bouc_wen_id as bw

HERE = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("_adapters", HERE / "_adapters.py")
assert spec is not None and spec.loader is not None
ad = importlib.util.module_from_spec(spec)
sys.modules["_adapters"] = ad  # (its dataclasses look their module up)
spec.loader.exec_module(ad)

if __name__ == "__main__":
    root = Path(os.environ["BOUC_WEN_ID_REAL_DATA"])
    which = sys.argv[1] if len(sys.argv) > 1 else "friction"
    if which == "friction":
        ms = [ad.load_friction_damper(root / ad.DATASETS["friction-damper"] / f) for f in ad.FRICTION_FILES]
    else:
        ms = [ad.load_wire_rope(root / ad.DATASETS["wire-rope"] / f) for f in ad.WIRE_ROPE_FILES]
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(ms, value_stability=False)
    print(f"{which}: {d.status}: {d.headline[:160]}; cpu {time.process_time() - t0:.1f} s")
    for n in d.notes:
        if "ring-down" in n:
            print("  note:", n)
    print("  settings:", d.settings.get("ring_down_unchecked"))

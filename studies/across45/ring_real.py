"""The ring-down check (ring_down.rings) on the real lab measurements: does it fire, and where? (session 45,
across45; the lab path reads each steady segment's first periods.)

Run: BOUC_WEN_ID_REAL_DATA=/work/shared/data/real PYTHONPATH=python python studies/across45/ring_real.py

``ring_real.py diagnose friction`` (or ``wire``, ``mr``: one data set; session 46, ring46): what diagnose's
notes and settings say of the ring-down check on that set (the segments too short for it noted only where
the diagnosis read a drift, ring_unchecked.py). Run on main and on a branch to compare.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import time
import warnings
from pathlib import Path

import bouc_wen_id as bw
from bouc_wen_id.diagnosis import ring_down

HERE = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("_adapters", HERE / "_adapters.py")
assert spec is not None and spec.loader is not None
ad = importlib.util.module_from_spec(spec)
sys.modules["_adapters"] = ad  # (its dataclasses look their module up)
spec.loader.exec_module(ad)

if __name__ == "__main__":
    root = Path(os.environ["BOUC_WEN_ID_REAL_DATA"])
    sets = {
        "mr": [m for f in ad.MR_FILES for m in ad.load_mr_damper(root / ad.DATASETS["mr-damper"] / f)],
        "friction": [
            ad.load_friction_damper(root / ad.DATASETS["friction-damper"] / f) for f in ad.FRICTION_FILES
        ],
        "wire": [ad.load_wire_rope(root / ad.DATASETS["wire-rope"] / f) for f in ad.WIRE_ROPE_FILES],
    }
    if sys.argv[1:2] == ["diagnose"]:
        which = sys.argv[2] if len(sys.argv) > 2 else "friction"
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(sets[which], value_stability=False)
        print(f"{which}: {d.status}: {d.headline[:160]}; cpu {time.process_time() - t0:.1f} s")
        for note in d.notes:
            if "ring-down" in note:
                print("  note:", note)
        print("  settings:", d.settings.get("ring_down_unchecked"))
        sys.exit(0)
    for name, ms in sets.items():
        t0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found, notes, short, n = ring_down.checked(ms)
        print(
            f"{name}: {len(ms)} measurements ({n} segments), {len(found)} ringing; cpu "
            f"{time.process_time() - t0:.1f} s"
        )
        for note in notes:
            print("   ", note[:300])
        if short:  # (session 46: in the diagnosis's settings, noted only where it read a drift)
            print(f"    not checked (under {ring_down.LEAST_PERIODS} periods): {', '.join(short)[:300]}")

"""``import bouc_wen_id`` stays lean (issue #8: under 0.2 s): SciPy, matplotlib and Dask are imported on
first use, never by the package import, and the lazy imports change nothing of the public API."""

from __future__ import annotations

import json
import subprocess
import sys

#: Heavy packages the plain import must not load (each costs 0.1-0.5 s; the wall-time target is in
#: benches/bench_pipeline.py, not here: a timed test would fail on a loaded machine).
HEAVY = ("scipy", "matplotlib", "dask", "distributed", "pandas")

PROBE = f"""
import json, sys
import bouc_wen_id
heavy = sorted({{m.split(".")[0] for m in sys.modules}} & set({HEAVY!r}))
missing = [n for n in bouc_wen_id.__all__ if not hasattr(bouc_wen_id, n)]
print(json.dumps({{"heavy": heavy, "missing": missing, "n": len(bouc_wen_id.__all__)}}))
"""


def test_import_loads_no_heavy_package_and_every_public_name_resolves() -> None:
    # A fresh interpreter: this test process has long imported SciPy and matplotlib.
    proc = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["heavy"] == [], f"import bouc_wen_id loads {out['heavy']}: import it inside the function"
    assert out["missing"] == [] and out["n"] > 40, out

"""Probe: the G null (seed 4) through Recordings and bw.load; per experiment the lines, noise var, colour."""

from __future__ import annotations

import sys
import tempfile
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import bouc_wen_id as bw  # noqa: E402
import drive46 as dv  # noqa: E402
import sim46 as s  # noqa: E402
from bouc_wen_id.diagnosis import data, lines  # noqa: E402

sy, pl, nn = dv.base("G")
runs = s.simulate(sy, pl)
recs = s.recordings(runs, pl, nn, dv.SD, int(sys.argv[1]) if len(sys.argv) > 1 else 4)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    for label, items in [("rec", recs)]:
        for r in items:
            print(label, r.metadata["name"], "lines", lines._lines(r, 1e-3 / 4))
        for e in data.prepare(items):
            print(label, e.source, getattr(e, "n_periods", None), e.noise_var, e.colour, e.colour_band)
    with tempfile.TemporaryDirectory() as d:
        dv.write_csv(recs, d)
        ms = bw.load(d)
        for e in data.prepare(ms):
            print("load", e.source, getattr(e, "n_periods", None), e.noise_var, e.colour, e.colour_band)

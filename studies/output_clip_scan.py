"""False alarms of the clipped-output clause (diagnosis/output_clip.py, session 34) on blind's generator.

Makes blind cases (benches/blind.py's ``make_case``: nulls and four library terms at 10x, indices 0-3, the
drawn design and the ``clipped`` and ``few_periods`` designs, blind's own noise kinds, quantised among
them) and lists those whose recorded outputs :func:`output_clip.clipped` flags (none is clipped)::

    PYTHONPATH=$PWD/python:$PWD/benches python studies/output_clip_scan.py
"""

from __future__ import annotations

import time
from types import SimpleNamespace
from typing import Any

import blind  # benches/blind.py
import numpy as np
from bouc_wen_id.diagnosis import output_clip


def main() -> None:
    t0 = time.time()
    n, hits = 0, list[Any]()
    for eff in ("null", "viscous", "stiffness@x", "coulomb", "play"):
        tag = (blind.LIBRARY + blind.OUTSIDE + ("null",)).index(eff)
        for k in range(4):
            sd = int(np.random.SeedSequence([2026, tag, 10, k]).generate_state(1)[0])
            for dz in (None, "clipped", "few_periods"):
                made = blind.make_case(blind.Case(eff, 10.0, k, sd, None, blind.DRIFT, dz))
                items = [SimpleNamespace(y=y, name=f"r{i}") for i, y in enumerate(made["y"])]
                flagged = output_clip.clipped(items)
                n += 1
                if flagged:
                    hits.append((eff, k, dz, made["info"]["noise"], flagged))
    print(f"{n} cases, flagged: {hits}, {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()

"""Identify a magnetorheological damper from one lab file: read, keep the steady periods, average, fit.

Run from the repository root (the package installed)::

    python examples/mr_damper.py                      # ../shared/data/real/mr-damper-utfsm/ME5mm3Hz.txt
    # (or below $BOUC_WEN_ID_REAL_DATA)
    python examples/mr_damper.py path/to/ME5mm4Hz.txt # another file of the same session

The file (UTFSM MR damper on an MTS machine, 1000 Hz) holds five tests, one per coil current, separated by
DAQ pauses; this script takes the first (0 A).  Copy it and change ``read_block`` for your own format.
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

import bouc_wen_id as bw
import numpy as np

REAL = os.environ.get("BOUC_WEN_ID_REAL_DATA") or Path(__file__).resolve().parents[2] / "shared/data/real"
DATA = Path(REAL) / "mr-damper-utfsm"
#: Scales from the folder's PROVENANCE.md (volts to mm and N) and the 2022-05-13 session's channel order.
MM_PER_VOLT, N_PER_VOLT = 10.0, 980.665
DISPLACEMENT, FORCE = 2, 3  # CSV columns of CHANNEL0 and CHANNEL1
HEADER_LINES = 7


def read_block(path: Path) -> bw.Measurement:
    """The samples from ``DAQ Start`` to the first ``DAQ Pause``, as a Measurement in mm and N."""
    lines = path.read_text(encoding="ascii").splitlines()
    dt = float(lines[2].split(":")[1])  # "Sampling Interval:  0.001"
    rows = [line.split(",") for line in lines[HEADER_LINES:]]
    stop = next(i for i, r in enumerate(rows) if r[-1].strip() == "DAQ Pause") + 1
    u = np.array([float(r[DISPLACEMENT]) for r in rows[:stop]]) * MM_PER_VOLT
    y = np.array([float(r[FORCE]) for r in rows[:stop]]) * N_PER_VOLT
    return bw.Measurement.from_rate(
        1.0 / dt, u, y, nominal_frequency=2 * np.pi * 3.0, units={"u": "mm", "y": "N"}, name=path.stem
    )


def main(path: Path) -> int:
    m = read_block(path)
    m.check()  # refuses clipped channels
    found = bw.signal.average_segments(m)
    print(found.report.summary())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = bw.identify(list(found.periods), method="refined")
        except bw.BoucWenIdError as exc:  # a named refusal says what the data lack
            print(f"refused: {type(exc).__name__}: {exc}")
            return 1
    print(result.summary())
    for w in caught:
        print(f"warning: {w.category.__name__}: {w.message}")
    e = result.experiments[0]
    print(f"loop fit NRMSE {e.nrmse:.3f} against {e.linear_nrmse:.3f} for a spring + dashpot")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else DATA / "ME5mm3Hz.txt"))

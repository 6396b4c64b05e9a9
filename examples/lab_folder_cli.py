"""A folder of lab records through the command line: ``bouc-wen-id identify <folder>``.

Run from the repository root (the package installed)::

    python examples/lab_folder_cli.py /tmp/lab     # writes /tmp/lab/*.csv, then the report in /tmp/lab/report

The records are what a rig writes: a DAQ rate of 2 kHz, a sine whose frequency is 1.5 % off its nominal
value, idle stretches and amplitude ramps around the steady part, offsets and noise.  Here they are
simulated on the demo plant (seeded); with your own rig, skip ``write_records`` and point the command at
your folder of CSV files (``--columns`` names the t, u and y columns when they are not called so).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import bouc_wen_id as bw
import numpy as np

RATE = 2000.0  # Hz
NOMINAL_HZ = (0.3, 0.6, 1.0)  # one record per frequency
CLOCK_OFFSET = 1.015  # the generator runs 1.5 % fast against the DAQ clock


def write_records(folder: Path, seed: int = 0) -> list[Path]:
    """One CSV per frequency: 2 s idle, a 2-period ramp, 12 steady periods, a ramp down, 1 s idle."""
    rng = np.random.default_rng(seed)
    plant = bw.demo_plant()
    paths = []
    for f_nom in NOMINAL_HZ:
        f = f_nom * CLOCK_OFFSET
        t = np.arange(int((3.0 + 16 / f) * RATE)) / RATE
        envelope = np.clip((t - 2.0) * f / 2, 0, 1) * np.clip((2.0 + 16 / f - t) * f / 2, 0, 1)
        u = 0.4 * envelope * np.cos(2 * np.pi * f * t)
        _, w = bw.simulate_input(plant, t, u)
        y = w + 0.3 + 0.01 * rng.standard_normal(t.size)  # a force offset and sensor noise
        m = bw.Measurement(t, u + 2.0, y, nominal_frequency=2 * np.pi * f_nom, units={"u": "mm", "y": "kN"})
        paths += bw.save(folder / f"sine_{f_nom:g}Hz.csv", m)
    return paths


def main(folder: Path) -> int:
    folder.mkdir(parents=True, exist_ok=True)
    for path in write_records(folder):
        print(f"wrote {path}")
    command = ["bouc-wen-id", "identify", str(folder), "--out", str(folder / "report")]
    print("$ " + " ".join(command))
    # The console script sits next to this interpreter; ``python -m bouc_wen_id`` is the same command.
    return subprocess.call([sys.executable, "-m", "bouc_wen_id", *command[1:]])


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("lab_records")))

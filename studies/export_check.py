"""How closely the exported model reproduces ``simulate_input`` (issue #21 item 2), for docs/export.md.

For each row: a seeded random plant (G of order 0-4, with or without delay and feed-through; a random
subset of the simulated terms), a random sampled input, the Rust simulator against the compiled C function
(``bw.to_c``, ``cc -std=c99 -Wall -Wextra -Werror -pedantic -O2``) and against the python-control system
(continuous: ``bw.to_nlsys`` under ``bouc_wen_id.export.rk4_response``, the simulator's RK4 step;
discrete: ``bw.to_nlsys(plant, dt=...)`` run by python-control's ``input_output_response`` through
``bouc_wen_id.export.discrete_response``). Every term of the registry the simulator has may be drawn, on u,
inside the hysteresis, on x and on the output. Prints a Markdown table of the largest difference relative to
the signal's largest magnitude (x, w, y).

A second table does the same for Dahl friction (on u, on x, on both; its force a state of the exported
model), on ``tests/test_export_dahl.py``'s random plants and smooth inputs (``sigma |v'| h / Fc <= 0.5``).

Usage: ``python studies/export_check.py [--plants 12] [--dahl 9]``.
"""

from __future__ import annotations

import argparse
import ctypes
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.export import discrete_response, peak_speeds, rk4_response

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from test_export import SIMULATED, random_input, random_plant, rel, step  # noqa: E402
from test_export_dahl import dahl_plant, smooth_input  # noqa: E402


def compiled(source: str, name: str, folder: Path) -> ctypes.CDLL:
    c, so = folder / f"{name}.c", folder / f"{name}.so"
    c.write_text(source, encoding="utf-8")
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        raise SystemExit("no C compiler on this machine")
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-shared", "-fPIC"]
    subprocess.run([cc, *flags, str(c), "-o", str(so), "-lm"], check=True)
    return ctypes.CDLL(str(so))


def errors(
    plant: bw.WienerPlant, t: np.ndarray, u: np.ndarray, substeps: int, folder: Path, name: str
) -> str:
    """The row's three cells: C, discrete nlsys, continuous nlsys under the simulator's RK4 (x, w, y)."""
    p = ctypes.POINTER(ctypes.c_double)
    ref = bw.simulate_input(plant, t, u, substeps=substeps, output=True)
    fn = getattr(compiled(bw.to_c(plant, name=name), name, folder), name)
    fn.argtypes = [p, ctypes.c_long, ctypes.c_double, ctypes.c_int, p, p, p]
    outs = [np.zeros(u.size) for _ in range(3)]
    rc = fn(u.ctypes.data_as(p), u.size, step(t), substeps, *(o.ctypes.data_as(p) for o in outs))
    c_err = ", ".join(f"{rel(a, b):.1e}" for a, b in zip(outs, ref)) if rc == 0 else f"rc {rc}"
    vmax, vx = peak_speeds(plant, t, u, substeps)
    nl = rk4_response(bw.to_nlsys(plant, vmax=vmax, vx=vx), t, u, substeps=substeps, plant=plant)
    n_err = ", ".join(f"{rel(a, b):.1e}" for a, b in zip(nl, ref))
    sysd = bw.to_nlsys(plant, vmax=vmax, vx=vx, dt=step(t), substeps=substeps)
    dn = discrete_response(sysd, t, u, plant=plant)
    d_err = ", ".join(f"{rel(a, b):.1e}" for a, b in zip(dn, ref))
    return f"{c_err} | {d_err} | {n_err}"


def dahl_table(count: int, folder: Path) -> None:
    print(
        "\n| seed | places | order | delay | other terms | C: x, w, y | nlsys discrete: x, w, y "
        "| nlsys continuous (RK4): x, w, y |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for seed in range(count):
        places = ("u", "x", "ux")[seed % 3]
        rng = np.random.default_rng([31, seed // 3, len(places), ord(places[0])])  # the test's draws
        substeps = int(rng.integers(1, 5))
        t, u = smooth_input(rng, 300)
        plant, _ = dahl_plant(rng, places, t, u, substeps)
        kinds = " ".join(t.kind for t in plant.terms if "dahl" not in t.kind) or "-"
        order, delay = plant.linear.den.size - 1, plant.linear.delay
        cells = errors(plant, t, u, substeps, folder, f"d{seed}")
        print(f"| {seed // 3} | {places} | {order} | {delay:.3g} | {kinds} | {cells} |")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--plants", type=int, default=12)
    ap.add_argument("--dahl", type=int, default=9)
    args = ap.parse_args()
    print(
        "| seed | order | delay | terms | C: x, w, y | nlsys discrete: x, w, y "
        "| nlsys continuous (RK4): x, w, y |"
    )
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.plants):
            rng = np.random.default_rng(seed)
            plant = random_plant(rng, SIMULATED)
            t, u = random_input(rng)
            substeps = int(rng.integers(1, 5))
            cells = errors(plant, t, u, substeps, Path(tmp), f"m{seed}")
            kinds = " ".join(t.kind for t in plant.terms) or "(plain)"
            order, delay = plant.linear.den.size - 1, plant.linear.delay
            print(f"| {seed} | {order} | {delay:.3g} | {kinds} | {cells} |")
        dahl_table(args.dahl, Path(tmp))
    return 0


if __name__ == "__main__":
    sys.exit(main())

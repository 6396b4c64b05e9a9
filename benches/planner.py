#!/usr/bin/env python
"""Seeded Monte Carlo of the experiment planner: does a planned design reach its predicted precision?

Run in an environment where the package is installed (or built with ``maturin develop``)::

    python benches/planner.py               # 200 runs per design, two targets: about a minute
    python benches/planner.py --runs 100    # the least the target asks for
    python benches/planner.py --quick       # 10 runs: a smoke run, not for conclusions

What it does
------------
The prior is the truth here (the demo plant, ``bw.demo_plant()``: a resonance at 5 rad/s behind a 0.05 s
delay, alpha = 2), so that the bound is the one the identification should reach.  Lab limits: the band
1-10 rad/s, ``|U| <= 1``, 100 Hz sampling, 10 settling periods and 2 s set-up per experiment, output noise
sd 0.05 per sample, a budget of 300 s.  For each target (``bouc_wen``, and ``G`` on a 6-point grid)
``bw.plan_experiment`` plans a design and the naive design of the same budget (evenly log-spaced
frequencies at the largest amplitude, equal periods).  Each design is simulated ``--runs`` times
(``design.simulate(plant, seed=seed0 + 10000 k + s)``, every random number from that seed) and identified
with ``bw.identify(recordings)`` (the refined output-error fit); a run that raises a ``BoucWenIdError`` is
counted as a failure and printed, never fatal.

What is printed
---------------
Per design, for beta, gamma, mu and, per experiment, |G| and phi (alpha-normalised): the predicted
standard deviation (the Cramer-Rao bound the planner reports), the achieved one (the sample SD of the
estimates over the runs), their ratio with its Monte Carlo standard error ``ratio / sqrt(2 (n - 1))``, and
the bias in units of the achieved SD.  Target: every ratio within [0.8, 1.2] (PASS / MISS); with 200 runs a
ratio carries a standard error of about 5 %, so a verdict within two of them of a limit is not conclusive.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
import warnings
from typing import Any

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import bouc_wen_id as bw  # noqa: E402
import numpy as np  # noqa: E402

#: The lab of the study (see the module docstring).
LIMITS: dict[str, Any] = dict(
    band=(1.0, 10.0),
    max_amplitude=1.0,
    noise_sd=0.05,
    sample_rate=100.0,
    settle_periods=10,
    overhead=2.0,
)
BUDGET = 300.0
#: The targets studied, with their own settings: "G" tests every grid point, 6 of them here.
TARGETS: dict[str, dict[str, Any]] = {"bouc_wen": {}, "G": {"n_frequencies": 6}}
#: Achieved / predicted SD must lie within these bounds.
RATIO_LOW, RATIO_HIGH = 0.8, 1.2


def monte_carlo(
    plant: bw.WienerPlant, design: bw.planning.Design, runs: int, seed0: int
) -> tuple[np.ndarray[Any, np.dtype[np.float64]], list[str]]:
    """Estimates ``[beta, gamma, mu, |G_0|, phi_0, |G_1|, ...]`` of every run that returned, and failures."""
    rows: list[list[float]] = []
    failures: list[str] = []
    for s in range(runs):
        recs = design.simulate(plant, seed=seed0 + s)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = bw.identify(recs)
        except bw.BoucWenIdError as exc:
            failures.append(f"seed {seed0 + s}: {type(exc).__name__}: {exc}")
            continue
        row = [r.beta, r.gamma, r.mu]
        for g, p in zip(r.gains, r.phases):
            row += [float(g), float(p)]
        rows.append(row)
    return np.array(rows), failures


def report(name: str, plant: bw.WienerPlant, design: bw.planning.Design, runs: int, seed0: int) -> bool:
    t0 = time.perf_counter()
    est, failures = monte_carlo(plant, design, runs, seed0)
    wall = time.perf_counter() - t0
    norm = plant.normalized()
    gains, phases = norm.linear.gain_phase([e.frequency for e in design.experiments])
    h = norm.hysteresis
    truth = [h.beta, h.gamma, h.mu]
    names = ["beta", "gamma", "mu"]
    cr = design.predicted
    predicted = [cr.beta, cr.gamma, cr.mu]
    for i, e in enumerate(design.experiments):
        truth += [float(gains[i]), float(phases[i])]
        names += [f"|G| @{e.frequency:.3g}", f"phi @{e.frequency:.3g}"]
        predicted += [float(cr.gain[i]), float(cr.phase[i])]
    n = est.shape[0]
    print(f"\n{name}: {len(design.experiments)} experiments, {design.total_time:.1f} s of test time")
    for e in design.experiments:
        print(
            f"  omega {e.frequency:7.4g} rad/s  U {e.amplitude:6.3g}  P {e.samples_per_period:4d}  "
            f"N {e.periods:4d}  ({e.duration:6.1f} s)"
        )
    print(f"  {n} of {runs} runs identified ({wall:.1f} s, {wall / runs:.3f} s a run)")
    for f in failures:
        print(f"  failed: {f}")
    if n < 3:
        print("  too few runs to estimate an SD")
        return False
    print(f"  {'param':<14} {'predicted SD':>13} {'achieved SD':>12} {'ratio':>14} {'bias/SD':>8}  verdict")
    ok = True
    for j, label in enumerate(names):
        col = est[:, j]
        err = col - truth[j]
        if label.startswith("phi"):
            err = (err + np.pi) % (2 * np.pi) - np.pi  # phases live on a circle
        sd = float(np.std(err, ddof=1))
        ratio = sd / predicted[j]
        se = ratio / np.sqrt(2 * (n - 1))
        bias = float(np.mean(err)) / sd
        good = RATIO_LOW <= ratio <= RATIO_HIGH
        ok &= good
        print(
            f"  {label:<14} {predicted[j]:>13.4g} {sd:>12.4g} {ratio:>7.3f} +-{se:5.3f} {bias:>8.2f}  "
            f"{'PASS' if good else 'MISS'}"
        )
    return ok


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--runs", type=int, default=200, help="Monte Carlo runs per design (>= 100)")
    parser.add_argument("--quick", action="store_true", help="10 runs: a smoke run")
    parser.add_argument("--seed", type=int, default=20261123, help="first seed")
    args = parser.parse_args()
    runs = 10 if args.quick else args.runs
    print(f"benches/planner.py: {runs} runs per design, seed0 {args.seed}")
    print(f"bouc_wen_id {bw.__version__}, Python {platform.python_version()}, {platform.machine()}")
    plant = bw.demo_plant()
    print(f"plant (prior = truth): {plant.linear!r}, {plant.hysteresis!r}")
    print(f"limits: {LIMITS}, budget {BUDGET:g} s")
    verdicts: list[tuple[str, bool]] = []
    for k, (target, extra) in enumerate(TARGETS.items()):
        t0 = time.perf_counter()
        plan = bw.plan_experiment(plant, BUDGET, target=target, **LIMITS, **extra)  # type: ignore[arg-type]
        print(f"\n=== target {target!r}: planned in {time.perf_counter() - t0:.2f} s ===")
        print(plan.summary())
        designs = [("planned", plan.design)] + ([("naive", plan.naive)] if plan.naive is not None else [])
        for j, (name, design) in enumerate(designs):
            ok = report(f"{target} / {name}", plant, design, runs, args.seed + 10000 * (2 * k + j))
            verdicts.append((f"{target} / {name}", ok))
    print("\nSummary (achieved SD within [0.8, 1.2] x predicted for every parameter):")
    for name, ok in verdicts:
        print(f"  {name:<22} {'PASS' if ok else 'MISS'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python
"""Seeded study of the G(s) fit (issue #11 part 1): recovery of known transfer functions and order selection.

Run in an environment where the package is installed::

    python benches/tfit.py               # 40 seeds for recovery, 8 for order selection (~3 min on 1 core)
    python benches/tfit.py --quick       # 6 and 2 seeds: a smoke run, not for conclusions

Design
------
Eight known G: orders 1-4 (a first-order lag; a resonance; a third order with a zero; a fourth order with
two resonances and two zeros), each without and with a 0.05 s pure delay, behind the Bouc-Wen element of
``benches/accuracy.py`` (beta 0.8, gamma 0.2, mu 1.6), tested at 16 log-spaced frequencies in
[0.3, 20] rad/s (dense enough that every resonance has a point in its half-power band), amplitudes
designed as the demo does (|G| U = 1.2 w_0), P = 256 samples per period.

Noise: the points' 2x2 covariances of (|G_i|, phi_i) are the Cramer-Rao blocks (``bw.cramer_rao``) of
that design at the noise levels of ``benches/accuracy.py`` -- (sd 0.05, N = 50), (sd 0.1, N = 200) -- and
of its demo design (sd 0.02, N = 40); the refined estimator reaches these bounds (accuracy.py), so they are
the uncertainty an identification hands to the fit.  Each seed draws the points from N(truth, CRB block).

Printed per (G, noise level):

- ``max rel err``: median over seeds of ``max_w |G_fit(jw) - G(jw)| / |G(jw)|`` over 200 frequencies in
  the tested band, with the true order and delay given (recovery);
- ``pt rel se``: the median relative standard error of the points themselves, for scale;
- ``cov95``: the fraction of (seed, frequency) pairs at 5 untested frequencies where the true |G| lies in
  the fit's 95 % interval (``predict``);
- ``delay err``: median |delay_fit - delay| (s) when a delay is fitted;
- ``order hit``: fraction of seeds where the automatic selection (AICc over 0 <= m <= n <= 4, with and
  without delay) returns the true (m, n) and the true presence of a delay.
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import bouc_wen_id as bw  # noqa: E402
import numpy as np  # noqa: E402
from bouc_wen_id.demo import design_amplitudes  # noqa: E402

DELAY = 0.05
CASES = {
    "1: 2/(s+3)": ([2.0], [1.0, 3.0]),
    "2: 25/(s^2+2s+25)": ([25.0], [1.0, 2.0, 25.0]),
    "3: (s+4)/(s^3+3s^2+6s+4)": ([1.0, 4.0], [1.0, 3.0, 6.0, 4.0]),
    "4: (3s^2+s+20)/(s^4+1.2s^3+30s^2+10s+50)": ([3.0, 1.0, 20.0], [1.0, 1.2, 30.0, 10.0, 50.0]),
}
LEVELS = (("sd 0.05, N 50", 0.05, 50), ("sd 0.1, N 200", 0.1, 200), ("sd 0.02, N 40", 0.02, 40))
OMEGA = np.geomspace(0.3, 20.0, 16)
UNTESTED = np.array([0.5, 1.5, 3.3, 7.0, 15.0])
DENSE = np.geomspace(0.3, 20.0, 200)


def crb_blocks(tf: bw.TransferFunction, sd: float, periods: int) -> np.ndarray:
    plant = bw.WienerPlant(tf, bw.BoucWen(0.8, 0.2, 1.6))
    freqs = [float(w) for w in OMEGA]
    plan = bw.SinePlan(
        frequencies=tuple(freqs),
        amplitudes=design_amplitudes(plant, freqs),
        settle_periods=20,
        periods=periods,
        samples_per_period=256,
        substeps=2,
        noise_sd=sd,
        seed=0,
    )
    cov = bw.cramer_rao(plant, plan).covariance
    return np.stack([cov[3 + 2 * i : 5 + 2 * i, 3 + 2 * i : 5 + 2 * i] for i in range(OMEGA.size)])


def draw(tf: bw.TransferFunction, blocks: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    g = tf.freqresp(OMEGA)
    gain, phase = np.abs(g), -np.angle(g)
    out = np.empty(OMEGA.size, dtype=complex)
    for i in range(OMEGA.size):
        d = np.linalg.cholesky(blocks[i]) @ rng.standard_normal(2)
        out[i] = (gain[i] + d[0]) * np.exp(-1j * (phase[i] + d[1]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--order-seeds", type=int, default=8)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.seeds, args.order_seeds = 6, 2
    warnings.simplefilter("ignore", bw.IdentifiabilityWarning)  # counted in the table, not printed
    print(f"G(s) fit study: {args.seeds} seeds (recovery), {args.order_seeds} seeds (order selection)")
    head = (
        f"{'G':<44}{'delay':>6}  {'noise':<14}{'pt rel se':>10}{'max rel err':>12}{'cov95':>7}"
        f"{'delay err':>10}{'order hit':>10}"
    )
    print(head)
    print("-" * len(head))
    t0 = time.perf_counter()
    hits_all = tries_all = 0
    for ci, (name, (num, den)) in enumerate(CASES.items()):
        for delayed in (False, True):
            tf = bw.TransferFunction(num, den, DELAY if delayed else 0.0)
            m, n = len(num) - 1, len(den) - 1
            for li, (label, sd, periods) in enumerate(LEVELS):
                blocks = crb_blocks(tf, sd, periods)
                g_true = tf.freqresp(OMEGA)
                rel_se = np.median(np.sqrt(blocks[:, 0, 0]) / np.abs(g_true))
                errs, delay_errs, cover = [], [], []
                for seed in range(args.seeds):
                    rng = np.random.default_rng(100_000 * ci + 10_000 * delayed + 1000 * li + seed)
                    g = draw(tf, blocks, rng)
                    fit = bw.fit_transfer_function(
                        omega=OMEGA, response=g, covariance=blocks, order=(m, n), delay=delayed
                    )
                    dense = fit.transfer_function.freqresp(DENSE)
                    errs.append(np.max(np.abs(dense - tf.freqresp(DENSE)) / np.abs(tf.freqresp(DENSE))))
                    if delayed:
                        delay_errs.append(abs(fit.transfer_function.delay - DELAY))
                    p = fit.predict(UNTESTED)
                    lo, hi = p.gain_interval.T
                    truth = np.abs(tf.freqresp(UNTESTED))
                    cover.extend((lo <= truth) & (truth <= hi))
                hits = 0
                for seed in range(args.order_seeds):
                    rng = np.random.default_rng(
                        7_000_000 + 100_000 * ci + 10_000 * delayed + 1000 * li + seed
                    )
                    g = draw(tf, blocks, rng)
                    fit = bw.fit_transfer_function(omega=OMEGA, response=g, covariance=blocks)
                    hits += (fit.m, fit.n, fit.delay_fitted) == (m, n, delayed)
                hits_all += hits
                tries_all += args.order_seeds
                derr = f"{np.median(delay_errs):>10.2e}" if delayed else f"{'-':>10}"
                print(
                    f"{name:<44}{('yes' if delayed else 'no'):>6}  {label:<14}{rel_se:>10.2e}"
                    f"{np.median(errs):>12.2e}{np.mean(cover):>7.3f}{derr}"
                    f"{f'{hits}/{args.order_seeds}':>10}",
                    flush=True,
                )
    print("-" * len(head))
    print(f"order-selection hit rate overall: {hits_all}/{tries_all} = {hits_all / tries_all:.3f}")
    print(f"wall time {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()

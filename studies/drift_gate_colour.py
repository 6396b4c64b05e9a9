"""The drift gate's false alarms and power under white and AR(1) noise, on records written down directly.

The drift gate (``drift.with_drift_gate``) is the blocks' chi-square against no drift, ``cost0`` on ``dof0``,
rejected at ``alpha / 2``. Its statistic is ``sum_b w_b sum_k hw_k |dev_bk|^2`` (``drift._inner``): each
block's harmonics about their weighted mean, weighed by the block's samples over the noise level of each
harmonic (``harmonic_var``; one level, ``noise_var``, when it is empty). This study forms that statistic
exactly as ``drift.drift_data`` does (no fit is needed: the regressors do not enter it) on:

* ``lab``: 4 fixed-rate Measurements (no whole number of samples per period: 97.3, 121.7, 153.1 and 185.4),
  ``(1 - r s) tanh(2 cos(wt - 0.4))`` (s from -1/2 to 1/2 over the record: a loop that shrinks), 16-40
  periods, noise sd 0.01 white or AR(1);
* ``rec``: 4 Recordings of 128 samples per period (4 settling + 16 periods), the same loop and noise.

``r = 0`` is the null: the false alarms at the gate's level; ``r > 0`` (SIZE times the averaged noise sd over
the record) its power. ``--hw none`` drops the per-harmonic levels (one level for every harmonic, which is
what main gave lab measurements: their ``harmonic_var`` was empty).

Usage: ``python studies/drift_gate_colour.py lab 0.7 0 --seeds 200`` (KIND PHI SIZE; PHI 0 is white).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import data, drift

TWO_PI = 2.0 * math.pi
SD = 0.01
LEVEL = 0.025  # the gate's level: alpha / 2 at alpha = 0.05


def _noise(rng: np.random.Generator, n: int, phi: float) -> Any:
    if phi == 0.0:
        return rng.normal(0.0, SD, n)
    e = rng.normal(0.0, SD * math.sqrt(1.0 - phi**2), n)
    e[0] = rng.normal(0.0, SD)
    for k in range(1, n):
        e[k] += phi * e[k - 1]
    return e


def items(kind: str, phi: float, size: float, seed: int) -> list[Any]:
    """The set's records; ``size`` the loop's shrink over each record in averaged noise sd."""
    rng = np.random.default_rng([seed, 61])
    out: list[Any] = []
    if kind == "lab":
        plan = [(97.3, 40), (121.7, 30), (153.1, 24), (185.4, 16)]
    else:
        plan = [(128.0, 16)] * 4
    for i, (spp, periods) in enumerate(plan):
        om = TWO_PI * (1.0 + 0.3 * i)
        dt = TWO_PI / om / spp
        settle = 4 if kind == "rec" else 0
        n = int(round((periods + settle) * spp)) if kind == "rec" else int(periods * spp)
        t = np.arange(n) * dt
        s = np.clip((t - settle * spp * dt) / (periods * spp * dt), 0.0, 1.0) - 0.5
        # SIZE averaged-noise sd of shrink (sd / sqrt(samples)) spread over the loop's rms (about 0.8).
        r = size * SD / math.sqrt(n) / 0.8
        y = (1.0 - r * s) * np.tanh(2.0 * np.cos(om * t - 0.4)) + _noise(rng, n, phi)
        u = np.cos(om * t)
        if kind == "lab":
            out.append(bw.Measurement(t, u, y, nominal_frequency=om))
        else:
            out.append(bw.Recording(t, u, y, 1.0, om, settle_periods=settle))
    return out


def gate(exps: list[Any], per_harmonic: bool) -> tuple[float, int]:
    """``(cost0, dof0)`` of the drift gate, as ``drift.drift_data`` and ``drift._sums`` form them."""
    c0, dof = 0.0, 0
    for e in exps:
        keep = drift.whole_blocks(e)
        if keep.size < 2:
            continue
        k = e.block_coef.shape[1] - 1
        w = e.block_samples[keep] / e.noise_var
        c = e.block_coef[keep]
        dev = c - (w[:, None] * c).sum(axis=0) / w.sum()
        hw = drift.harmonic_weights(e, k) if per_harmonic else None
        z = np.zeros(k + 1, np.complex128)
        dd = drift.DriftData(0, dev, np.zeros(keep.size), w, 0.0, z, np.zeros(1), math.nan, hw=hw)
        c0 += float(np.dot(w, drift._inner(dev, dev, hw)))
        dof += dd.dof
    return c0, dof


def main() -> None:
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("kind", choices=["lab", "rec"])
    ap.add_argument("phi", type=float)
    ap.add_argument("size", type=float)
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--hw", choices=["own", "none", "both"], default="both")
    a = ap.parse_args()
    modes = {"own": True, "none": False} if a.hw == "both" else {a.hw: a.hw == "own"}
    ratios: dict[str, list[float]] = {m: [] for m in modes}
    hits = dict.fromkeys(modes, 0)
    for seed in range(a.seeds):
        exps = data.prepare(items(a.kind, a.phi, a.size, seed))
        for m, own in modes.items():
            c0, dof = gate(exps, own)
            ratios[m].append(c0 / dof)
            hits[m] += int(float(chdtrc(dof, c0)) < LEVEL)
    for m in modes:
        q = np.percentile(ratios[m], [5, 50, 95])
        print(
            f"{a.kind} phi={a.phi:g} size={a.size:g} hw={m}: gate at {LEVEL:g} {hits[m]}/{a.seeds}, "
            f"chi2/dof median {q[1]:.3f} (5-95 %: {q[0]:.3f}-{q[2]:.3f})"
        )


if __name__ == "__main__":
    main()

"""How the block chi-square of the degradation test sits against its degrees of freedom, harmonic by
harmonic, on noise alone (review 46's H plan, no degradation): AR(2) noise as sim46 makes it (poles
0.95 e^{+-0.3i} a sample, P = 40) against white noise.

    PYTHONPATH=python python studies/nuar46/calib46.py [SEEDS]

For each record the library's own reduction (``diagnosis.data.prepare``: the block harmonics, the noise
level and the per-harmonic levels ``harmonic_var``) is read, the block deviations about their weighted mean
weighed as ``drift.drift_data`` weighs them (``block_samples / noise_var`` times ``harmonic_weights``),
and their chi-square per harmonic is divided by its degrees of freedom (1 at the DC, 2 above, per block
beyond the first). 1 is calibrated; below 1 the levels overstate the noise in the blocks. The truth column
is the AR(2) spectrum at each harmonic over its band-pooled (+-2 harmonics) mean: what pooling alone does
to a level.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import drive46  # noqa: E402
import sim46  # noqa: E402
from bouc_wen_id.diagnosis.data import prepare  # noqa: E402
from bouc_wen_id.diagnosis.drift import harmonic_weights, whole_blocks  # noqa: E402
from bouc_wen_id.diagnosis.settling import _settled  # noqa: E402


def per_harmonic(exps: list) -> tuple[np.ndarray, np.ndarray]:
    """Chi-square and dof per harmonic, summed over ``exps``."""
    chi, dof = None, None
    for e in exps:
        keep = whole_blocks(e)
        coef = e.block_coef[keep]
        k = coef.shape[1] - 1
        w = e.block_samples[keep] / e.noise_var
        mean = (w[:, None] * coef).sum(axis=0) / w.sum()
        dev = coef - mean
        hw = harmonic_weights(e, k)
        hw = np.ones(k + 1) if hw is None else hw
        c = (np.abs(dev) ** 2) * hw * w[:, None]
        c[:, 0] = (dev[:, 0].real ** 2) * hw[0] * w
        c[:, 1:] *= 0.5
        d = np.full(k + 1, 2.0 * (keep.size - 1))
        d[0] = keep.size - 1
        chi = c.sum(axis=0) if chi is None else chi + c.sum(axis=0)
        dof = d if dof is None else dof + d
    assert chi is not None and dof is not None
    return chi, dof


def pooled_truth(p: int, k: int) -> np.ndarray:
    """The AR(2) spectrum at harmonics 0..k over its mean over +-2 harmonics (harmonic_levels' band)."""
    r, th = 0.95, 0.3
    a1, a2 = 2 * r * np.cos(th), -(r**2)
    js = np.arange(0, k + 3)
    z = np.exp(-1j * 2 * np.pi * js / p)
    s = 1.0 / np.abs(1 - a1 * z - a2 * z**2) ** 2
    out = np.empty(k + 1)
    for j in range(k + 1):
        a, b = (0, 0) if j == 0 else (max(1, j - 2), min(k, j + 2))
        out[j] = s[j] / s[a : b + 1].mean()
    return out


def main(argv: list[str]) -> None:
    seeds = [int(x) for x in argv[1:]] or list(range(1, 9))
    runs, pl, *_ = drive46.build("null", 0.0, "H")
    for kind in ("ar2", "white"):
        chi, dof = None, None
        for seed in seeds:
            recs = sim46.recordings(runs, pl, kind, drive46.SD, seed)
            exps = prepare(_settled(recs)[0])  # the start-up transient trimmed as diagnose trims it
            c, d = per_harmonic(exps)
            chi = c if chi is None else chi + c
            dof = d if dof is None else dof + d
        assert chi is not None and dof is not None
        print(
            f"{kind}: {len(seeds)} seeds x 8 records; block chi2 / dof over all harmonics "
            f"{chi.sum() / dof.sum():.3f}"
        )
        print("  harmonic    " + " ".join(f"{j:5d}" for j in range(chi.size)))
        print("  chi2/dof    " + " ".join(f"{v:5.2f}" for v in chi / dof))
        if kind == "ar2":
            print("  S_k/pooled  " + " ".join(f"{v:5.2f}" for v in pooled_truth(pl.samples, chi.size - 1)))


if __name__ == "__main__":
    main(sys.argv)

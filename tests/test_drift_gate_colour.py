"""The drift gate's statistic under coloured noise on lab measurements (issue 18: "every statistic is valid
or says why not"; the blind bench's ``degradation:10:0`` and ``10:1``).

The gate (``drift.with_drift_gate``) is the blocks' chi-square against no drift. Each block harmonic must be
weighed by its own noise level: a lab measurement had none (``harmonic_var`` empty), so every harmonic was
weighed by the largest coloured band's level, and under AR(1) noise the chi-square of a null sat at 0.5-0.7
of its degrees of freedom and that of a degrading record (blind ``degradation:10:0``) below them: the
degradation was never a candidate. The records here are written down in NumPy (no simulator of ours).
"""

from __future__ import annotations

import importlib
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import data, drift

TWO_PI = 2.0 * math.pi
SD = 0.01


def _records(phi: float, seed: int, shrink: float = 0.0) -> list[Any]:
    """Four fixed-rate lab records (97.3-185.4 samples per period: no whole number), ``(1 - shrink s)
    tanh(2 cos(wt - 0.4))`` with s from -1/2 to 1/2 over each record, AR(1) noise of marginal sd 0.01."""
    rng = np.random.default_rng([seed, 71])
    out = []
    for i, (spp, periods) in enumerate([(97.3, 40), (121.7, 30), (153.1, 24), (185.4, 16)]):
        om = TWO_PI * (1.0 + 0.3 * i)
        n = int(periods * spp)
        t = np.arange(n) * (TWO_PI / om / spp)
        e = rng.normal(0.0, SD * math.sqrt(1.0 - phi**2), n)
        e[0] = rng.normal(0.0, SD)
        for k in range(1, n):
            e[k] += phi * e[k - 1]
        s = np.arange(n) / n - 0.5
        y = (1.0 - shrink * s) * np.tanh(2.0 * np.cos(om * t - 0.4)) + e
        out.append(bw.Measurement(t, np.cos(om * t), y, nominal_frequency=om))
    return out


def _gate(exps: list[Any]) -> tuple[float, int]:
    """``(cost0, dof0)`` of the gate as ``drift.drift_data`` forms it (its weights and ``_inner``)."""
    c0, dof = 0.0, 0
    for e in exps:
        keep = drift.whole_blocks(e)
        k = e.block_coef.shape[1] - 1
        w = e.block_samples[keep] / e.noise_var
        c = e.block_coef[keep]
        dev = c - (w[:, None] * c).sum(axis=0) / w.sum()
        hw = drift.harmonic_weights(e, k)
        dd = drift.DriftData(
            0, dev, np.zeros(keep.size), w, 0.0, np.zeros(k + 1, np.complex128), w, 0.0, hw=hw
        )
        c0 += float(np.dot(w, drift._inner(dev, dev, hw)))
        dof += dd.dof
    return c0, dof


def _p(c0: float, dof: int) -> float:
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    return float(chdtrc(dof, c0))


@pytest.mark.parametrize("phi", [0.3, 0.8])
def test_a_lab_null_under_ar1_noise_sits_at_its_degrees_of_freedom(phi: float) -> None:
    """Null records: the gate's chi-square over its dof near 1 (one level for all harmonics: 0.5-0.9 at
    phi 0.8; at phi = 0.3 the colour check misses some records and their blocks sat at 1.8)."""
    ratios, levels = [], []
    for seed in range(6):
        exps = data.prepare(_records(phi, seed))
        c0, dof = _gate(exps)
        ratios.append(c0 / dof)
        levels += [e.harmonic_var.size == e.block_coef.shape[1] for e in exps]
    assert 0.9 < float(np.median(ratios)) < 1.1, ratios
    assert max(ratios) < 1.2, ratios
    assert all(levels)  # every lab experiment carries each block harmonic's level


def test_a_shrinking_lab_loop_under_ar1_noise_passes_the_gate() -> None:
    """A loop that shrinks by 5 % over each record under AR(1) noise, phi 0.8: the gate sees the drift in
    every seed (p 1e-8 to 1e-12; one level for all harmonics put the chi-square at 0.4-0.7 of its dof, p =
    1), and the nulls of the same seeds stay above its level."""
    for seed in range(3):
        assert _p(*_gate(data.prepare(_records(0.8, seed, shrink=0.05)))) < 0.025, seed
        assert _p(*_gate(data.prepare(_records(0.8, seed)))) > 0.025, seed


def test_the_blind_degradation_case_drifts_at_the_gate() -> None:
    """The blind bench's ``degradation:10:0`` (seed 2026; fixed-rate lab files, AR(1) noise): the block
    chi-square was 1413 on 1736 (p = 1) over its 8 experiments, the degradation never a candidate; each
    harmonic at its own level it rejects no drift."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
    blind: Any = importlib.import_module("blind")
    tag = (blind.LIBRARY + blind.OUTSIDE + ("null",)).index("degradation")
    seed = int(np.random.SeedSequence([2026, tag, 10, 0]).generate_state(1)[0])
    made = blind.make_case(blind.Case("degradation", 10.0, 0, seed, None, blind.DRIFT))
    assert made["info"]["design"] == "fixed_rate" and made["info"]["noise"] == "ar1"
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, (e, u, y) in enumerate(zip(made["exps"], made["u"], made["y"])):
            paths.append(Path(tmp) / f"run_{i:02d}.csv")
            blind.write_csv(paths[-1], e, u, y)
        exps = data.prepare(bw.load(paths))
    c0, dof = _gate(exps)
    assert c0 > dof and _p(c0, dof) < 0.025, (c0, dof)

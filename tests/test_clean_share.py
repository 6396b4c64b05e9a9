"""The clean-input share of the excess (diagnosis/clean_share.py, review 33 ``clip_cu``).

Viscous damping on u with two of five inputs clipped, through a resonant G: the term's law held on the three
clean experiments, but the clipped experiments' input harmonics (which no device term explains) dwarfed the
pooled excess, the term removed 13 % of it and the verdict was "unexplained". The share on the clean
experiments decides "explained in part" too. Fits are built directly (outputs per experiment) so the rule,
not a noise draw, decides."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from bouc_wen_id.diagnosis import clean_share, run
from bouc_wen_id.diagnosis.law import MIN_CLEAN

N = 64


def _exps(n_clean: int, n_clipped: int) -> list[Any]:
    rng = np.random.default_rng(3)
    out = []
    for i in range(n_clean + n_clipped):
        wave = np.zeros(0) if i < n_clean else np.array([0.05, 0.0])
        out.append(SimpleNamespace(ybar=rng.normal(size=N), weight=1.0, waveform=wave))
    return out


def _fit(exps: list[Any], clean_misfit: float, clipped_misfit: float) -> Any:
    """Outputs leaving a residual of ``clean_misfit`` (per sample, a low harmonic) on the clean experiments
    and ``clipped_misfit`` on the others, beside the exps' unit noise."""
    t = np.arange(N) / N
    outs = []
    for e in exps:
        a = clean_misfit if not e.waveform.size else clipped_misfit
        outs.append(e.ybar - np.random.default_rng(4).normal(size=N) - a * np.sin(6 * np.pi * t))
    return SimpleNamespace(outputs=outs, cost=np.nan)


def test_the_clean_experiments_share_decides_explained_in_part_where_clipped_ones_dwarf_the_excess() -> None:
    """The final model removes the clean experiments' misfit and none of the clipped ones' (10 times
    larger): pooled share far below one half, clean share near one, and the status "partly explained"."""
    exps = _exps(3, 2)
    plain, final = _fit(exps, 3.0, 30.0), _fit(exps, 0.0, 30.0)
    pooled = 0.02
    c = clean_share.share(exps, plain, exps, final)
    assert c > 0.9
    share = clean_share.naming_share(pooled, c)
    assert run.classify(False, True, False, pooled) == "unexplained"
    assert run.classify(False, True, False, share) == "partly explained"
    said = clean_share.text("partly explained", ["a term"], pooled, c, exps)
    assert "on the 3 experiments whose input is a sine" in said and "over all 5, 2 %" in said


def test_a_term_that_leaves_the_clean_misfit_gains_nothing() -> None:
    """A term that removes nothing on the clean experiments: clean share 0, the pooled share stands."""
    exps = _exps(3, 2)
    plain = _fit(exps, 3.0, 30.0)
    c = clean_share.share(exps, plain, exps, plain)
    assert abs(c) < 1e-12 and clean_share.naming_share(0.02, c) == 0.02
    assert clean_share.text("partly explained", ["a term"], 0.02, c, exps) == ""


def test_no_clean_subset_without_enough_clean_or_without_a_clipped_input() -> None:
    """Every input a sine (the pooled share is the clean one), or fewer than MIN_CLEAN clean inputs (the
    law test's own rule: too few to judge alone): NaN, and the pooled share stands."""
    for n_clean, n_clipped in ((5, 0), (MIN_CLEAN - 1, 3)):
        exps = _exps(n_clean, n_clipped)
        c = clean_share.share(exps, _fit(exps, 3.0, 30.0), exps, _fit(exps, 0.0, 30.0))
        assert np.isnan(c) and clean_share.naming_share(0.02, c) == 0.02

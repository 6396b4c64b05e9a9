"""The feedback structure's held-out check and the separating-design search under free DCs (free_dc.py).

Under a wandering baseline or a zero drift taken out, each marked experiment's DC is set, not measured: the
fits leave it free. Before, the feedback's held-out check (``structure._held_out``) fitted its folds on the
set DCs and the separating-design search (``select._separating``) counted a difference of the two models'
DCs that such an experiment cannot see. Both now go through free_dc's projection (``marked``, ``project``,
``centred``); where nothing is marked they are as before. The data are NumPy-made: a first-order lag into a
``tanh`` loop with a second harmonic (no Bouc-Wen loop, not the library's simulator), white noise.
"""

from __future__ import annotations

import importlib
import math
import re
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import free_dc, structure
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.fitting import fit_from, fit_plain, scale_of, scaled, substeps_for
from bouc_wen_id.diagnosis.select import _separating
from bouc_wen_id.timedomain import fit_feedback_sines

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

TWO_PI = 2.0 * math.pi
P = 64


def _marked(exps: list[Any]) -> list[Any]:
    """``exps`` marked as if their period means had been taken out (``harmonic_var[0] = inf``)."""
    out = []
    for e in exps:
        hv = np.full(8, e.noise_var)
        hv[0] = math.inf
        out.append(replace(e, harmonic_var=hv))
    assert all(e.baseline_removed for e in out)
    return out


def _exps(seed: int) -> list[Any]:
    """Four experiments, two amplitudes at each of two frequencies (the feedback's gate needs them): x lags
    u through a first-order G (corner 1.5 rad/s), y = tanh(2 x) plus a second harmonic, with white noise;
    every one marked (:func:`_marked`)."""
    rng = np.random.default_rng([seed, 51])
    recs = []
    for om, amp in ((TWO_PI * 0.4, 0.8), (TWO_PI * 0.4, 1.6), (TWO_PI * 0.9, 0.8), (TWO_PI * 0.9, 1.6)):
        g = 1.0 / (1.0 + 1j * om / 1.5)
        t = np.arange(12 * P) * (TWO_PI / om / P)
        x = amp * abs(g) * np.cos(om * t + np.angle(g))
        y = np.tanh(2.0 * x) + 0.04 * np.cos(2.0 * om * t) + rng.normal(0, 0.01, t.size)
        recs.append(bw.Recording(t, amp * np.cos(om * t), y, amp, om, settle_periods=2))
    return _marked(prepare(recs))


def _diagnosis(exps: list[Any], common: Any) -> Any:
    """What ``structure._held_out`` reads of a diagnosis: its experiments, settings and final fit (the
    free-DC fit of the plain model when ``common`` is not None, as diagnose fits a wandering set)."""
    s = scale_of(exps)
    sx = scaled(exps, s)
    substeps = substeps_for([e.ybar.size for e in sx])
    plain = fit_plain(exps, sx, s, substeps)
    settings: dict[str, Any] = {"scale": {"y": s.y, "u": s.u}, "substeps": substeps}
    if common is not None:
        settings["common_dc"] = common
        sx = free_dc.marked(sx, [True] * len(sx), common)
        plain = fit_from(sx, plain.params, substeps) or plain
    return SimpleNamespace(experiments=tuple(exps), settings=settings, final_fit=plain)


def _shifted(exps: list[Any], k: int, c: float) -> list[Any]:
    return [replace(e, ybar=e.ybar + (c if i == k else 0.0)) for i, e in enumerate(exps)]


def test_the_feedback_held_out_check_does_not_see_a_marked_experiments_dc() -> None:
    """A constant added to one marked experiment's output (its DC is set by the wander's removal, not
    measured) leaves the cascade's and the feedback's held-out costs and NRMSE as they were; before, the
    cascade's folds and the feedback's left-out residual carried it (the shifted fold's cost grew by
    ``weight N c^2``). Without a wander (nothing marked) the shift is seen, as before. The data: the main
    bench's feedback plant (benches/generator.py, its own RK4; seed 5000 at 10x, two amplitudes per
    frequency), where the feedback's refits are well posed (on data it cannot fit, a refit moves by 30 %
    for a change of 1e-9 in the data: nothing is invariant there)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exps = _marked(prepare(gen.make_case("structure", "feedback", "", 10.0, 5000).recordings))
    fit = fit_feedback_sines(
        structure._sines(exps), starts=structure.STARTS, seed=0, max_step=structure.max_step(exps)
    )
    d = _diagnosis(exps, False)
    k, c = 1, 0.3
    a = structure._held_out(d, fit, {})
    b = structure._held_out(replace_exps(d, _shifted(exps, k, c)), fit, {})
    assert a is not None and b is not None and a.folds == b.folds and len(a.folds) == len(exps)
    np.testing.assert_allclose(b.cost_before, a.cost_before, rtol=1e-3)
    np.testing.assert_allclose(b.cost_after, a.cost_after, rtol=1e-3)
    np.testing.assert_allclose(b.nrmse_before, a.nrmse_before, rtol=1e-3)
    np.testing.assert_allclose(b.nrmse_after, a.nrmse_after, rtol=1e-3)
    # Unmarked (no wander): the shift is data, and the left-out fold of that experiment sees it.
    plain = _diagnosis(exps, None)
    u0 = structure._held_out(plain, fit, {})
    u1 = structure._held_out(replace_exps(plain, _shifted(exps, k, c)), fit, {})
    assert u0 is not None and u1 is not None
    grow = exps[k].weight * exps[k].ybar.size * c**2
    assert u1.cost_after[k] - u0.cost_after[k] > 0.5 * grow
    assert u1.cost_before[k] - u0.cost_before[k] > 0.5 * grow


def _sd(text: str) -> float:
    """The predicted difference (noise sd) of a separating design's text."""
    m = re.search(r"predicted difference ([0-9.e+-]+) noise sd", text)
    assert m is not None, text
    return float(m.group(1))


def replace_exps(d: Any, exps: list[Any]) -> Any:
    return SimpleNamespace(experiments=tuple(exps), settings=d.settings, final_fit=d.final_fit)


@pytest.mark.parametrize("common", [False, True])
def test_a_separating_design_does_not_count_a_dc_a_marked_experiment_cannot_see(common: bool) -> None:
    """Two models that differ only by an output offset (a pure DC): at a marked experiment whose DCs are
    all free, no design separates them ("none of the designs tried"); before, every design showed the
    offset as a predicted difference. With the common centre kept (an offset can be named) and without a
    wander the offset separates them, at the same number of noise sd either way."""
    exps = _exps(5)
    d = _diagnosis(exps, None)
    sx = scaled(exps, scale_of(exps))
    substeps = int(d.settings["substeps"])
    fa = replace(d.final_fit, params=d.final_fit.params.with_term("offset", 0.0))
    fb = replace(d.final_fit, params=d.final_fit.params.with_term("offset", 0.2))
    raw = _separating(sx, fa, fb, substeps)
    free = _separating(free_dc.marked(sx, [True] * len(sx), common), fa, fb, substeps)
    assert _sd(raw) > 10.0, raw  # 0.2 on a unit loop, in noise sd
    if common:
        assert free == raw
    else:  # nothing but rounding left of the difference (before: the same text as ``raw``)
        assert free.startswith("none of the designs tried") or _sd(free) < 1e-6, free


def test_nothing_marked_the_separating_design_is_the_models_own_difference() -> None:
    """Without a wander the search is as it was: a real difference (an asymmetry against none) is found at
    some design, with the same words whether the experiments pass through ``marked`` with nothing removed."""
    exps = _exps(7)
    d = _diagnosis(exps, None)
    sx = scaled(exps, scale_of(exps))
    substeps = int(d.settings["substeps"])
    fb = replace(d.final_fit, params=d.final_fit.params.with_term("asymmetry", 0.3))
    text = _separating(sx, d.final_fit, fb, substeps)
    assert "repeated at" in text
    assert _separating(free_dc.marked(sx, [False] * len(sx), False), d.final_fit, fb, substeps) == text

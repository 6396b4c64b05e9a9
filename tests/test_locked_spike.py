"""A spike at the same sample of every period (a disturbance locked to the excitation) is said; the verdict is
read with it bridged. Gaussian noise, a one-period spike and dry friction's sharp step at a reversal are not
said so (task spike43, diagnosis/locked_spike.py).

Data made apart from the benches' generator: the tests' resonant G with a delay (wiener_sim.py) and white
noise, and a first-order G with AR(1) noise (test_spikes_said.py's loop); dry friction through the library's
simulator with a sharp smoothing, the candidates without it so its steps stay in the residual.
"""

from __future__ import annotations

import math
import re
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import locked_spike, outliers

LOCKED = re.compile(
    r"^(\S+) \(experiment \d+\): samples? (\d+)(?:\.\.(\d+))? stands? ([\d.]+) se off every model"
)


def _resonant(seed: int, size_se: float, where: tuple[int, ...], at: int = 37) -> list[Any]:
    """Three records (1, 2, 4 Hz) of wiener_sim's plant, white noise 1 % of the output's rms, and ``size_se``
    standard errors of the averaged period added at sample ``at`` of every period of the records ``where``."""
    from wiener_sim import PERIODS, SETTLE, P, simulate

    freqs = np.array([1.0, 2.0, 4.0])
    h, u, w = simulate(freqs, np.ones(3))
    rng = np.random.default_rng(seed)
    recs = []
    for i, f in enumerate(freqs):
        t = np.arange(w[i].size) * h[i]
        sd = 0.01 * float(np.sqrt(np.mean(w[i] ** 2)))
        y = w[i] + rng.normal(0.0, sd, t.size)
        if i in where:
            y[at::P] += size_se * sd / math.sqrt(PERIODS)
        meta = {"name": f"rec{i}"}
        recs.append(
            bw.Recording(t, u[i], y, 1.0, 2 * math.pi * float(f), settle_periods=SETTLE, metadata=meta)
        )
    return recs


def _diagnose(recs: list[Any], candidates: Any = None) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs, candidates=candidates, held_out_test=False, value_stability=False)


def _said(notes: Any) -> dict[str, tuple[int, int, float]]:
    hits = (LOCKED.match(str(n)) for n in notes)
    return {
        m.group(1): (int(m.group(2)), int(m.group(3) or m.group(2)), float(m.group(4))) for m in hits if m
    }


def test_a_spike_locked_to_every_period_is_said_and_the_verdict_read_without_it() -> None:
    before = _diagnose(_resonant(4301, 0.0, ()))
    assert before.status == "adequate", before.verdict  # the control the spike is put on
    d = _diagnose(_resonant(4301, 20.0, (0, 1, 2)))
    said = _said(d.notes)
    assert set(said) == {"rec0", "rec1", "rec2"} and _said(d.to_dict()["notes"]) == said, d.notes
    assert all(a == b == 37 and 15.0 < z < 25.0 for a, b, z in said.values()), said
    assert "bridged" in d.verdict and d.status == "adequate", d.verdict
    first = [n for n in d.notes if n.startswith("with sample 37 of rec0")]
    assert len(first) == 1 and ": unexplained:" in first[0], d.notes  # the reading with the spike in


def test_a_three_sample_spike_in_one_record_with_ar1_noise_through_a_first_order_g() -> None:
    from test_spikes_said import DESIGN, SD, SETTLE, _ar1, _loop

    rng = np.random.default_rng(4302)
    recs = []
    for i, (amp, om) in enumerate(DESIGN):
        t, u, y = _loop(amp, om)
        y = y + _ar1(rng, y.size)
        if i == 1:
            for k in (90, 91, 92):
                y[k::128] += 12.0 * SD * (1.0 if k != 91 else 1.5)
        meta = {"name": f"rec{i}"}
        recs.append(bw.Recording(t, u, y, amplitude=amp, frequency=om, settle_periods=SETTLE, metadata=meta))
    d = _diagnose(recs, ("offset", "viscous"))
    said = _said(d.notes)
    assert set(said) == {"rec1"} and said["rec1"][:2] == (90, 92), d.notes


def test_gaussian_noise_alone_is_not_said() -> None:
    for seed in (4303, 4304):
        d = _diagnose(_resonant(seed, 0.0, ()))
        assert _said(d.notes) == {} and "bridged" not in d.verdict, (seed, d.notes)


def test_a_spike_in_one_period_is_an_outlier_not_a_locked_disturbance() -> None:
    recs = _resonant(4305, 0.0, ())
    y = np.array(recs[2].y)
    y[12 * 128 + 50] += 0.2 * float(np.max(np.abs(y)))  # one period's sample 50: ~15 se in the average
    recs[2] = bw.Recording(
        recs[2].t, recs[2].u, y, 1.0, recs[2].frequency, settle_periods=8, metadata=recs[2].metadata
    )
    d = _diagnose(recs)
    assert _said(d.notes) == {}, d.notes
    assert any(n.startswith("rec2: 1 sample is an outlier") for n in d.notes), d.notes


def _dry(term: Any) -> tuple[Any, list[Any]]:
    lin = bw.TransferFunction([36.0], [1.0, 3.0, 36.0], delay=0.02)
    plan = bw.SinePlan(
        np.array([2.0, 4.0, 2.0]),
        np.array([0.5, 0.5, 1.0]),
        settle_periods=8,
        periods=16,
        samples_per_period=128,
        substeps=4,
        noise_sd=0.005,
        seed=4306,
    )
    recs = bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.5, 0.3, 1.5), terms=(term,)), plan)
    return _diagnose(recs, ("offset", "viscous")), recs


def test_dry_friction_steps_at_the_reversals_are_not_said() -> None:
    """The step leaves residuals beyond the threshold; the largest of each record lies at a reversal."""
    for term in (T.Coulomb(0.01, smoothing=0.005), T.CoulombX(0.01, smoothing=0.005)):
        d, recs = _dry(term)
        assert d.status != "adequate" and _said(d.notes) == {}, (term, d.notes)
        limit = outliers.threshold(sum(e.ybar.size for e in d.experiments))
        phases = d.final_fit.params.phases
        tops = []
        for i, e in enumerate(d.experiments):
            z = locked_spike._z(e, d.final.outputs[i])
            top = int(np.argmax(np.abs(z)))
            at = np.concatenate(locked_spike._reversals(e, float(phases[i])))
            tops.append(abs(float(z[top])))
            if tops[-1] > limit:
                assert locked_spike._near(top, 1, at, z.size, locked_spike.reversal_window(z.size)), (term, i)
        assert max(tops) > limit, (term, tops)

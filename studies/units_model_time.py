"""What a model fitted in mm/N says of a record in m/kN, and what a fit of a time column in ms gives.

Run from a worktree (``PYTHONPATH=$PWD/python python studies/units_model_time.py``); on a checkout without
``bouc_wen_id.timeunits`` it prints what the old code did with the same data.  The numbers of docs/units.md
come from it.  Data: the library's simulator on a first-order G with a delay and a stiffness term (a chirp),
and sine experiments of another first-order plant (seed 5).
"""

from __future__ import annotations

import importlib.util
import math
import warnings

import bouc_wen_id as bw
import numpy as np

NEW = importlib.util.find_spec("bouc_wen_id.timeunits") is not None


def _plant() -> bw.WienerPlant:
    g = bw.TransferFunction([25.0], [1.0, 25.0], 0.004)
    h = bw.BoucWen(0.6, 0.4, 1.5)
    terms = (bw.terms.Stiffness(0.2),)
    return bw.WienerPlant(g, h, terms, units={"u": "mm", "y": "N"}) if NEW else bw.WienerPlant(g, h, terms)


def model_units() -> None:
    plant = _plant()
    rng = np.random.default_rng(3)
    t = np.arange(3000) / 500.0
    u = 1.2 * np.sin(2 * math.pi * (0.5 + 0.6 * t) * t) * np.minimum(t, 1.0)
    _, _, y = bw.simulate_input(plant, t, u, output=True)
    y = y + 0.01 * float(np.std(y)) * rng.standard_normal(t.size)
    print(f"record in mm/N:  NRMSE {bw.validate(plant, t, u, y).nrmse:.4g}")
    m = bw.Measurement(t, u / 1e3, y / 1e3, units={"u": "m", "y": "kN"}, name="in_m_kN")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        if NEW:
            rep = bw.validate(plant, m)
        else:
            rep = bw.validate(plant, m.t, m.u, m.y)
    print(f"record in m/kN:  NRMSE {rep.nrmse:.4g}  warnings: {[str(w.message) for w in said]}")


def time_in_ms() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([12.0], [1.0, 12.0], 0.01), bw.BoucWen(0.5, 0.5, 2.2))
    plan = bw.SinePlan(
        [3.0, 7.0, 15.0], 0.8, settle_periods=3, periods=6, samples_per_period=80, noise_sd=0.004, seed=5
    )
    recs = bw.simulate(plant, plan)
    ms = [bw.Measurement(r.t * 1e3, r.u, r.y, nominal_frequency=r.frequency) for r in recs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            res = bw.identify(ms)
            print(
                f"t in ms, nominal frequencies {plan.frequencies.tolist()} rad/s: fitted at "
                f"{np.round(res.frequencies, 6).tolist()} rad/s, beta {res.beta:.4g} (true 0.5)"
            )
        except bw.BoucWenIdError as err:
            print(f"t in ms: {type(err).__name__}: {str(err)[:160]}")
        bad = bw.Recording(recs[1].t * 1e3, recs[1].u, recs[1].y, recs[1].amplitude, recs[1].frequency)
        try:
            bw.identify([bad])
        except bw.BoucWenIdError as err:
            print(f"Recording, t in ms: {type(err).__name__}: {str(err)[:160]}")


if __name__ == "__main__":
    model_units()
    time_in_ms()

"""Diagnosis.to_model on reviewer 35's recordings: the fitted term against the diagnosis, held-out NRMSE.

    PYTHONPATH=python:/work/review35 python studies/to_model.py CASE [CASE ...]

CASE is a case of reviewer 35's ``run35.py`` (its own RK4 simulator, seed = crc32 of the case). For each:
``diagnose``, then ``d.to_model(recs)`` (the named terms from their diagnosed values, the declared settling as
lead-in), the fitted terms and G, the residual whiteness, and the held-out NRMSE of the middle experiment
(left out of both fits) for ``to_model`` and for the plain ``fit_time_domain``, after the same lead-in.
"""

from __future__ import annotations

import sys
import time
import warnings

import bouc_wen_id as bw
from bouc_wen_id.timedomain._records import settling_lead_in


def main(cases: list[str]) -> None:
    import run35  # type: ignore[import-not-found]  # reviewer 35's cases, on PYTHONPATH

    warnings.simplefilter("ignore")
    for cid in cases:
        recs, eff = run35.build(cid)
        d = bw.diagnose(recs)
        t0 = time.perf_counter()
        fit = d.to_model(recs)
        print(f"{cid}: truth {eff}; diagnosis {[str(n) for n in d.named]}")
        print(f"  to_model {time.perf_counter() - t0:.1f} s: G {fit.plant.linear}")
        names = fit.parameter_names[len(fit.parameter_names) - len(fit.plant.terms) :]
        for t, name in zip(fit.plant.terms, names):
            print(f"  fitted {t.kind} = {t.value:.5g} +- {fit.standard_errors[name]:.2g}")
        print(f"  RMSE {fit.rmse:.4g}, whiteness p = {fit.adequacy.p_value:.3g}")
        k = len(recs) // 2
        rest, held = recs[:k] + recs[k + 1 :], recs[k]
        lead = settling_lead_in(recs)
        mine = bw.validate(d.to_model(rest), held.t, held.u, held.y, lead_in=lead).nrmse
        plain = bw.validate(bw.fit_time_domain(rest), held.t, held.u, held.y, lead_in=lead).nrmse
        print(f"  held-out experiment {k}: NRMSE to_model {mine:.4g}, plain fit_time_domain {plain:.4g}")


if __name__ == "__main__":
    main(sys.argv[1:])

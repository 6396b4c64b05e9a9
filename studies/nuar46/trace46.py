"""Where strength degradation under AR(2) noise is lost (review 46 failure 2): one case traced.

    PYTHONPATH=python python studies/nuar46/trace46.py CASE_ID [white] [fix]

Builds the case as review 46's driver does, then runs ``bw.diagnose`` with the drift stage and the
per-record trend test watched (no library change): every call of ``run._degradation_first`` (the
degradation test on period blocks, its drift gate and held-out costs) and of ``settling.drift_p`` (each
record's trend test, Holm-adjusted), and the records' noise levels at harmonics 0-3 (``harmonic_var`` over
``noise_var``). ``white`` repeats it with every record's harmonic levels set to its per-sample variance
(the block test and the adequacy test then weigh the noise as white); ``fix`` tries the proposed share
(:func:`_share_fix`).
"""

from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import bouc_wen_id as bw  # noqa: E402
import drive46  # noqa: E402
from bouc_wen_id.diagnosis import run, settling  # noqa: E402

SEEN: dict[str, list[Any]] = {"deg": [], "drift_p": [], "levels": []}


def _watch_degradation() -> None:
    inner = run._degradation_first

    def watched(exps: Any, *a: Any, **k: Any) -> Any:
        out = inner(exps, *a, **k)
        deg = out[0]
        row = {"records": [e.source for e in exps]}
        if deg is not None:
            keep = ("d", "value", "standard_error", "cost0", "cost1", "dof0", "p_adjusted", "share")
            row |= {f: getattr(deg, f) for f in keep}
            row |= {"passed": deg.passed, "drift_present": deg.drift_present, "named": deg.named}
            row |= {"drift_p_value": deg.drift_p_value, "gain_alternative": deg.gain_alternative}
            row |= {"held_out_before": sum(deg.held_out_before), "held_out_after": sum(deg.held_out_after)}
            row["held_out_per_record"] = [
                round(a_ - b_, 2) for b_, a_ in zip(deg.held_out_before, deg.held_out_after)
            ]
            row["term"] = deg.term
            row["cost0_over_dof0"] = deg.cost0 / deg.dof0
            # the proposed share: of the excess over what the term leaves at or above the noise level
            ex = deg.cost0 - min(deg.dof0, deg.cost1)
            row["share_proposed"] = (deg.cost0 - deg.cost1) / ex if ex > 0 else 0.0
        SEEN["deg"].append(row)
        return out

    run._degradation_first = watched  # type: ignore[assignment]


def _watch_drift_p() -> None:
    inner = settling.drift_p

    def watched(exps: Any) -> list[float]:
        out = inner(exps)
        raw = [settling.trend_p(e) for e in exps]
        SEEN["drift_p"].append({e.source: (r, p) for e, r, p in zip(exps, raw, out)})
        if not SEEN["levels"] or len(SEEN["levels"][-1]) != len(exps):
            lv = {e.source: [round(float(v) / e.noise_var, 2) for v in e.harmonic_var[:4]] for e in exps}
            SEEN["levels"].append(lv)
        return out

    settling.drift_p = watched  # type: ignore[assignment]


def _white_levels() -> None:
    """Every record's harmonic levels set to its per-sample variance (the noise weighed as white)."""
    inner = run._noise_floors

    def whitened(items: Any, exps: Any) -> Any:
        out, notes = inner(items, exps)
        flat = [
            replace(
                e,
                harmonic_var=np.full_like(e.harmonic_var, e.noise_var),
                adequacy_var=np.full_like(e.adequacy_var, e.noise_var),
            )
            for e in out
        ]
        return flat, notes

    run._noise_floors = whitened  # type: ignore[assignment]


def _share_fix() -> None:
    """The proposed fix, tried by monkeypatch (no library change): the degradation test's share of the drift
    excess taken over ``c0 - min(dof0, c1)`` (the excess over what the term leaves, or over the noise level
    when it leaves less), so that blocks whose chi-square sits below its dof (levels that overstate the
    noise, as AR(2) colour makes them: calib46.py) no longer read a share of 0."""
    from bouc_wen_id.diagnosis import drift, drift_passes

    inner = drift.degradation_test

    def fixed(*a: Any, **k: Any) -> Any:
        t = inner(*a, **k)
        if t is None:
            return t
        ex = t.cost0 - min(t.dof0, t.cost1)
        share = (t.cost0 - t.cost1) / ex if ex > 0 else 0.0
        ok = math.isfinite(t.p_adjusted) and t.p_adjusted < a[2] and share >= drift.DRIFT_MATERIAL_SHARE
        return replace(t, share=share, passed=bool(ok))

    drift.degradation_test = fixed  # type: ignore[assignment]
    run.degradation_test = fixed  # type: ignore[attr-defined]
    drift_passes.degradation_test = fixed  # type: ignore[attr-defined]


def main(argv: list[str]) -> None:
    cid = argv[1]
    if "fix" in argv[2:]:
        _share_fix()
    if "white" in argv[2:]:
        _white_levels()
    _watch_degradation()
    _watch_drift_p()
    recs, head = drive46.prepare(cid)
    c0 = time.process_time()
    dg = bw.diagnose(recs)
    out = {"id": cid, "white_levels": "white" in argv[2:], "fix": "fix" in argv[2:]}
    out |= {"truth": head["truth"], "status": dg.status}
    out |= {"headline": dg.headline, "named": [(n.term, n.value, n.standard_error) for n in dg.named]}
    out |= {"cpu": time.process_time() - c0, "degradation_calls": SEEN["deg"]}
    out["drift_p_calls"] = [
        {k: [float(f"{r:.3g}"), float(f"{p:.3g}")] for k, (r, p) in c.items() if math.isfinite(p)}
        for c in SEEN["drift_p"][:2]
    ]
    out["levels_over_noise_var_h0_3"] = SEEN["levels"][:1]
    print(json.dumps(out, indent=1, default=str))


if __name__ == "__main__":
    main(sys.argv)

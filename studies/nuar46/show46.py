"""One case's trace (trace46.py's JSON on stdin or a file) as a few lines: the verdict, the named terms
against the truth, each degradation test (value, se, block chi-square over dof, p adj, share as the library
reads it and as proposed, named) and the records whose trend test's Holm p is below 0.1.

    python studies/nuar46/show46.py TRACE.json [...]
"""

from __future__ import annotations

import json
import sys


def show(r: dict) -> str:
    tag = "fix " if r.get("fix") else ""
    out = [f"{tag}{r['id']}: {r['status']} ({r['cpu']:.1f} s cpu) | {r['headline'][:110]}"]
    for term, v, se in r["named"]:
        t = r["truth"].get(term)
        z = f" truth {t:.4g} z {(v - t) / se:+.1f}" if t is not None and se else ""
        out.append(f"   named {term} {v:.4g} +- {se:.2g}{z}")
    for d in r["degradation_calls"]:
        if "d" not in d:
            continue
        out.append(
            f"   deg test on {len(d['records'])} records: {d['value']:.3g} +- {d['standard_error']:.2g}, "
            f"block chi2 {d['cost0']:.0f} -> {d['cost1']:.0f} on {d['dof0']} dof "
            f"({d['cost0_over_dof0']:.2f}), p adj "
            f"{d['p_adjusted']:.2g}, share {d['share']:.2f} (proposed {d['share_proposed']:.2f}), gate "
            f"{d['drift_present']}, held-out {d['held_out_before']:.0f} -> {d['held_out_after']:.0f}, named "
            f"{d['named']}"
        )
    low = {k: v[1] for k, v in (r["drift_p_calls"] or [{}])[0].items() if v[1] < 0.1}
    out.append(f"   trend test, Holm p < 0.1: {low}")
    return "\n".join(out)


if __name__ == "__main__":
    for path in sys.argv[1:]:
        print(show(json.load(open(path))))

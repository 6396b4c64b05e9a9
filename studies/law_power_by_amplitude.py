"""Why a term's law passes when its value should move with amplitude: its per-experiment values and se.

Review 41 (finding 2): a Duffing spring (k3 x^3) across the hysteretic element was named a linear
``stiffness@x`` whose law (one k for every experiment, ``law.law_test``) passed at p = 0.75. This runs the
diagnosis on a directory of recordings and, each time the law of ``--term`` is tested, prints the term's
value freed per experiment (the law test's own Gauss-Newton step, ``law.freed_step``) with its sandwich se,
twice: as the law test has it (each experiment's own |G| and phase free), and with the per-experiment |G|
and phase held at the fit (their Jacobian columns zeroed), to see whether the value trades with |G|.

Usage::

    python studies/law_power_by_amplitude.py DIR [--term stiffness@x]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from bouc_wen_id.cli import main as cli_main
from bouc_wen_id.diagnosis import law, select
from bouc_wen_id.terms import StiffnessX


def per_experiment(exps: Sequence[Any], fit: Any, term: str, substeps: int) -> list[tuple[float, float]]:
    """The term's value per experiment and its se (the law test's freed step); [] where it has none."""
    step = law.freed_step(exps, fit, term, substeps)
    if step is None:
        return []
    beta, cov, scale, cols = step
    k0 = float(fit.params.values[fit.params.terms.index(term)])
    c = cols[0]
    se = np.sqrt(np.diag(cov)[c]) / scale[c]
    return [(k0 + float(b), float(s)) for b, s in zip(beta[c] / scale[c], se)]


def run(data: str, term: str) -> None:
    orig_test, orig_out = law.law_test, law.augmented_output

    def held(*args: Any, **kw: Any) -> Any:
        out = orig_out(*args, **kw)
        return dataclasses.replace(out, own_jacobian=np.zeros_like(out.own_jacobian))

    def probe(exps: Sequence[Any], fit: Any, t: str, substeps: int) -> float:
        p = orig_test(exps, fit, t, substeps)
        if t != term:
            return p
        free = per_experiment(exps, fit, t, substeps)
        law.augmented_output = held  # type: ignore[assignment]
        try:
            fixed = per_experiment(exps, fit, t, substeps)
        finally:
            law.augmented_output = orig_out  # type: ignore[assignment]
        print(f"law of {t}: p = {p:.3g}", file=sys.stderr)
        for i, e in enumerate(exps):
            a = f"  exp {i}: U = {e.amplitude:.3g}, w = {e.frequency:.3g}, |G| = {fit.params.gains[i]:.3g}"
            if free:
                a += f"; value {free[i][0]:.4g} +- {free[i][1]:.3g} (|G| free)"
            if fixed:
                a += f", {fixed[i][0]:.4g} +- {fixed[i][1]:.3g} (|G| held)"
            print(a, file=sys.stderr)
        return p

    law.law_test = select.law_test = probe  # type: ignore[assignment]
    with tempfile.TemporaryDirectory() as tmp:
        cli_main(["diagnose", data, "--no-figures", "--json", str(Path(tmp) / "d.json")])


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--term", default=StiffnessX.kind)
    a = ap.parse_args()
    run(a.data, a.term)

"""Parameters that follow the coil current of the MR damper (issue #21 item 3), proved by held-out level.

The shipped MR damper data (``../shared/data/real/mr-damper-utfsm``: six files, 0.25-5 Hz, each with five
DAQ blocks at 0, 0.25, 0.5, 0.75 and 1 A) are reduced to one averaged period per file and current. The model
is the augmented Wiener-Bouc-Wen of design.md 9.1 with an output offset, a viscous damping and a parallel
stiffness on the measured displacement (the Spencer-like terms the diagnosis names at several currents),
one gain and phase per file; every experiment is weighted as ``1 / (P var(ybar))``, so the cost is the sum
of the squared NRMSEs.

1. **Per-level fits** (:func:`bouc_wen_id.augmented.fit_augmented`, each current alone): in-sample NRMSE per
   file, and the **held-out-file** NRMSE (design.md 10.4: the physics fitted on the other five files, the
   held-out file's own gain and phase refitted with it frozen).
2. **Operating-point fits** (:mod:`bouc_wen_id.operating`): every parameter a polynomial of degree 0, 1 or 2
   in the current, or a monotone spline (``"monotone"``: quadratic between the extreme currents, held
   beyond, its slope of one sign), one joint fit over the levels. Leave one current out: fit on the other
   four, predict the held-out current **whole** (every parameter from its polynomial) and **with its own (g,
   phi) refitted** (the physics predicted, as the held-out-file protocol). The form is the one with the lowest
   mean held-out score (the same folds choose it: one choice among four).
3. The chosen form fitted on all five currents: each parameter against current with 95 % intervals
   (``docs/real-data/operating-parameters.png``), the per-level fits' values beside them.

Writes ``docs/real-data-operating.md`` (every number from this run), ``docs/real-data/operating.json`` and
the figure.

Usage: ``python studies/operating_point.py [--data DIR] [--degrees 0,1,2,monotone] [--quiet] [--from-json]
[--reuse-levels]``.
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import operating as op
from bouc_wen_id import terms as T
from bouc_wen_id.augmented import AugExperiment, AugParams, fit_augmented

REPO = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the sibling modules import by name (studies/ is not a package)
    sys.path.insert(0, str(HERE))
#: The model's terms: offset, viscous damping and parallel stiffness on the measured displacement.
TERMS = (T.Offset.kind, T.Viscous.kind, T.Stiffness.kind)
#: The gains relative to the yield level (the knee's travel follows it: ``fit_operating(relative_gains=)``).
RELATIVE_GAINS = True
#: The coordinates plotted, with their labels (the own gains and phases are left out of the figure).
PLOTTED = (
    ("w_u", "w_u = yield force (N)"),
    ("log_mu_minus_1", "log(mu - 1)"),
    ("log_rho", "log rho, rho = (beta - gamma)/(beta + gamma)"),
    (T.Offset.kind, "offset y0 (N)"),
    (T.Viscous.kind, "viscous c (N s/mm)"),
    (T.Stiffness.kind, "stiffness k (N/mm)"),
)


#: The page's description of the method (Markdown).
MODEL_PROSE = """\
**Model.** The augmented Wiener-Bouc-Wen model (design.md 9.1) with an output offset, a viscous damping
and a parallel stiffness on the measured displacement, one gain and phase per file; each experiment
weighted `1/(P var(ybar))` (the cost is the sum of squared NRMSEs). **Operating fit:** every parameter
(the saturation level `w_u = (beta + gamma)^(-1/mu)`, `log(mu - 1)`, `log rho` with `rho = (beta -
gamma)/(beta + gamma)`, the three terms, and each file's `log g` and `phi`) a polynomial in the current
(degree 0, 1 or 2) or a monotone spline (*monotone*: Ramsay's quadratic I-splines of knots at the extreme
fitted currents, held at its end values beyond them (no extrapolation); its two slope coefficients held
to the sign of the joint degree-1 fit's slope, which also starts it), one joint fit over the currents.
**Held-out level:** fit on four currents, predict the fifth *whole* (every parameter from its polynomial)
or with each file's own (g, phi) refitted to it and the physics predicted (*own refit*, the held-out
protocol of design.md 10.4). **Per level:** the fit of that current alone (*in-sample*) and its
held-out-file NRMSE (physics from the other five files, the file's (g, phi) refitted)."""

#: The page's note under the figure (Markdown; ``{d}`` the chosen form).
FIGURE_PROSE = """\
The figure: the {d} fit on all five currents (line), and the monotone spline's when another form is chosen
(dashed), each with its 95 % interval (band: the delta method
on the Gauss-Newton covariance scaled by the residual variance, i.e. the misfit taken as white noise,
which it is not: the bands are narrower than the model error warrants), and the per-level fits (dots).
0 A and 1 A held out are extrapolations (the monotone spline holds the nearest fitted current's values
there). `log(mu - 1)` and `log rho`: the joint fit runs to the edges
mu -> 1 (a sharp knee) and beta = gamma (rho -> 0), where the loop no longer depends on them (their bands
are the Gauss-Newton's, near zero because the gradient vanishes, not a measured precision); the
per-level fits end on beta = gamma too (their dots sit at the start's floor, log 1e-3). A form whose
fit fails to predict a held-out current (the model refuses the extrapolated parameters: *fails*) scores
infinity."""


def _adapters() -> Any:
    """The data sets' adapters (the sibling ``_adapters.py``)."""
    import _adapters

    return _adapters


def experiments(data: Path) -> tuple[list[float], list[list[AugExperiment]], list[str]]:
    """Per current, the six files' averaged periods as augmented-fit experiments (equal weight each)."""
    A = _adapters()
    blocks = [A.load_mr_damper(data / A.DATASETS["mr-damper"] / f) for f in A.MR_FILES]
    levels, out = [], []
    for k, current in enumerate(A.MR_CURRENTS):
        row = []
        for b in blocks:
            ap = bw.average_measurement(b[k])[0]
            ybar = np.asarray(ap.ybar, dtype=np.float64) + float(ap.offset_y)
            row.append(
                AugExperiment(
                    ybar=ybar,
                    amplitude=float(ap.amplitude),
                    frequency=float(ap.frequency),
                    grid_phase=0.0,
                    weight=1.0 / (ybar.size * float(np.var(ybar))),
                    source=str(ap.source),
                )
            )
        levels.append(float(current))
        out.append(row)
    return levels, out, [Path(f).stem for f in A.MR_FILES]


def level_fit(exps: list[AugExperiment]) -> AugParams:
    """One current alone, from a start read off the loops (yield force, a knee at 10 % of the stroke)."""
    fy = 0.8 * float(np.median([0.5 * np.ptp(e.ybar) for e in exps]))
    mu = 1.5
    s = fy ** (-mu)
    gains = np.array([fy / (0.1 * abs(e.amplitude)) for e in exps])
    offset = float(np.mean([np.mean(e.ybar) for e in exps]))
    start = AugParams(0.5 * s, 0.45 * s, mu, TERMS, np.array([offset, 0.0, 0.0]), gains, np.zeros(len(exps)))
    return fit_augmented(exps, start).params


def held_out_files(exps: list[AugExperiment], fit: AugParams) -> list[float]:
    """design.md 10.4 on one current: the physics on the other files, the held-out file's (g, phi)
    refitted."""
    out = []
    for i in range(len(exps)):
        keep = [j for j in range(len(exps)) if j != i]
        start = AugParams(
            fit.beta, fit.gamma, fit.mu, fit.terms, fit.values, fit.gains[keep], fit.phases[keep]
        )
        try:
            phys = fit_augmented([exps[j] for j in keep], start).params
        except bw.BoucWenIdError:
            out.append(math.nan)
            continue
        full = AugParams(phys.beta, phys.gamma, phys.mu, phys.terms, phys.values, fit.gains, fit.phases)
        out.append(op.nrmse(exps[i], op.refit_own(exps[i], full, i), i))
    return out


def _own_refit_nrmse(exps: list[AugExperiment], params: AugParams) -> list[float]:
    return [op.nrmse(e, op.refit_own(e, params, i), i) for i, e in enumerate(exps)]


def form_label(d: Any) -> str:
    """How the page names a form: ``degree-2 polynomial``, ``monotone spline``."""
    return "monotone spline" if str(d) == op.MONOTONE else f"degree-{d} polynomial"


def parse_forms(text: str) -> list[op.Form]:
    return [f if f == op.MONOTONE else int(f) for f in (t.strip() for t in text.split(","))]


def run(data: Path, degrees: list[op.Form], log: Any, reuse: bool = False) -> dict[str, Any]:
    t0 = time.time()
    levels, exps, files = experiments(data)
    doc: dict[str, Any] = {"levels_A": levels, "files": files, "terms": list(TERMS), "degrees": degrees}
    cache = REPO / "docs" / "real-data" / "operating-levels.pkl"
    if reuse and cache.is_file():
        fits, per_level = pickle.loads(cache.read_bytes())
        log(f"per-level fits read from {cache.name} (a previous run of this script)")
    else:
        fits, per_level = [], []
        for lv, ex in zip(levels, exps):
            fit = level_fit(ex)
            fits.append(fit)
            ins = [op.nrmse(e, fit, i) for i, e in enumerate(ex)]
            hof = held_out_files(ex, fit)
            per_level.append({"in_sample": ins, "held_out_file": hof, "params": _params_dict(fit)})
            log(
                f"[{time.time() - t0:.0f} s] per-level fit {lv:g} A: NRMSE {np.round(ins, 3)}, "
                f"held-out file {np.round(hof, 3)}"
            )
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_bytes(pickle.dumps((fits, per_level)))
    doc["per_level"] = per_level
    lolo: dict[str, Any] = {}
    for d in degrees:
        rows = []
        for out in range(len(levels)):
            keep = [j for j in range(len(levels)) if j != out]
            try:
                fit = op.fit_operating(
                    [levels[j] for j in keep],
                    [exps[j] for j in keep],
                    [fits[j] for j in keep],
                    d,
                    relative_gains=RELATIVE_GAINS,
                )
                pred = fit.params_at(levels[out])
                whole = [op.nrmse(e, pred, i) for i, e in enumerate(exps[out])]
                own = _own_refit_nrmse(exps[out], pred)
            except bw.BoucWenIdError as exc:
                whole, own = [math.inf] * len(files), [math.inf] * len(files)
                log(f"  degree {d}, {levels[out]:g} A held out: {type(exc).__name__}: {exc}")
            rows.append({"held_out_A": levels[out], "whole": whole, "own_refit": own})
            log(
                f"[{time.time() - t0:.0f} s] degree {d}, {levels[out]:g} A held out: whole "
                f"{np.round(whole, 3)}, own (g, phi) refitted {np.round(own, 3)}"
            )
        lolo[str(d)] = rows
    doc["held_out_level"] = lolo
    score = {d: float(np.mean([np.mean(np.square(r["whole"])) for r in lolo[str(d)]])) for d in degrees}
    best = min(score, key=lambda d: (score[d], op.n_basis(d), d == op.MONOTONE))
    doc["score"] = {str(d): v for d, v in score.items()}
    doc["degree"] = best
    doc["final"] = _final(levels, exps, fits, best)
    if op.MONOTONE in degrees and best != op.MONOTONE:
        # The spline fitted on all five currents too, drawn beside the chosen form (its own intervals).
        doc["final_monotone"] = _final(levels, exps, fits, op.MONOTONE)
    doc["seconds"] = time.time() - t0
    log(f"[{doc['seconds']:.0f} s] {form_label(best)} chosen (mean held-out NRMSE^2 {score})")
    return doc


def _final(levels: list[float], exps: list[list[AugExperiment]], fits: list[AugParams], form: op.Form) -> Any:
    """``form`` fitted on every current: its cost, in-sample NRMSEs and each plotted coordinate's curve
    ``(value, low, high)`` (95 %) on a grid of the current."""
    final = op.fit_operating(levels, exps, fits, form, relative_gains=RELATIVE_GAINS)
    grid = np.linspace(levels[0], levels[-1], 41)
    return {
        "cost": final.cost,
        "in_sample": [
            [op.nrmse(e, final.params_at(lv), i) for i, e in enumerate(ex)] for lv, ex in zip(levels, exps)
        ],
        "curves": {name: [list(final.interval(name, float(v))) for v in grid] for name, _ in PLOTTED},
        "grid_A": grid.tolist(),
    }


def _params_dict(p: AugParams) -> dict[str, Any]:
    shared, log_g, phi = op.coordinates_of(p)
    names = op.HYSTERESIS_COORDINATES + tuple(p.terms)
    return {
        "beta": p.beta,
        "gamma": p.gamma,
        "mu": p.mu,
        "coordinates": dict(zip(names, shared.tolist())),
        "gains": p.gains.tolist(),
        "phases": p.phases.tolist(),
    }


def figure(doc: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(13, 7))
    grid = np.array(doc["grid_A"] if "grid_A" in doc else doc["final"]["grid_A"])
    for ax, (name, label) in zip(axes.ravel(), PLOTTED):
        curve = np.array(doc["final"]["curves"][name])
        ax.plot(grid, curve[:, 0], color="C0", label=f"{form_label(doc['degree'])} in the current, joint fit")
        ax.fill_between(grid, curve[:, 1], curve[:, 2], color="C0", alpha=0.25, label="95 % interval")
        if "final_monotone" in doc:
            lo, hi = ax.get_ylim()  # the chosen form's scale: a coordinate at an edge may lie far off it
            mono = np.array(doc["final_monotone"]["curves"][name])
            ax.plot(grid, mono[:, 0], "--", color="C2", label="monotone spline, joint fit (not chosen)")
            ax.fill_between(grid, mono[:, 1], mono[:, 2], color="C2", alpha=0.12, label="its 95 % interval")
            off = mono[:, 0].max() < lo - (hi - lo) or mono[:, 0].min() > hi + (hi - lo)
            if off:
                ax.text(0.03, 0.05, f"spline off scale: {np.median(mono[:, 0]):.3g}", transform=ax.transAxes)
                ax.set_ylim(lo, hi)
        pts = [lv["params"]["coordinates"][name] for lv in doc["per_level"]]
        ax.plot(doc["levels_A"], pts, "o", color="C1", label="per-level fit")
        ax.set_xlabel("coil current (A)")
        ax.set_title(label, fontsize=10)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("MR damper: each parameter against coil current (studies/operating_point.py)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _fmt(v: float) -> str:
    return "fails" if not math.isfinite(v) else f"{v:.3f}"


def page(doc: dict[str, Any]) -> str:
    d = doc["degree"]
    lines = [
        "# MR damper: parameters that follow the coil current",
        "",
        "Generated by `python studies/operating_point.py` (bouc_wen_id "
        f"{bw.__version__}, {doc['seconds']:.0f} s; the per-level fits may come from a previous run's cache,",
        "`--reuse-levels`); every number below is from that run. Issue #21 item 3;",
        "the method is `bouc_wen_id.operating` (module docstring).",
        "",
        *MODEL_PROSE.splitlines(),
        "",
        f"**Form chosen by held-out level: {form_label(d)}** (mean squared held-out NRMSE per form: "
        + ", ".join(f"{form_label(k)}: {v:.4g}" for k, v in doc["score"].items())
        + "; the same folds choose it, one choice among the forms tried).",
        "",
        "| current | file | per-level in-sample | per-level held-out file | "
        + " | ".join(f"held-out level, {form_label(k)} (whole / own refit)" for k in doc["score"])
        + " |",
        "|---|---|---|---|" + "---|" * len(doc["score"]),
    ]
    for k, lv in enumerate(doc["levels_A"]):
        for i, f in enumerate(doc["files"]):
            per, held = doc["per_level"][k], doc["held_out_level"]
            cells = [
                f"{_fmt(held[deg][k]['whole'][i])} / {_fmt(held[deg][k]['own_refit'][i])}"
                for deg in doc["score"]
            ]
            lines.append(
                f"| {lv:g} A | {f} | {_fmt(per['in_sample'][i])} | {_fmt(per['held_out_file'][i])} | "
                + " | ".join(cells)
                + " |"
            )
    med = {
        deg: [float(np.median(doc["held_out_level"][deg][k]["whole"])) for k in range(len(doc["levels_A"]))]
        for deg in doc["score"]
    }
    lines += [
        "",
        "Median over the six files, per current (in-sample / held-out file / held-out level whole at the "
        "chosen form): "
        + "; ".join(
            f"{lv:g} A: {np.median(doc['per_level'][k]['in_sample']):.3f} / "
            f"{np.nanmedian(doc['per_level'][k]['held_out_file']):.3f} / {med[str(d)][k]:.3f}"
            for k, lv in enumerate(doc["levels_A"])
        )
        + ".",
        "",
        "![parameters against current](real-data/operating-parameters.png)",
        "",
        *FIGURE_PROSE.format(d=form_label(d)).splitlines(),
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    A = _adapters()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--degrees", default="0,1,2,monotone", help="polynomial degrees and/or 'monotone'")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument(
        "--reuse-levels",
        action="store_true",
        help="take the per-level fits from docs/real-data/operating-levels.pkl (a previous run) if present",
    )
    ap.add_argument(
        "--from-json",
        action="store_true",
        help="rewrite the page and figure from docs/real-data/operating.json (a run), fitting nothing",
    )
    args = ap.parse_args(argv)
    out = REPO / "docs" / "real-data"
    if args.from_json:
        doc = json.loads((out / "operating.json").read_text(encoding="utf-8"))
        figure(doc, out / "operating-parameters.png")
        (REPO / "docs" / "real-data-operating.md").write_text(page(doc), encoding="utf-8")
        return 0
    if not (args.data / A.DATASETS["mr-damper"]).is_dir():
        raise SystemExit(f"error: {args.data / A.DATASETS['mr-damper']} not found (the shipped real data)")
    log = (lambda s: None) if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    warnings.simplefilter("ignore")
    doc = run(args.data, parse_forms(args.degrees), log, args.reuse_levels)
    out.mkdir(parents=True, exist_ok=True)
    (out / "operating.json").write_text(json.dumps(doc, indent=1, default=float) + "\n", encoding="utf-8")
    figure(doc, out / "operating-parameters.png")
    (REPO / "docs" / "real-data-operating.md").write_text(page(doc), encoding="utf-8")
    print(
        "wrote docs/real-data-operating.md, docs/real-data/operating.json, "
        "docs/real-data/operating-parameters.png"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

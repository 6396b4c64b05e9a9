"""The diagnosis on the four real data sets of ``../shared/data/real``: what is named, what is not, where.

For each data set the files are diagnosed jointly (one Bouc-Wen element and one set of physical terms
shared by every experiment, one |G| and phase per experiment); the MR damper once per coil current, across
its six files. Writes ``docs/real-data/diagnosis-*.png`` (loops and residual over the cycle, plain against
final), ``docs/real-data/diagnosis.json`` and ``docs/real-data-diagnosis.md`` (the findings, generated:
every number in it comes from this run).

Across current levels: the MR damper's levels are also diagnosed with ONE structure (``bw.diagnose_across``:
each candidate added at every level at once, its value free per level; the levels' own diagnoses reused),
written as the page's section "Across current levels" and ``docs/real-data/diagnosis-across.json``. Each
level's own terms there are read against its stability check (``across_stable.checked``): a term only some
preprocessing variants name is listed as that level's alternative, not its finding, as its verdict says.

Stability: every group is diagnosed again under preprocessing variants (:data:`VARIANTS`: the steady stretch
without its last or first third, half the harmonics kept in the averaged period); a term named in every
variant is a finding, one that comes and goes is listed as an alternative (``--no-stability`` skips them).

Usage: ``python studies/diagnose_real.py [--data DIR] [--datasets mr-damper,friction-damper,...]
[--no-stability] [--quiet]`` (progress on stderr unless ``--quiet``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
from bouc_wen_id.diagnosis import stability as stab
from bouc_wen_id.diagnosis.report import plot_harmonics, plot_loops, plot_residual_cycle
from bouc_wen_id.diagnosis.result import clean
from bouc_wen_id.diagnosis.verdict_text import details, headline

REPO = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the sibling modules import by name (studies/ is not a package)
    sys.path.insert(0, str(HERE))


def _adapters() -> Any:
    """The data sets' adapters (the sibling ``_adapters.py``)."""
    import _adapters

    return _adapters


def groups(data: Path, datasets: list[str]) -> list[tuple[str, str, list[bw.Measurement]]]:
    """(data set, group label, measurements) for every joint diagnosis."""
    A = _adapters()
    out: list[tuple[str, str, list[bw.Measurement]]] = []
    if "mr-damper" in datasets:
        blocks = [A.load_mr_damper(data / A.DATASETS["mr-damper"] / f) for f in A.MR_FILES]
        for k, current in enumerate(A.MR_CURRENTS):
            out.append(("mr-damper", f"{current:g} A", [b[k] for b in blocks]))
    if "friction-damper" in datasets:
        ms = [A.load_friction_damper(data / A.DATASETS["friction-damper"] / f) for f in A.FRICTION_FILES]
        out.append(("friction-damper", "all tests", ms))
    if "wire-rope" in datasets:
        ms = [A.load_wire_rope(data / A.DATASETS["wire-rope"] / f) for f in A.WIRE_ROPE_FILES]
        out.append(("wire-rope", "all files", ms))
    if "bh-microwire" in datasets:
        ms = [A.load_bh_loop(data / A.DATASETS["bh-microwire"] / f) for f in A.BH_FILES]
        out.append(("bh-microwire", "50-250 kHz", ms))
    return out


#: Preprocessing variants of the stability check (the library's, diagnosis/stability.py): (key, description).
VARIANTS = stab.VARIANTS


def variant_items(ms: list[bw.Measurement], variant: str) -> list[Any]:
    """One preprocessing variant's experiments (:func:`bouc_wen_id.diagnosis.stability.variant_items`)."""
    return stab.variant_items(ms, variant)


def figure(d: bw.Diagnosis, path: Path, title: str) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12.0, 3.4), dpi=90)
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(1, 3, i) for i in (1, 2, 3)]
    plot_loops(d, axes[0])
    plot_residual_cycle(d, axes[1])
    plot_harmonics(d, axes[2])
    fig.suptitle(title, fontsize=9)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.16, top=0.88, wspace=0.3)
    fig.savefig(path)


def _row(dataset: str, label: str, d: bw.Diagnosis, y_unit: str = "") -> dict[str, Any]:
    ho = d.held_out
    return {
        "dataset": dataset,
        "group": label,
        "y_unit": y_unit,
        "experiments": len(d.experiments),
        "status": d.status,
        "verdict": d.verdict,
        "main_status": d.status,
        "main_verdict": d.verdict,
        "named": [t.to_dict() for t in d.named],  # after the stability check: its findings only
        "named_main_run": [t.to_dict() for t in d.named],
        "partial": [t.to_dict() for t in d.partial],
        "plain_chi2_dof": d.plain.cost / max(d.plain.dof, 1),
        "final_chi2_dof": d.final.cost / max(d.final.dof, 1),
        "explained_fraction": d.explained_fraction,
        "insample_nrmse_plain": list(d.plain.nrmse),
        "insample_nrmse_final": list(d.final.nrmse),
        "held_out": None if ho is None else ho.to_dict(),
        "where_plain": d.before.describe(),
        "where_final": d.after.describe(),
        "seconds": d.seconds,
        "steps": [s.to_dict() for s in d.steps],
        "degradation": None if d.degradation is None else d.degradation.to_dict(),
        "notes": list(getattr(d, "notes", ()) or ()),
        "skipped": dict(d.settings.get("skipped", {}) or {}),
    }


def _count_of(r: dict[str, Any], term: str) -> str:
    """ "k of n": how many of the completed runs named ``term`` (the row's stability record)."""
    st = r.get("stability") or {}
    k = next((len(t["named_in"]) for t in st.get("terms", ()) if t["term"] == term), 0)
    return f"{k} of {len(st.get('completed', ()))}"


def _table_verdict(verdict: str) -> str:
    """The table's cell: the verdict's headline, and a pointer to its further clauses in the section."""
    more = len(details(verdict))
    return headline(verdict) + (f" (+{more} further clause{'s' if more > 1 else ''} below)" if more else "")


def _median(v: list[float]) -> float:
    s = sorted(x for x in v if math.isfinite(x))
    if not s:
        return math.nan
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


INTRO = """\
# Diagnosis of the real data (generated by `studies/diagnose_real.py`)

Every number on this page comes from one run of `{command}` on the code as it is
(commit {commit}): the main run took {wall:.0f} s wall on the 2-core machine (the diagnoses {diag:.0f} s, the
figures {figs:.0f} s; per group in its section), {stab}. Load average {load0:.1f} at the start and
{load:.1f} at the end (2 cores; this run itself adds about 1): {machine}.
Each group is diagnosed jointly: one Bouc-Wen element and one set of candidate terms shared by its
experiments, one |G| and phase per experiment. A term is named only if it passes the nested F-test
(Bonferroni over the candidates), removes at least 10 % of the excess misfit and lowers the held-out cost
(each experiment left out in turn, physics fitted on the others). See `docs/diagnosis.md` for the method.
"""

STABLE_INTRO = """\
The verdicts below (table and sections) are the main run's read against the preprocessing variants
(`bouc_wen_id.diagnosis.stability`): a term the main run names but a completed variant does not is said as
an alternative, not a finding, with its count; a term only some variants name is said likewise; a variant
that failed is not counted and is said. Each section keeps the main run's own verdict when it differs."""

UNCHECKED_INTRO = """\
The preprocessing variants were not run (`--no-stability`): the verdicts are the main run's, their
stability under preprocessing not checked."""


def _stability_lines(rows: list[dict[str, Any]]) -> list[str]:
    with_st = [r for r in rows if r.get("stability")]
    if not with_st:
        return []
    lines = [
        "",
        "## Stability under preprocessing",
        "",
        "Each group diagnosed again under each variant: "
        + "; ".join(f"**{k}**: {v}" for k, v in VARIANTS)
        + ". A term named in every variant that completed is a finding; one that comes and goes is an "
        "alternative, not a finding.",
        "",
        "| data set | group | status per variant | findings (named in every variant) "
        "| alternatives (named in k of n variants) |",
        "|---|---|---|---|---|",
    ]
    for r in with_st:
        st = r["stability"]
        n = len(st["completed"])
        status = ", ".join(f"{v}: {s}" for v, s in {stab.MAIN: r["main_status"], **st["variants"]}.items())
        count = {t["term"]: len(t["named_in"]) for t in st["terms"]}
        alts = ", ".join(f"{t} ({count[t]} of {n})" for t in st["alternatives"])
        lines.append(
            f"| {r['dataset']} | {r['group']} | {status} | {', '.join(st['findings']) or 'none'} "
            f"| {alts or 'none'} |"
        )
    return lines


def _machine_state(load_start: float) -> str:
    """How loaded the machine was when the run started (before the run's own load)."""
    if not math.isfinite(load_start):
        return "the machine's load is unknown"
    if load_start < 1.0:
        return "a quiet machine, so the times are this code's own"
    return "the machine was shared with other jobs, so the times are those of a loaded machine"


def markdown(
    rows: list[dict[str, Any]], timing: dict[str, float], command: str = "", commit: str = ""
) -> str:
    stab = (
        f"the stability variants another {timing['stability']:.0f} s"
        if any(r.get("stability") for r in rows)
        else "the stability variants not run"
    )
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    intro = INTRO.format(
        machine=_machine_state(timing.get("load_start", math.nan)),
        wall=timing["wall"],
        diag=timing["diagnoses"],
        figs=timing["figures"],
        stab=stab,
        load=load,
        load0=timing.get("load_start", math.nan),
        command=command or "python studies/diagnose_real.py",
        commit=commit or "unknown",
    ).splitlines()
    intro += ["", *(STABLE_INTRO if any(r.get("stability") for r in rows) else UNCHECKED_INTRO).splitlines()]
    lines = [
        *intro,
        "",
        "| data set | group | exps | verdict | plain chi2/dof | final chi2/dof | excess explained "
        "| held-out NRMSE plain -> final (median) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ho = r["held_out"]
        hot = "-"
        if ho:
            hot = f"{_median(ho['nrmse_before']):.3f} -> {_median(ho['nrmse_after']):.3f}"
        lines.append(
            f"| {r['dataset']} | {r['group']} | {r['experiments']} | {_table_verdict(r['verdict'])} "
            f"| {r['plain_chi2_dof']:.3g} | {r['final_chi2_dof']:.3g} "
            f"| {100 * r['explained_fraction']:.0f} % | {hot} |"
        )
    lines += _stability_lines(rows)
    lines += ["", "## Per group", ""]
    for r in rows:
        lines.append(f"### {r['dataset']}, {r['group']}")
        lines.append("")
        lines.append(f"**{r['status']}**: {headline(r['verdict'])}")
        lines.append("")
        lines += [f"- {c}" for c in details(r["verdict"])]
        lines += [""] if details(r["verdict"]) else []
        lines.append(f"- diagnosed in {r['seconds']:.1f} s")
        st = r.get("stability")
        if st:
            named = ", ".join(
                f"{t['term']} in {len(t['named_in'])} of {len(st['completed'])}"
                for t in sorted(st["terms"], key=lambda t: str(t["term"]))
            )
            lines.append(f"- named under the preprocessing variants: {named or 'nothing'}")
            if r["verdict"] != r["main_verdict"]:
                lines.append(
                    f"- the main run's own verdict (before the stability check): {r['main_verdict']}"
                )
        lines.append(f"- where the plain model misses: {r['where_plain'] or 'nowhere above the noise'}")
        lines.append(f"- where the final model misses: {r['where_final'] or 'nowhere above the noise'}")
        for k, st in enumerate(r["steps"], 1):
            tried = ", ".join(
                f"{t['term']} (share {t['share_of_excess']:.2f}"
                + (
                    f", held-out {'better' if t['held_out']['improves'] else 'worse'}"
                    if t["held_out"]
                    else ""
                )
                + ")"
                for t in sorted(st["trials"], key=lambda t: -(t["share_of_excess"] or 0))[:4]
                if t["share_of_excess"] is not None
            )
            lines.append(f"- step {k}: chosen **{st['chosen'] or 'none'}**; best candidates: {tried}")
        deg = r.get("degradation")
        if deg:
            yu = r.get("y_unit") or "[y]"
            du = f"1/({yu})^2" if " " in yu else f"1/{yu}^2"
            # The drift term tested first: strength (delta_nu) or stiffness (delta_eta) degradation.
            sym = next(k for k in ("delta_nu", "delta_eta") if k in deg)
            lines.append(
                f"- {deg.get('term', 'degradation')} (drift space, period blocks): {sym} = {deg[sym]:.3g} "
                f"± {deg['standard_error']:.2g} {du}, p = {deg['p_adjusted']:.2g} (Bonferroni), "
                f"share of the drift excess {deg['share_of_drift_excess']:.2f}, held-out "
                f"{'better' if deg['held_out_improves'] else 'worse'}: "
                f"{'named in the main run' if deg['named'] else 'not named'}"
                + (
                    f", an alternative under preprocessing ({_count_of(r, deg.get('term', ''))}: the verdict)"
                    if deg["named"] and deg.get("term") in (r.get("stability") or {}).get("alternatives", ())
                    else ""
                )
                + (f" (a negative {sym} is a stiffening, not a degradation)" if deg[sym] < 0 else "")
            )
        for why in r.get("notes", []):
            lines.append(f"- note: {why}")
        for term, why in r.get("skipped", {}).items():
            lines.append(f"- {term} not tested: {why}")
        ho = r["held_out"]
        if ho:
            pairs = ", ".join(f"{b:.3f} -> {a:.3f}" for b, a in zip(ho["nrmse_before"], ho["nrmse_after"]))
            lines.append(f"- held-out NRMSE per left-out experiment (plain -> final): {pairs}")
        slug = f"diagnosis-{r['dataset']}-{r['group'].replace(' ', '').replace('.', 'p')}.png"
        lines += ["", f"![{r['dataset']} {r['group']}](real-data/{slug})", ""]
    return "\n".join(lines) + "\n"


def across_candidates(ds: list[bw.Diagnosis]) -> list[str]:
    """The across-levels candidates: every steady term some level named (or tried as partial), at both of
    its places. The joint selection costs about what the per-level selections cost together; the study's
    budget (at most ~20 s beside the main run) allows the terms the levels themselves point at, not all."""
    from bouc_wen_id.diagnosis.drift import DRIFT_TERMS
    from bouc_wen_id.diagnosis.select import siblings
    from bouc_wen_id.terms import DIAGNOSIS_CANDIDATES, TERMS

    out: list[str] = []
    for d in ds:
        for t in (*d.named, *d.partial):
            for k in (t.term, *siblings(t.term)) if t.term in TERMS else ():
                if k not in out and k not in DRIFT_TERMS and k in DIAGNOSIS_CANDIDATES:
                    out.append(k)
    return out


def mr_across(mr: list[tuple[str, list[bw.Measurement], Any]], progress: bool) -> Any:
    """``bw.diagnose_across`` on the MR damper's levels, each given as (label, its measurements, its own
    diagnosis): the candidates are the steady terms the levels' own diagnoses named or tried
    (:func:`across_candidates`). Called by :func:`across_levels` and by ``benches/real_verdicts.py``."""
    A = _adapters()
    own = [d for _, _, d in mr]
    currents = [float(A.MR_CURRENTS[[f"{c:g} A" for c in A.MR_CURRENTS].index(lab)]) for lab, _, _ in mr]
    units = mr[0][1][0].units
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(
            [ms for _, ms, _ in mr],
            currents,
            labels=[lab for lab, _, _ in mr],
            candidates=across_candidates(own),
            per_condition=own,
            y_unit=units.get("y", ""),
            u_unit=units.get("u", ""),
            progress=progress,
        )


def across_levels(
    loaded: list[tuple[str, str, list[bw.Measurement]]], rows: list[dict[str, Any]], quiet: bool
) -> tuple[Any, float]:
    """The MR damper's current levels diagnosed across (bw.diagnose_across), reusing each level's own
    diagnosis (its prepared experiments and plain fit); (result or None, seconds)."""
    mr = [(lab, ms, r) for (ds, lab, ms), r in zip(loaded, rows) if ds == "mr-damper" and "runs" in r]
    if len(mr) < 2:
        return None, 0.0
    if not quiet:
        print("-- mr-damper across current levels", file=sys.stderr)
    a = mr_across([(lab, ms, r["runs"]["as recorded"]) for lab, ms, r in mr], progress=not quiet)
    print(f"mr-damper across levels: {a.verdict} ({a.seconds:.1f} s)")
    return a, a.seconds


def across_checked(
    a: Any, loaded: list[tuple[str, str, list[bw.Measurement]]], rows: list[dict[str, Any]]
) -> Any:
    """``a`` with each level's own terms read against its stability check (``across_stable.checked``: a term
    only some preprocessing variants name is that level's alternative, not its finding, as its verdict
    says); ``a`` as it is when the variants were not run."""
    from bouc_wen_id.diagnosis import across_stable

    checks = {lab: r.get("check") for (ds, lab, _), r in zip(loaded, rows) if ds == "mr-damper"}
    if a is None or not any(checks.values()):
        return a
    return across_stable.checked(a, [checks.get(c.label) for c in a.conditions])


def _per_level(c: Any, by_label: dict[str, dict[str, Any]]) -> str:
    """A level's own structure: its findings, then its alternatives with their counts (k of n variants)."""
    own = ", ".join(c.per_level_terms or ()) or "none"
    r = by_label.get(c.label, {})
    alts = [f"{t} ({_count_of(r, t)}): an alternative, not a finding" for t in c.per_level_alternatives]
    return "; ".join([own, *alts])


def across_markdown(a: Any, seconds: float, rows: list[dict[str, Any]] | None = None) -> str:
    """The section "Across current levels" of the page (docs/diagnosis.md, "Across conditions")."""
    lines = [
        "",
        "## Across current levels",
        "",
        "The MR damper's five current levels diagnosed with one structure (`bw.diagnose_across`, "
        f"{seconds:.0f} s, each level's own experiments and plain fit reused): a candidate is added at every "
        "level at once, its value free per level, chosen by the combined F test (Bonferroni over the "
        "candidates), the summed share and the held-out cost summed over the levels. Candidates: "
        + ", ".join(a.settings["candidates"])
        + " (every steady term some level's own diagnosis named or tried, at both places).",
        "",
        f"**{headline(a.verdict)}**",
        "",
        *(f"- {c}" for c in details(a.verdict)),
        *([""] if details(a.verdict) else []),
    ]
    if a.terms:
        head = (
            "| term | "
            + " | ".join(c.label for c in a.conditions)
            + " | smooth in the current (p per degree) | one shared value (refitted; F test) |"
        )
        lines += [head, "|---" * (len(a.conditions) + 3) + "|"]
        for t in a.terms:
            cells = [
                f"{v:.3g} ± {se:.2g}" + ("" if pr else " (not needed)")
                for v, se, pr in zip(t.values, t.standard_errors, t.present)
            ]
            ps = ", ".join(f"{d}: {p:.2g}" for d, p in enumerate(t.smooth_p))
            deg = "none" if t.smooth_degree is None else f"degree {t.smooth_degree}"
            sf = t.shared_fit
            one = (
                "-"
                if sf is None
                else f"{'shared' if sf.shared else 'varies'}: {sf.value:.3g} ± {sf.standard_error:.2g}, "
                f"p {f'= {sf.p_value:.2g}' if sf.p_value > 0 else '< 1e-300'}"
            )
            lines.append(
                f"| {t.label} ({t.symbol}, {t.unit}) | " + " | ".join(cells) + f" | {deg} ({ps}) | {one} |"
            )
        lines.append("")
    lines += [
        "| level | chi2/dof plain -> joint | held-out NRMSE plain | joint structure | per-level structure "
        "(its terms) |",
        "|---|---|---|---|---|",
    ]
    by_label = {r["group"]: r for r in rows or () if r.get("dataset") == "mr-damper"}
    for c in a.conditions:
        own = _per_level(c, by_label)
        lines.append(
            f"| {c.label} | {c.plain_chi2_dof:.3g} -> {c.final_chi2_dof:.3g} | {c.held_out_plain:.3f} "
            f"| {c.held_out_joint:.3f} | {c.held_out_per_level:.3f} ({own}) |"
        )
    lines.append(
        "\nHeld-out NRMSE: the median over the left-out experiments (physics fitted on the others, only the "
        "left-out one's |G| and phase refitted). Standard errors are inflated by sqrt(chi2/dof) of each "
        f"level's fit; 'not needed' marks a level whose own F test (alpha / {len(a.conditions)}) does not "
        "ask for the term."
        + (
            " The per-level structure lists a level's findings; a term its own diagnosis named but only some "
            "preprocessing variants name is said as an alternative (named in k of n variants), as its "
            "verdict says it."
            if any(c.per_level_alternatives for c in a.conditions)
            else ""
        )
    )
    return "\n".join(lines) + "\n"


def _diagnose(items: list[Any], units: Any, progress: bool) -> bw.Diagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(items, y_unit=units.get("y", ""), u_unit=units.get("u", ""), progress=progress)


def _commit() -> str:
    """The checked-out commit (with "+ uncommitted changes" when the code, not the docs this study writes,
    differs from it), or "unknown"."""
    import subprocess

    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "python", "rust", "studies"],
            cwd=REPO,
            capture_output=True,
            text=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return f"{head} + uncommitted changes" if dirty else head


def main(argv: list[str] | None = None) -> int:
    A = _adapters()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--datasets", default="mr-damper,friction-damper,wire-rope,bh-microwire")
    ap.add_argument("--docs", type=Path, default=REPO / "docs")
    ap.add_argument("--no-stability", action="store_true", help="skip the preprocessing variants")
    ap.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        print(f"error: the real data are not at {args.data}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    rows = []
    figs = args.docs / "real-data"
    figs.mkdir(parents=True, exist_ok=True)
    loaded = groups(args.data, args.datasets.split(","))
    t_main = t_figs = 0.0
    for dataset, label, ms in loaded:
        units = ms[0].units
        if not args.quiet:
            print(f"-- {dataset} {label}", file=sys.stderr)
        try:
            d = _diagnose(ms, units, progress=not args.quiet)
        except bw.BoucWenIdError as exc:
            print(f"{dataset} {label}: refused: {type(exc).__name__}: {exc}")
            rows.append({"dataset": dataset, "group": label, "error": f"{type(exc).__name__}: {exc}"})
            continue
        t_main += d.seconds
        print(f"{dataset} {label}: {d.verdict} ({d.seconds:.1f} s)")
        slug = f"diagnosis-{dataset}-{label.replace(' ', '').replace('.', 'p')}.png"
        tf = time.perf_counter()
        figure(d, figs / slug, f"{dataset}, {label}: {d.status}")
        t_figs += time.perf_counter() - tf
        rows.append(_row(dataset, label, d, units.get("y", "")))
        rows[-1]["runs"] = {"as recorded": d}
    across, t_across = across_levels(loaded, rows, quiet=args.quiet)
    wall = time.perf_counter() - t0
    t1 = time.perf_counter()
    if not args.no_stability:
        for (dataset, label, ms), r in zip(loaded, [r for r in rows]):
            if "error" in r:
                continue
            for variant, _ in VARIANTS[1:]:
                if not args.quiet:
                    print(f"-- {dataset} {label}, variant {variant}", file=sys.stderr)
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        items = variant_items(ms, variant)
                    r["runs"][variant] = _diagnose(items, ms[0].units, False)
                except bw.BoucWenIdError as exc:
                    r["runs"][variant] = f"refused: {type(exc).__name__}"
            main_d = r["runs"].pop(stab.MAIN)
            st = stab.stability(main_d, r["runs"])
            r["runs"][stab.MAIN] = main_d
            r.update(status=st.status, verdict=st.verdict, stability=st.to_dict(), check=st)
            r["named"] = [t for t in r["named_main_run"] if t["term"] not in st.alternatives]
            print(
                f"{dataset} {label}: named in how many of {len(st.completed)} completed variants: "
                + stab.describe(st)
                + (f"; verdict revised: {st.verdict}" if st.verdict != main_d.verdict else "")
            )
    across = across_checked(across, loaded, rows)  # a level's alternatives said as such (across_stable.py)
    for r in rows:
        r.pop("runs", None)
        r.pop("check", None)
    wall_stab = time.perf_counter() - t1
    timing = {
        "wall": wall,
        "diagnoses": t_main,
        "figures": t_figs,
        "stability": wall_stab,
        "across": t_across,
        "load_start": load0,
    }
    ok = [r for r in rows if "error" not in r]
    (figs / "diagnosis.json").write_text(json.dumps(clean(rows), indent=1, allow_nan=False))
    command = "python studies/diagnose_real.py " + " ".join(argv if argv is not None else sys.argv[1:])
    page = markdown(ok, timing, command.strip(), _commit())
    if across is not None:
        page += across_markdown(across, t_across, ok)
        (figs / "diagnosis-across.json").write_text(
            json.dumps(clean(across.to_dict()), indent=1, allow_nan=False)
        )
    refused = [r for r in rows if "error" in r]
    if refused:
        page += (
            "\n## Refused\n\n"
            + "\n".join(f"- {r['dataset']} {r['group']}: {r['error']}" for r in refused)
            + "\n"
        )
    (args.docs / "real-data-diagnosis.md").write_text(page)
    print(
        f"wrote {args.docs / 'real-data-diagnosis.md'} (main run {wall:.0f} s, diagnoses {t_main:.0f} s "
        f"and figures {t_figs:.0f} s; stability variants {wall_stab:.0f} s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The real-data page: tables, the prose template and the rendering of ``docs/real-data.md``.

Works on ``results.json`` alone (the dictionary :mod:`real_data` writes), so the page can be regenerated
without the data: ``python studies/real_data.py --doc-only``.  The prose is ``real_data.md.in``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Optional

from bouc_wen_id.validation import z_value

TWO_PI = 2.0 * math.pi
#: Two-sided 95 % normal quantile.
Z95 = z_value(0.95)
#: The library's default mu bracket (identify's mu_bracket), which the page quotes.
MU_BRACKET = (1.0, 10.0)
DATASET_ORDER = ("mr-damper", "friction-damper", "wire-rope", "bh-microwire")
DATASET_TITLES = {
    "mr-damper": "MR damper (UTFSM, MTS machine)",
    "friction-damper": "Banded rotary friction damper with backlash (ARTS-Lab BRFD)",
    "wire-rope": "Wire-rope isolator on a shaker (SUPMECA)",
    "bh-microwire": "B-H loops of an amorphous microwire (DYK-Team)",
}


def _wrap_pi(phi: float) -> float:
    """A phase in (-pi, pi]."""
    return math.pi - (math.pi - phi) % TWO_PI


def _g(v: Optional[float], digits: int = 4) -> str:
    if v is None or not math.isfinite(v):
        return "-"
    return f"{v:.{digits}g}"


def _ci(est: Optional[dict[str, Any]], digits: int = 4) -> str:
    if not est or est.get("value") is None:
        return "-"
    text = _g(est["value"], digits)
    if est.get("ci95"):
        lo, hi = est["ci95"]
        text += f" [{_g(lo, 3)}, {_g(hi, 3)}]"
    return text


def _phase_ci(est: Optional[dict[str, Any]]) -> str:
    """A phase and its interval on the branch (-pi, pi]."""
    if not est or est.get("value") is None:
        return "-"
    v = _wrap_pi(est["value"])
    text = f"{v:.3f}"
    if est.get("se") is not None:
        text += f" ± {Z95 * est['se']:.2g}"
    return text


def _outcome_cell(ident: dict[str, Any]) -> str:
    if ident["outcome"] == "identified":
        text = "identified"
        if ident.get("constraint"):
            text += f", **on {ident['constraint']}**"
        if list(ident["mu_bracket"]) != list(MU_BRACKET):
            text += f", mu in ({ident['mu_bracket'][0]:g}, {ident['mu_bracket'][1]:g}]"
        return text
    err = ident["error"]
    why = err["class"]
    if err["class"] == "SearchAtBoundError" and err.get("lower") is not None:
        why += " (mu -> 1)" if err["lower"] else f" (mu -> {err['bound']:g})"
    if ident["outcome"] == "library bug":
        why = f"**library bug**: {why}"
    return f"refused: {why}"


def _warn_cell(rec: dict[str, Any]) -> str:
    cats: dict[str, int] = {}
    for part in (rec.get("preprocessing", {}), rec.get("averaged", {}), rec.get("identification", {})):
        for w in part.get("warnings", []) if part else []:
            cats[w["category"]] = cats.get(w["category"], 0) + 1
    return ", ".join(sorted(cats)) or "-"


def _adequacy_cell(ident: dict[str, Any]) -> str:
    a = ident.get("adequacy")
    if not a:
        return "-"
    return f"{_g(a['ratio'], 3)} ({a['dof']} dof), p = {_g(a['p_value'], 2)}"


def data_table(recs: Sequence[dict[str, Any]]) -> list[str]:
    rows = [
        "| experiment | kept / dropped | f found (Hz) | vs nominal | periods | samples/period | input THD "
        "| noise sd | output lead (deg) | linear NRMSE |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in recs:
        pre = r.get("preprocessing", {})
        kept = len(pre.get("kept", []))
        reasons: dict[str, int] = {}
        for _, _, why in pre.get("dropped", []):
            reasons[why] = reasons.get(why, 0) + 1
        dropped = ", ".join(f"{k}" + (f" x{v}" if v > 1 else "") for k, v in sorted(reasons.items())) or "-"
        seg = "" if r.get("segment") in (0, None) else f" #{r['segment']}"
        if r.get("frequency_hz") is None:
            err = r.get("error", {})
            rows.append(f"| {r['label']}{seg} | refused ({err.get('class', '?')}) | | | | | | | | |")
            continue
        av = r.get("averaged", {})
        unit = r["units"]["y"].split(" ")[0]
        off = r["frequency_offset_pct"]
        off_cell = "-" if off is None else f"{off:+.3f} %"
        rows.append(
            f"| {r['label']}{seg} | {kept} / {dropped} | {r['frequency_hz']:.6g} "
            f"| {off_cell} "
            f"| {r['periods']:.2f} | {r['samples_per_period']:.2f} | {_g(r['input']['thd'], 2)} "
            f"| {_g(av.get('noise_sd'), 3)} {unit} | {_g(av.get('output_phase_lead_deg'), 3)} "
            f"| {_g(av.get('linear_nrmse'), 3)} |"
        )
    return rows


def ident_table(recs: Sequence[dict[str, Any]]) -> list[str]:
    rows = [
        "| experiment | outcome | beta [95 %] | gamma [95 %] | mu [95 %] | \\|G\\| [95 %] | phi (rad) ± 95 % "
        "| NRMSE | adequacy chi2/dof, p | cross-check NRMSE (mu, phi) | warnings |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in recs:
        seg = "" if r.get("segment") in (0, None) else f" #{r['segment']}"
        ident = r.get("identification")
        xc = r.get("crosscheck")
        xc_cell = "-"
        if xc:
            xc_cell = f"{xc['nrmse']:.3g} ({xc['mu']:.3g}, {_wrap_pi(xc['phase']):.2f})"
            if xc.get("constraint"):
                xc_cell += f", {xc['constraint']}"
        if ident is None:
            err = r.get("error", {})
            rows.append(
                f"| {r['label']}{seg} | refused before identification: {err.get('class', '?')} "
                f"| | | | | | | | | {_warn_cell(r)} |"
            )
            continue
        if ident["outcome"] != "identified":
            rows.append(
                f"| {r['label']}{seg} | {_outcome_cell(ident)} | | | | | | | | {xc_cell} | {_warn_cell(r)} |"
            )
            continue
        e = ident["experiments"][0]
        rows.append(
            f"| {r['label']}{seg} | {_outcome_cell(ident)} | {_ci(ident['beta'], 3)} "
            f"| {_ci(ident['gamma'], 3)} "
            f"| {_ci(ident['mu'], 3)} | {_ci(e['gain'], 4)} | {_phase_ci(e['phase'])} | {_g(e['nrmse'], 3)} "
            f"| {_adequacy_cell(ident)} | {xc_cell} | {_warn_cell(r)} |"
        )
    return rows


def joint_table(joints: Sequence[dict[str, Any]]) -> list[str]:
    rows: list[str] = []
    for j in joints:
        ident = j["identification"]
        tried = ", ".join(
            f"ref {a['reference']}: "
            + (f"cost {_g(a['cost'], 4)}" if a["outcome"] == "identified" else a.get("error", a["outcome"]))
            for a in j["attempts"]
        )
        rows.append(
            f"**Joint fit, {j['label']}** ({len(j['members'])} experiments). References tried: {tried}."
        )
        rows.append("")
        if j["status"] != "identified":
            rows.append(f"Refused for every reference: {', '.join(j.get('errors', []))}.")
            err = ident.get("error")
            if err:
                rows.append(f"With reference 0: `{err['class']}: {err['message']}`")
            rows.append("")
            continue
        rows.append(
            f"{_outcome_cell(ident)} with reference {ident['reference']}: beta = {_ci(ident['beta'], 3)}, "
            f"gamma = {_ci(ident['gamma'], 3)}, mu = {_ci(ident['mu'], 3)}; adequacy "
            f"{_adequacy_cell(ident)}."
        )
        rows.append("")
        rows.append("| experiment | f (Hz) | \\|G\\| [95 %] | phi (rad) ± 95 % | NRMSE |")
        rows.append("|---|---|---|---|---|")
        for name, e in zip(j["members"], ident["experiments"]):
            rows.append(
                f"| {name} | {e['frequency_hz']:.5g} | {_ci(e['gain'], 4)} | {_phase_ci(e['phase'])} "
                f"| {_g(e['nrmse'], 3)} |"
            )
        warns = sorted({w["category"] for w in ident.get("warnings", [])})
        if warns:
            rows.append("")
            rows.append(f"Warnings: {', '.join(warns)}.")
        rows.append("")
    return rows


def summary_table(recs_all: Sequence[dict[str, Any]], joints: Sequence[dict[str, Any]]) -> list[str]:
    """One row per data set: what was identified, refused, and how well anything fits."""
    rows = [
        "| data set | experiments | identified (on a constraint) | refused (error) | library NRMSE "
        "| cross-check NRMSE | linear NRMSE | joint fits identified |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for dataset in DATASET_ORDER:
        recs = [r for r in recs_all if r["dataset"] == dataset]
        if not recs:
            continue
        ident = [r for r in recs if r.get("status") == "identified"]
        on_c = [r for r in ident if r["identification"].get("constraint")]
        errors: dict[str, int] = {}
        for r in recs:
            if r.get("status") != "identified":
                err = (r.get("identification") or r).get("error", {})
                key = err.get("class", "?")
                if key == "SearchAtBoundError":
                    key += ", mu -> 1" if err.get("lower") else ", mu upper end"
                errors[key] = errors.get(key, 0) + 1
        refused = "; ".join(f"{v} ({k})" for k, v in sorted(errors.items())) or "0"
        js = [j for j in joints if j["dataset"] == dataset]
        rows.append(
            f"| {DATASET_TITLES[dataset]} | {len(recs)} | {len(ident)} ({len(on_c)}) | {refused} "
            f"| {_range([_lib_nrmse(r) for r in ident], '.3g')} "
            f"| {_range([r['crosscheck']['nrmse'] for r in recs if r.get('crosscheck')], '.3g')} "
            f"| {_range([r['averaged']['linear_nrmse'] for r in recs if r.get('averaged')], '.3g')} "
            f"| {sum(j['status'] == 'identified' for j in js)} of {len(js)} |"
        )
    return rows


def tally(recs: Sequence[dict[str, Any]]) -> str:
    """One sentence: how many experiments were identified, on a constraint, refused and why."""
    n = len(recs)
    ident = [r for r in recs if r.get("status") == "identified"]
    on_c = [r for r in ident if r["identification"].get("constraint")]
    refused: dict[str, int] = {}
    for r in recs:
        if r.get("status") == "identified":
            continue
        err = (r.get("identification") or r).get("error", {})
        key = err.get("class", "?")
        if key == "SearchAtBoundError":
            key += " (mu -> 1)" if err.get("lower") else " (mu at the upper end)"
        refused[key] = refused.get(key, 0) + 1
    parts = [f"{len(ident)} of {n} experiments identified"]
    if ident:
        parts[-1] += f" ({len(on_c)} of them on a Bouc-Wen constraint)"
    if refused:
        parts.append("refused: " + ", ".join(f"{v} x {k}" for k, v in sorted(refused.items())))
    bugs = [r for r in recs if r.get("status") == "library bug"]
    if bugs:
        parts.append(f"**{len(bugs)} library bug(s)**")
    nr = [r["identification"]["experiments"][0]["nrmse"] for r in ident]
    if nr:
        parts.append(f"library NRMSE {_range(nr, '.3g')}")
    xc = [r["crosscheck"]["nrmse"] for r in recs if r.get("crosscheck")]
    if xc:
        parts.append(f"cross-check NRMSE {_range(xc, '.3g')}")
    lin = [r["averaged"]["linear_nrmse"] for r in recs if r.get("averaged")]
    if lin:
        parts.append(f"best linear (spring + dashpot) NRMSE {_range(lin, '.3g')}")
    return "; ".join(parts) + "."


#: The page's prose, in a Markdown template next to this script (sections named like the keys below).
TEMPLATE = Path(__file__).with_name("real_data.md.in")


def prose() -> dict[str, str]:
    """The template's sections, by name (``intro``, ``mr_prose_before``, ..., ``rough_edges``)."""
    sections: dict[str, list[str]] = {}
    current: Optional[list[str]] = None
    for line in TEMPLATE.read_text(encoding="utf-8").splitlines():
        if line.startswith("<!-- section: ") and line.endswith(" -->"):
            current = sections.setdefault(line[len("<!-- section: ") : -len(" -->")], [])
        elif current is not None:
            current.append(line)
    return {name: "\n".join(body).strip("\n") + "\n" for name, body in sections.items()}


def _range(values: Sequence[Optional[float]], fmt: str, unit: str = "") -> str:
    vals = [float(v) for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return "-"
    lo, hi = min(vals), max(vals)
    a, b = f"{lo:{fmt}}", f"{hi:{fmt}}"
    if a == b:
        return f"{a}{unit}"
    return f"{a} to {b}{unit}" if lo < 0 else f"{a}-{b}{unit}"


def _lib_nrmse(r: dict[str, Any]) -> Optional[float]:
    ident = r.get("identification") or {}
    if ident.get("outcome") != "identified":
        return None
    value: Optional[float] = ident["experiments"][0]["nrmse"]
    return value


def _adeq_ratio(r: dict[str, Any]) -> Optional[float]:
    ident = r.get("identification") or {}
    a = ident.get("adequacy") if ident.get("outcome") == "identified" else None
    return None if not a else a["ratio"]


def _section_facts(dataset: str, recs: Sequence[dict[str, Any]]) -> dict[str, str]:
    ok = [r for r in recs if r.get("frequency_hz") is not None]
    av = [r for r in ok if r.get("averaged")]
    xcs = [r["crosscheck"] for r in av if r.get("crosscheck")]
    ident = [r for r in av if _lib_nrmse(r) is not None]
    mu1 = [
        r
        for r in av
        if r["identification"]["outcome"] == "refused" and r["identification"]["error"].get("lower")
    ]
    facts = {
        "freq_range": _range([r["frequency_offset_pct"] for r in ok], ".2f", " %"),
        "periods_range": _range([r["periods"] for r in ok], ".0f", " periods"),
        "lead_range": _range([r["averaged"]["output_phase_lead_deg"] for r in av], ".0f"),
        "lin_range": _range([r["averaged"]["linear_nrmse"] for r in av], ".2f"),
        "lib_range": _range([_lib_nrmse(r) for r in ident], ".3g"),
        "lib_phi_range": _range(
            [_wrap_pi(r["identification"]["experiments"][0]["phase"]["value"]) for r in ident], ".2f"
        ),
        "adeq_range": _range([_adeq_ratio(r) for r in ident], ".3g"),
        "xc_range": _range([x["nrmse"] for x in xcs], ".3g"),
        "xc_mu_range": _range([x["mu"] for x in xcs], ".2f"),
        "xc_phi_range": _range([_wrap_pi(x["phase"]) for x in xcs], ".2f"),
        "n_ident": str(len(ident)),
        "n_mu1": str(len(mu1)),
    }
    if dataset == "mr-damper":
        for key, current in (("f0", "0"), ("f1", "1")):
            amps = [
                0.5 * r["averaged"]["output_peak_to_peak"]
                for r in av
                if r["metadata"]["coil_current_A"] == current
            ]
            facts[key] = _range(amps, ".0f")
    if dataset == "friction-damper":
        sweep = [r for r in av if "0.5amplitude" in r["file"] and r.get("crosscheck")]
        facts["xc_gain_sweep"] = ", ".join(f"{r['crosscheck']['gain']:.3g}" for r in sweep) + " kip/in"
        facts["fr15_periods"] = _range([r["periods"] for r in ok if "1.5amplitude" in r["file"]], ".2f")
        facts["fr_freq"] = f"{max((abs(r['frequency_offset_pct']) for r in ok), default=math.nan):.3f} %"
    if dataset == "wire-rope":
        prov = {"16Hz_A2": 93, "18Hz_A2": 230, "20Hz_A2": 196, "22Hz_A2": 238, "18Hz_A4": 122, "22Hz_A4": 216}
        facts["freqs"] = ", ".join(f"{r['frequency_hz']:.3f}" for r in ok)
        facts["offsets"] = _range([r["frequency_offset_pct"] for r in ok], ".2f", " %")
        facts["distorted"] = str(
            sum(
                any(w["category"] == "DistortedInputWarning" for w in r["preprocessing"]["warnings"])
                for r in ok
            )
        )
        facts["prov_periods"] = "/".join(str(prov.get(r["label"], "?")) for r in ok)
        facts["kept_periods"] = "/".join(f"{r['periods']:.0f}" for r in ok)
        for key, level in (("lead_a2", "A2"), ("lead_a4", "A4")):
            leads = [
                r["averaged"]["output_phase_lead_deg"]
                for r in av
                if r["metadata"]["amplitude_level"] == level
            ]
            facts[key] = _range(leads, ".0f")
    if dataset == "bh-microwire":
        facts["kept"] = "/".join(f"{r['periods']:.0f}" for r in ok)
        facts["freqs"] = ", ".join(f"{r['frequency_hz'] / 1e3:.2f}" for r in ok)
    return facts


def _bracket_facts(recs_all: Sequence[dict[str, Any]]) -> dict[str, str]:
    retried = [r for r in recs_all if r.get("first_attempt")]
    parts = []
    for r in retried:
        ident = r["identification"]
        if ident["outcome"] == "identified":
            e = ident["experiments"][0]
            parts.append(f"{r['label']} then gave mu = {ident['mu']['value']:.3g} (NRMSE {e['nrmse']:.3g})")
        else:
            err = ident["error"]
            where = f"mu -> {err['bound']:g}" if err.get("bound") is not None else err["class"]
            parts.append(f"{r['label']} was refused again ({err['class']}, {where})")
    mu1 = [
        r
        for r in recs_all
        if r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    xc1 = [r for r in mu1 if r.get("crosscheck") and r["crosscheck"]["mu_at_lower_bound"]]
    return {
        "retries": "; ".join(parts) if parts else "none was needed",
        "n_mu1": str(len(mu1)),
        "xc_mu1": str(len(xc1)),
    }


def _rough_facts(recs_all: Sequence[dict[str, Any]]) -> dict[str, str]:
    ident = [r for r in recs_all if _lib_nrmse(r) is not None]
    on_c = [r for r in ident if r["identification"].get("constraint")]
    worse = [r for r in ident if (_lib_nrmse(r) or 0.0) >= 0.8]
    branch = [
        r for r in worse if r.get("crosscheck") and r["crosscheck"]["nrmse"] < 0.5 * (_lib_nrmse(r) or 0.0)
    ]
    ex_branch = "none"
    if branch:
        r = min(branch, key=lambda r: r["crosscheck"]["nrmse"] / (_lib_nrmse(r) or 1.0))
        e = r["identification"]["experiments"][0]
        ex_branch = (
            f"{r['label']}: library NRMSE {e['nrmse']:.3g} with phi = "
            f"{_wrap_pi(e['phase']['value']):.2f} rad, cross-check {r['crosscheck']['nrmse']:.3g} with "
            f"phi = {_wrap_pi(r['crosscheck']['phase']):.2f} rad"
        )
    mr_mu1 = [
        r
        for r in recs_all
        if r["dataset"] == "mr-damper"
        and r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    interior = [r for r in mr_mu1 if r.get("crosscheck") and r["crosscheck"]["mu"] > 1.2]
    mu1_all = [
        r
        for r in recs_all
        if r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    profile_mu1 = [
        r
        for r in mu1_all
        if r["profile"]["outcome"] == "refused" and r["profile"]["error"]["class"] == "SearchAtBoundError"
    ]
    ex_interior = ", ".join(f"{r['label']}: mu = {r['crosscheck']['mu']:.2f}" for r in interior[:3]) or "none"
    prov = {"16Hz_A2": 93, "18Hz_A2": 230, "20Hz_A2": 196, "22Hz_A2": 238, "18Hz_A4": 122, "22Hz_A4": 216}
    trims = [
        f"{r['label']}: {r['periods']:.0f} of {prov[r['label']]} periods kept"
        for r in recs_all
        if r["dataset"] == "wire-rope"
        and r.get("periods")
        and r["label"] in prov
        and r["periods"] < 0.9 * prov[r["label"]]
    ]
    return {
        "n_constraint": str(len(on_c)),
        "n_ident": str(len(ident)),
        "ex_constraint": ", ".join(r["label"] for r in on_c[:3]) or "none",
        "n_worse": str(len(worse)),
        "ex_worse": ", ".join(f"{r['label']} {_lib_nrmse(r):.3g}" for r in worse[:4]) or "none",
        "ex_branch": ex_branch,
        "n_interior": str(len(interior)),
        "n_mu1_all": str(len(mu1_all)),
        "n_profile_mu1": str(len(profile_mu1)),
        "n_mu1_mr": str(len(mr_mu1)),
        "ex_interior": ex_interior,
        "ex_trim": "; ".join(trims) or "none",
    }


def operating_section(path: Path) -> list[str]:
    """The MR damper's held-out-current table (issue 21) from ``operating.json``, the run of
    ``studies/operating_point.py`` that also wrote docs/real-data-operating.md; nothing when it is absent."""
    import json
    import statistics

    if not path.is_file():
        return []
    op = json.loads(path.read_text(encoding="utf-8"))
    form = op["degree"]
    label = "monotone spline" if form == "monotone" else f"degree-{form} polynomial"
    held = op["held_out_level"][str(form)]

    def med(values: Sequence[float]) -> str:
        finite = [v for v in values if v is not None and math.isfinite(v)]
        return f"{statistics.median(finite):.3f}" if finite else "fails"

    lines = [
        "### Parameters that follow the coil current: held-out current",
        "",
        "One joint fit over the currents, every parameter a low-order function of the current (a "
        "polynomial of degree 0-2 or a monotone spline, chosen by held-out current); fitted on four "
        "currents, the fifth "
        f"predicted whole. Chosen: **{label}**. Median NRMSE over the six files (from "
        "`docs/real-data/operating.json`, written by `python studies/operating_point.py`; the method, the "
        "per-file table, the score of every form and the figure of each parameter against current with its "
        "95 % interval: [real-data-operating.md](real-data-operating.md)):",
        "",
        "| current | per-level fit, in-sample | per-level fit, held-out file "
        "| held-out current, predicted whole | held-out current, own (g, phi) refitted |",
        "|---|---|---|---|---|",
    ]
    for k, current in enumerate(op["levels_A"]):
        per = op["per_level"][k]
        lines.append(
            f"| {current:g} A | {med(per['in_sample'])} | {med(per['held_out_file'])} | "
            f"{med(held[k]['whole'])} | {med(held[k]['own_refit'])} |"
        )
    return lines + [""]


def render(doc: dict[str, Any], doc_path: Path, out: Path) -> str:
    """docs/real-data.md from the results (``doc``); figure links relative to ``doc_path``."""
    recs_all: list[dict[str, Any]] = doc["experiments"]
    rel = Path(os.path.relpath(out, doc_path.parent))
    xcs = [r["crosscheck"] for r in recs_all if r.get("crosscheck")]
    text = prose()
    lines = [
        text["intro"].format(
            library=f"bouc_wen_id {doc['library_version']}",
            overall=tally(recs_all),
            xc_adequacy=_range([x.get("adequacy_ratio") for x in xcs], ".3g"),
            xc_p=_range([x.get("adequacy_p") for x in xcs], ".2g"),
            **_bracket_facts(recs_all),
        ),
        "",
    ]
    lines += summary_table(recs_all, doc["joint"]) + [""]
    key = {"mr-damper": "mr", "friction-damper": "friction", "wire-rope": "wire", "bh-microwire": "bh"}
    for dataset in DATASET_ORDER:
        recs = [r for r in recs_all if r["dataset"] == dataset]
        if not recs:
            continue
        before, after = text[f"{key[dataset]}_prose_before"], text[f"{key[dataset]}_prose_after"]
        facts = _section_facts(dataset, recs)
        figs = doc["figures"].get(dataset, [])
        lines += [f"## {DATASET_TITLES[dataset]}", "", before.format(**facts).rstrip(), ""]
        lines += [f"Outcome: {tally(recs)}", ""]
        lines += ["### Data: steady segments, frequency, noise", ""] + data_table(recs) + [""]
        for name in figs:
            if name.endswith("-segments.png"):
                lines += [f"![records and kept segments]({(rel / name).as_posix()})", ""]
        lines += ["### Identification, one experiment at a time", ""] + ident_table(recs) + [""]
        for name in figs:
            for suffix, alt in (("-loops.png", "averaged loops"), ("-residuals.png", "residuals")):
                if name.endswith(suffix):
                    lines += [f"![{alt}]({(rel / name).as_posix()})", ""]
        lines += [after.format(**facts).rstrip(), ""]
        joints = [j for j in doc["joint"] if j["dataset"] == dataset]
        if joints:
            lines += ["### Joint fits", ""] + joint_table(joints)
        for name in figs:
            if name.endswith("-bode.png"):
                lines += [f"![Bode points]({(rel / name).as_posix()})", ""]
        for name in figs:
            if "-joint-" in name:
                lines += [f"![joint fit loops]({(rel / name).as_posix()})", ""]
        if dataset == "mr-damper":
            lines += operating_section(out / "operating.json")
    lines.append(text["rough_edges"].format(**_rough_facts(recs_all)).rstrip())
    bugs = [r for r in recs_all if r.get("status") == "library bug"]
    if bugs:
        lines += ["", "**Exceptions that are not named errors (library bugs):**", ""]
        lines += [f"- {r['label']}: `{(r.get('identification') or r)['error']['class']}`" for r in bugs]
    lines += [
        "",
        "## Provenance and licenses",
        "",
        "- MR damper: DanielMaurelE/vRTHS_AMBC_MRdamper, MIT (c) 2022 mequiroz.",
        "- Friction damper: ARTS-Laboratory/Dataset-Friction-Damper-with-Backlash, CC BY-SA 4.0 "
        "(Coble, Huggins, "
        "Cao, Ricles, Downey); not redistributed, read from ../shared.",
        "- Wire-rope isolator: deepfe/Wire_rope_isolators, no license stated; read in place only.",
        "- B-H microwire: DYK-Team/Digital_BH-loop_algorithm, no license stated; read in place only.",
        "",
    ]
    return "\n".join(lines)

"""Figures and the self-contained HTML page of a :class:`~bouc_wen_id.diagnosis.Diagnosis`.

matplotlib is imported here only, lazily; every plotting function takes an optional ``ax`` so a user can
compose the figures, and returns the axes it drew on.
"""

from __future__ import annotations

import base64
import html
import io
import math
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional, Union

import numpy as np

from . import adequacy, left_out, limits_void
from .result import TERM_LABELS, Diagnosis, clean

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..result import IdentificationResult

TWO_PI = 2.0 * math.pi


def _label(what: str, unit: str) -> str:
    """An axis label with its unit: the data's own when known, else said to be the data's."""
    return f"{what} ({unit})" if unit else f"{what} (units of the data)"


def _units(d: Diagnosis, u_unit: str = "", y_unit: str = "") -> tuple[str, str]:
    """``(u_unit, y_unit)``: the ones given, else the diagnosis's own (``settings["units"]``) when it has
    them."""
    own = d.settings.get("units") if isinstance(d.settings, dict) else None
    own = own if isinstance(own, dict) else {}
    return u_unit or str(own.get("u", "") or ""), y_unit or str(own.get("y", "") or "")


def _legend_outside(ax: Axes) -> None:
    """The legend right of the axes, never over the data (the saved figure's box grows to hold it)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False, borderaxespad=0.0)


def _axes(ax: Optional[Axes], figsize: tuple[float, float] = (6.0, 3.2)) -> Axes:
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=100)
    return fig.add_subplot(1, 1, 1)


def plot_residual_cycle(d: Diagnosis, ax: Optional[Axes] = None, *, y_unit: str = "") -> Axes:
    """Residual against the phase of the input over one cycle, plain and final, with the noise band
    (``y_unit`` labels the axis)."""
    ax = _axes(ax)
    band = []
    for i, e in enumerate(d.experiments):
        p = e.samples_per_period
        th = np.mod(TWO_PI * np.arange(p) / p + e.grid_phase, TWO_PI)
        order = np.argsort(th)
        r0 = (e.ybar - d.plain.outputs[i])[order]
        r1 = (e.ybar - d.final.outputs[i])[order]
        ax.plot(
            np.degrees(th[order]), r0, color="tab:red", lw=0.8, alpha=0.6, label="plain" if i == 0 else None
        )
        ax.plot(
            np.degrees(th[order]), r1, color="tab:blue", lw=0.8, alpha=0.8, label="final" if i == 0 else None
        )
        band.append(2.0 * math.sqrt(e.noise_var / e.periods))
    b = float(np.median(band))
    ax.axhspan(-b, b, color="0.85", zorder=0, label="±2 noise sd")
    ax.set_xlabel("phase of the input u (deg)")
    ax.set_ylabel(_label("residual y - model", _units(d, y_unit=y_unit)[1]))
    ax.set_xlim(0, 360)
    ax.set_xticks(range(0, 361, 90))
    _legend_outside(ax)
    return ax


def plot_loops(
    d: Diagnosis, ax: Optional[Axes] = None, max_loops: int = 4, *, u_unit: str = "", y_unit: str = ""
) -> Axes:
    """Measured loops (output against the applied input, in the data's units: ``u_unit``, ``y_unit``)
    with the plain and the final model."""
    ax = _axes(ax)
    n = len(d.experiments)
    pick = sorted({int(round(v)) for v in np.linspace(0, n - 1, min(n, max_loops))})
    for k, i in enumerate(pick):
        e = d.experiments[i]
        u = e.input()
        ax.plot(u, e.ybar, ".", ms=2, color="0.3", label="data" if k == 0 else None)
        ax.plot(u, d.plain.outputs[i], color="tab:red", lw=0.9, label="plain" if k == 0 else None)
        ax.plot(u, d.final.outputs[i], color="tab:blue", lw=0.9, ls="--", label="final" if k == 0 else None)
    uu, yu = _units(d, u_unit, y_unit)
    ax.set_xlabel(_label("input u - its mean", uu))
    ax.set_ylabel(_label("averaged output y", yu))
    _legend_outside(ax)
    return ax


def plot_harmonics(d: Diagnosis, ax: Optional[Axes] = None) -> Axes:
    """Residual power per harmonic against its noise expectation, plain and final (log scale)."""
    ax = _axes(ax)
    hb = d.before.harmonics
    ha = d.after.harmonics
    k = np.array([h.harmonic for h in hb])
    ax.bar(k - 0.2, [max(h.statistic / h.dof, 1e-3) for h in hb], width=0.4, color="tab:red", label="plain")
    ax.bar(k + 0.2, [max(h.statistic / h.dof, 1e-3) for h in ha], width=0.4, color="tab:blue", label="final")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(k)
    ax.set_xticklabels(["DC" if v == 0 else str(v) for v in k], fontsize=7)
    ax.set_xlabel("harmonic of the input's frequency (DC: the mean)")
    ax.set_ylabel("residual power / noise power\n(ratio; 1: at the noise)")
    _legend_outside(ax)
    return ax


def plot_held_out(d: Diagnosis, ax: Optional[Axes] = None) -> Axes:
    """Held-out NRMSE per left-out experiment: plain against final."""
    ax = _axes(ax)
    ho = d.held_out
    if ho is None:
        ax.text(
            0.5, 0.5, "no term named: nothing to hold out", ha="center", va="center", transform=ax.transAxes
        )
        ax.set_axis_off()
        return ax
    x = np.arange(len(ho.folds))
    ax.bar(x - 0.2, ho.nrmse_before, width=0.4, color="tab:red", label="plain")
    ax.bar(x + 0.2, ho.nrmse_after, width=0.4, color="tab:blue", label="final")
    ax.set_xticks(x)
    # Each bar named by its experiment (its source: the file or recording), not by its index.
    names = [d.experiments[j].source or f"experiment {j}" for j in ho.folds]
    ax.set_xticklabels(
        names, fontsize=7, rotation=30 if len(names) > 4 else 0, ha="right" if len(names) > 4 else "center"
    )
    ax.set_xlabel("held-out experiment")
    ax.set_ylabel("held-out NRMSE\n(ratio to the output's spread)")
    ax.set_yscale("log")
    _legend_outside(ax)
    return ax


FIGURES = {
    "residual_cycle": plot_residual_cycle,
    "loops": plot_loops,
    "harmonics": plot_harmonics,
    "held_out": plot_held_out,
}


def figure(d: Diagnosis, name: str, *, u_unit: str = "", y_unit: str = "") -> Figure:
    """One figure of the report by name (see ``FIGURES``), its axes labelled in the data's units."""
    uu, yu = _units(d, u_unit, y_unit)
    if name == "loops":
        ax = plot_loops(d, u_unit=uu, y_unit=yu)
    elif name == "residual_cycle":
        ax = plot_residual_cycle(d, y_unit=yu)
    else:
        ax = FIGURES[name](d)
    fig = ax.figure
    fig.subplots_adjust(left=0.16, right=0.78, bottom=0.2, top=0.95)
    return fig  # type: ignore[return-value]


def _png(fig: Figure) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    # The box grows to every label and the legend outside the axes: nothing is clipped.
    fig.savefig(buf, format="png", bbox_inches="tight", pad_inches=0.08)
    return buf.getvalue()


def _table(rows: list[list[str]], head: list[str]) -> str:
    h = "".join(f"<th>{html.escape(c)}</th>" for c in head)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{h}</tr></thead><tbody>{body}</tbody></table>"


def _g(v: float, fmt: str = ".3g") -> str:
    return format(v, fmt) if isinstance(v, (int, float)) and math.isfinite(v) else "–"


_HEAD = (
    "<!doctype html><html><head><meta charset='utf-8'><title>bouc_wen_id diagnosis</title>"
    "<style>body{font-family:sans-serif;max-width:980px;margin:2em auto;line-height:1.4}"
    "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;"
    "text-align:right;font-size:90%}th{background:#eee}.verdict{font-size:130%;padding:0.6em;"
    "background:#f4f4ff;border-left:6px solid #446}img{max-width:100%}"
    ".warnings{padding:0.4em 0.8em;background:#fff6e6;border-left:6px solid #c80}</style></head><body>"
)
_FIGURES = (
    ("residual_cycle", "Residual over the cycle"),
    ("loops", "Loops"),
    ("harmonics", "Residual per harmonic"),
    ("held_out", "Held-out NRMSE"),
)


#: What ``identify`` made of the same experiments: its result, or the error it refused them with.
Identified = Union["IdentificationResult", Exception]


def identify_plain(experiments: Any, **options: Any) -> tuple[Identified, tuple[str, ...]]:
    """:func:`~bouc_wen_id.identify` on the same experiments (the plain model as a user fits it), with every
    warning it raised as a line ``Category: message`` (each once); a refusal is returned, not raised."""
    from ..errors import BoucWenIdError
    from ..identification import identify

    result: Identified
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = identify(experiments, **options)
        except BoucWenIdError as exc:
            result = exc
    lines: list[str] = []
    for w in caught:
        line = f"{w.category.__name__}: {w.message}"
        if line not in lines:
            lines.append(line)
    for note in () if isinstance(result, Exception) else result.warnings:
        if not any(note in line for line in lines):
            lines.append(note)
    return result, tuple(lines)


def html_page(
    d: Diagnosis,
    images: dict[str, bytes],
    identified: Optional[Identified] = None,
    identify_warnings: Sequence[str] = (),
) -> str:
    """The report a person reads: verdict first, then evidence, then the plain model ``identify`` fitted to
    the same data (``identified``) with the warnings it raised; figures inline (no external files)."""
    verdict, *evidence = _verdict_html(d)  # the verdict is the first text a reader meets
    parts = [_HEAD, verdict, "<h1>Diagnosis</h1>", *evidence]
    parts += _identified_html(identified, identify_warnings)
    parts += [*_terms_html(d), *_held_out_html(d)]
    parts += left_out.report_html(d)  # the records left out of its statistics, with why
    parts.append("<h2>Where the models miss</h2>")
    parts.append(
        f"<p>Plain: {html.escape(adequacy.where(d, final=False))}. "  # one rule (adequacy.py)
        f"Final: {html.escape(adequacy.where(d, final=True))}.</p>"
    )
    for name, title in _FIGURES:
        if name in images:
            b64 = base64.b64encode(images[name]).decode("ascii")
            parts.append(f"<h3>{title}</h3><img alt='{name}' src='data:image/png;base64,{b64}'>")
    parts += _selection_html(d)
    parts += _limits_html(d)  # detection limits (diagnosis/limits.py)
    parts += [f"<p>{html.escape(note)}</p>" for note in d.notes]
    parts += _experiments_html(d)
    parts.append("</body></html>")
    return "\n".join(parts)


def _verdict_html(d: Diagnosis) -> list[str]:
    return [
        f"<p class='verdict'><b>{html.escape(d.status_text)}</b>: {html.escape(d.headline)}</p>"
        + (f"<ul>{''.join(f'<li>{html.escape(c)}</li>' for c in d.details)}</ul>" if d.details else ""),
        f"<p>Plain model: χ²/dof = {_g(d.plain.chi2_dof)} "
        f"(p = {_g(d.plain.p_value, '.2g')}); "
        f"final model: χ²/dof = {_g(d.final.chi2_dof)} (p = {_g(d.final.p_value, '.2g')}); "
        f"{100 * d.explained_fraction:.1f} % of the plain model's excess explained. "
        f"{len(d.experiments)} experiments, {d.seconds:.1f} s.</p>",
    ]


def _identified_html(identified: Optional[Identified], notes: Sequence[str]) -> list[str]:
    """The plain model as ``identify`` fits it: its warnings first, then beta, gamma, mu and each
    experiment's G with their intervals, and its adequacy test."""
    if identified is None and not notes:
        return []
    parts = ["<h2>Identified model</h2>"]
    if notes:
        items = "".join(f"<li>{html.escape(n)}</li>" for n in notes)
        parts.append(f"<div class='warnings'><b>Warnings raised by identify</b><ul>{items}</ul></div>")
    if isinstance(identified, Exception):
        parts.append(
            f"<p class='warnings'>identify refused these data: {html.escape(type(identified).__name__)}: "
            f"{html.escape(str(identified))}</p>"
        )
        return parts
    if identified is None:
        return parts
    r = identified
    if not notes:
        parts.append("<p>identify raised no warning.</p>")
    conf = f"{100 * r.confidence:.0f} %"
    a = r.adequacy
    test = (
        f"; its adequacy test: χ² = {_g(a.statistic, '.4g')} on {a.dof} dof, p = {_g(a.p_value, '.2g')}"
        if a is not None
        else ""
    )
    parts.append(
        f"<p>The plain Wiener-Bouc-Wen model as <code>identify</code> fits these data (method "
        f"{html.escape(r.method)}; alpha-normalised: alpha = 1 and G carries the scale){test}.</p>"
    )
    rows = []
    for name in ("beta", "gamma", "mu"):
        value = float(getattr(r, name))
        if r.standard_errors is not None:
            lo, hi = r.interval(name)
            rows.append(
                [name, _g(value, ".5g"), _g(r.standard_errors[name]), f"[{_g(lo, '.4g')}, {_g(hi, '.4g')}]"]
            )
        else:
            rows.append([name, _g(value, ".5g"), "–", "–"])
    parts.append(_table(rows, ["parameter", "estimate", "std. error", f"{conf} interval"]))
    parts.append(_g_table(r, conf))
    return parts


def _g_table(r: IdentificationResult, conf: str) -> str:
    """Each experiment's |G| and phase lag (degrees, unwrapped along frequency) with their intervals."""
    from ..plotting import unwrapped_degrees
    from ..validation import z_value

    z = z_value(r.confidence)
    lags = unwrapped_degrees(r.frequencies, r.phases)
    rows = []
    for i, (e, lag) in enumerate(zip(r.experiments, lags)):
        g_ci = "–" if e.gain_se is None else f"± {_g(z * e.gain_se)}"
        p_ci = "–" if e.phase_se is None else f"± {_g(math.degrees(z * e.phase_se))}"
        name = e.source or f"experiment {i}"
        rows.append(
            [
                name,
                _g(e.frequency / TWO_PI, ".4g"),
                _g(e.gain, ".5g"),
                g_ci,
                _g(lag, ".4g"),
                p_ci,
                _g(e.nrmse, ".3g"),
            ]
        )
    head = ["experiment", "f (Hz)", "|G|", f"{conf} interval", "phase lag (deg)", f"{conf} interval", "NRMSE"]
    return _table(rows, head)


def _terms_html(d: Diagnosis) -> list[str]:
    """The named terms (or the partial ones), then every alternative with what would separate it."""
    parts = []
    if d.named or d.partial:
        rows = [
            [t.label, t.symbol, _g(t.value, ".4g"), _g(t.standard_error), t.unit]
            for t in (d.named or d.partial)
        ]
        parts.append("<h2>Terms</h2>" + _table(rows, ["term", "symbol", "value", "std. error", "unit"]))
    for a in d.alternatives:
        why = (
            f"parameter correlation {a.correlation:+.3f}"
            if math.isfinite(a.correlation)
            else "their improvements are within their uncertainty"
        )
        parts.append(
            f"<p>Alternative: <b>{html.escape(TERM_LABELS.get(a.rival, a.rival))}</b> fits as well as "
            f"{html.escape(TERM_LABELS.get(a.term, a.term))} ({why}). "
            f"To separate them: {html.escape(a.separating_experiment)}.</p>"
        )
    return parts


def _limits_html(d: Diagnosis) -> list[str]:
    """Every first-step candidate's detection limit: what the design could not have seen."""
    if not d.limits:
        return []
    if limits_void.void(d):
        return [f"<h2>Detection limits</h2><p>{html.escape(limits_void.reason(d))}.</p>"]
    rows = [
        [
            lim.label,
            lim.symbol,
            _g(lim.limit),
            _g(lim.limit_90),
            lim.unit,
            _g(100 * lim.absorbed, ".3g"),
            lim.note,
        ]
        for lim in d.limits
    ]
    head = [
        "term",
        "symbol",
        "limit (50 % power)",
        "90 % power",
        "unit",
        "absorbed by the plain model (%)",
        "",
    ]
    return [
        "<h2>Detection limits</h2><p>The value of each candidate the experiments detect with 50 % and 90 % "
        "power at its test's level (by linearisation, which may overstate the power: the size the test needs "
        "can be larger, the plain model absorbing more of a present term); below it, a term is not "
        "excluded.</p>" + _table(rows, head)
    ]


def _held_out_html(d: Diagnosis) -> list[str]:
    if d.held_out is None:
        return []
    rows = [
        [d.experiments[j].source, _g(b, ".4f"), _g(a, ".4f"), _g(a / b if b else math.nan, ".3f")]
        for j, b, a in zip(d.held_out.folds, d.held_out.nrmse_before, d.held_out.nrmse_after)
    ]
    return [
        "<h2>Held-out proof</h2><p>Each experiment left out in turn: the physics fitted on the "
        "others, only its own |G| and phase refitted.</p>"
        + _table(rows, ["held-out experiment", "plain NRMSE", "final NRMSE", "ratio"])
    ]


def _selection_html(d: Diagnosis) -> list[str]:
    """Every selection step's candidates with their tests, then degradation's, tested in drift space."""
    parts = ["<h2>Selection</h2>"]
    for k, st in enumerate(d.steps, 1):
        rows = [
            [
                t.term,
                _g(t.cost, ".6g"),
                _g(t.statistic, ".4g"),
                _g(t.p_adjusted, ".2g"),
                _g(t.share, ".2f"),
                "" if t.held_out is None else ("better" if t.held_out.improves else "worse"),
            ]
            for t in st.trials
        ]
        chosen = " + ".join(st.pair) if getattr(st, "pair", ()) else (st.chosen or "none")  # pairs.py
        parts.append(
            f"<p>Step {k}: from χ² = {_g(st.before_cost, '.6g')} (dof {st.before_dof}); chosen: "
            f"<b>{html.escape(chosen)}</b></p>"
            + _table(rows, ["term", "χ²", "F", "p (Bonferroni)", "share of excess", "held-out"])
        )
    deg = d.degradation
    if deg is not None:  # design.md 10.6
        ho = "better" if deg.held_out_improves else ("worse" if deg.held_out_after else "")
        gate = "" if deg.drift_present else " (no drift beyond the noise: not a candidate)"
        rows = [[deg.term, _g(deg.statistic, ".4g"), _g(deg.p_adjusted, ".2g"), _g(deg.share, ".2f"), ho]]
        if deg.rival is not None:  # the other drift term (strength or stiffness), tested alone
            r = deg.rival
            rows.append([r.term, _g(r.statistic, ".4g"), _g(r.p_adjusted, ".2g"), _g(r.share, ".2f"), ""])
        parts.append(
            "<p>Degradation, from the period-by-period record (block deviations from the mean period): "
            f"χ² {_g(deg.cost0, '.6g')} → {_g(deg.cost1, '.6g')} (dof {deg.dof0}){gate}</p>"
            + _table(rows, ["term", "F", "p (Bonferroni)", "share of drift excess", "held-out"])
        )
    return parts


def whole_periods(e: Any) -> float:
    """The whole periods an experiment's average comes from: one DC per period in its period-by-period
    record (a recording's periods after settling, a lab stretch's whole periods); NaN without that record.
    ``e.periods`` is not it for lab data: that is the samples averaged into each point of ``ybar``."""
    n = int(np.size(e.dc))
    return float(n) if n >= 3 else math.nan


def _experiments_html(d: Diagnosis) -> list[str]:
    rows = [
        [
            e.source,
            _g(e.frequency / TWO_PI, ".4g"),
            _g(e.amplitude, ".4g"),
            _g(whole_periods(e), ".4g"),
            str(e.samples_per_period),
            _g(e.periods, ".4g"),
            _g(p, ".4f"),
            _g(f, ".4f"),
        ]
        for e, p, f in zip(d.experiments, d.plain.nrmse, d.final.nrmse)
    ]
    head = ["experiment", "f (Hz)", "U", "periods", "points per period", "samples per point"]
    return [
        "<h2>Experiments</h2>",
        _table(rows, [*head, "plain NRMSE", "final NRMSE"]),
    ]


def write_report(
    d: Diagnosis,
    out: Path,
    figures: bool = True,
    *,
    identified: Optional[Identified] = None,
    identify_warnings: Sequence[str] = (),
    u_unit: str = "",
    y_unit: str = "",
) -> list[Path]:
    """``diagnosis.json`` first, then the figures (PNG) and ``report.html``, into the folder ``out``.

    ``identified``, ``identify_warnings``: the plain model ``identify`` fitted to the same experiments and
    the warnings it raised (:func:`identify_plain` gives both), shown after the verdict; ``u_unit``,
    ``y_unit``: the data's units, for the figures' axes.
    """
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "diagnosis.json"]
    written[0].write_text(d.to_json())
    images: dict[str, bytes] = {}
    if figures:
        for name in FIGURES:
            images[name] = _png(figure(d, name, u_unit=u_unit, y_unit=y_unit))
            path = out / f"{name}.png"
            path.write_bytes(images[name])
            written.append(path)
    page = out / "report.html"
    page.write_text(html_page(d, images, identified, identify_warnings))
    written.append(page)
    return written


__all__ = [
    "plot_residual_cycle",
    "plot_loops",
    "plot_harmonics",
    "plot_held_out",
    "write_report",
    "html_page",
    "identify_plain",
    "whole_periods",
    "clean",
]

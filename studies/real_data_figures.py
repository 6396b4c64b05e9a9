"""The real-data study's figures: records and kept segments, averaged loops, residuals, Bode points.

Each figure is a grid of panels (:func:`bouc_wen_id.plotting.panel_grid`), one per record or experiment;
the joint fits' loops are :func:`bouc_wen_id.plotting.plot_loops` of their results.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Optional

import numpy as np
from bouc_wen_id.plotting import panel_grid
from numpy.typing import NDArray
from real_data_page import TWO_PI, Z95, _wrap_pi

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.figure import Figure
    from real_data import Joint, Outcome, Spec

FloatArray = NDArray[np.float64]


def _short(o: Outcome) -> str:
    return (
        o.spec.label if o.record.get("segment", 0) in (0, None) else f"{o.spec.label} #{o.record['segment']}"
    )


def figure_segments(specs: Sequence[Spec], outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Each record's input and output (each scaled to its peak) against time, kept segments shaded."""
    fig, axes = panel_grid(len(specs), ncols, (2.6, 1.7))
    for ax, spec in zip(axes, specs):
        m = spec.measurement
        t = m.t - m.t[0]
        step = max(1, len(m) // 6000)

        def norm(x: FloatArray) -> FloatArray:
            c = x - np.median(x)
            out: FloatArray = c / max(float(np.max(np.abs(c))), 1e-300)
            return out

        ax.plot(t[::step], norm(m.y)[::step], lw=0.4, color="C0", label="y (output)")
        ax.plot(t[::step], norm(m.u)[::step], lw=0.6, color="C1", label="u (input)")
        for name, x in spec.extra.items():
            ax.plot(t[::step], norm(x)[::step], lw=0.4, color="C2", alpha=0.7, label=name)
        for o in outcomes:
            if o.spec is spec and o.report is not None:
                for seg in o.report.kept:
                    ax.axvspan(t[seg.start], t[seg.stop - 1], color="C2", alpha=0.15, lw=0)
                break
        ax.set_title(spec.label, fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_yticks([])
    axes[0].legend(fontsize=5, loc="lower left")
    fig.suptitle("Records (each channel scaled to its peak); shaded: the steady segments kept", fontsize=9)
    fig.supxlabel("time in the record (s)", fontsize=8)
    return fig


def _model_loop(o: Outcome) -> tuple[Optional[FloatArray], str]:
    if o.result is not None and o.result.experiments[0].model is not None:
        return o.result.experiments[0].model, "library"
    if o.cross is not None:
        return o.cross.loop, "cross-check"
    return None, ""


def figure_loops(outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Averaged loops against the measured input: data, the library's model, the cross-check's."""
    usable = [o for o in outcomes if o.averaged is not None]
    fig, axes = panel_grid(len(usable), ncols, (2.6, 2.3))
    for ax, o in zip(axes, usable):
        ap = o.averaged
        assert ap is not None
        u = np.append(ap.input_grid(), ap.input_grid()[:1])
        ax.plot(u, np.append(ap.ybar, ap.ybar[:1]), lw=1.3, color="C0", label="measured (averaged)")
        ident = o.record["identification"]
        if o.result is not None and o.result.experiments[0].model is not None:
            w = o.result.experiments[0].model
            ax.plot(u, np.append(w, w[:1]), "--", lw=1.0, color="C3", label="library fit")
        if o.cross is not None:
            w = o.cross.loop
            ax.plot(u, np.append(w, w[:1]), ":", lw=1.0, color="k", label="cross-check fit")
        if ident["outcome"] == "identified":
            head = f"NRMSE {ident['experiments'][0]['nrmse']:.3g}"
        else:
            head = f"refused: {ident['error']['class']}"
        xc = o.record.get("crosscheck")
        if xc:
            head += f"; x-check {xc['nrmse']:.3g}"
        ax.set_title(f"{_short(o)}\n{head}", fontsize=6.5)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    if usable:
        axes[0].legend(fontsize=5)
        units = usable[0].record["units"]
        fig.supxlabel(f"input u - offset ({units['u']})", fontsize=8)
        fig.supylabel(f"output y - offset ({units['y']})", fontsize=8)
    fig.suptitle(
        "Averaged loops against the measured input\nmeasured (blue), library refined fit (red dashed), "
        "cross-check fit (black dotted)",
        fontsize=8,
    )
    return fig


def figure_residuals(outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Averaged output minus model over one period (the library's fit, else the cross-check's)."""
    usable = [o for o in outcomes if o.averaged is not None and _model_loop(o)[0] is not None]
    fig, axes = panel_grid(len(usable), ncols, (2.6, 1.9))
    for ax, o in zip(axes, usable):
        ap = o.averaged
        assert ap is not None
        w, which = _model_loop(o)
        assert w is not None
        t = ap.times()
        ax.plot(t, ap.ybar - w, lw=0.9, color="C0" if which == "library" else "0.3")
        noise = o.record["averaged"]["noise_sd"]
        if noise is not None and ap.periods > 0:
            band = 2.0 * noise / math.sqrt(ap.periods)
            ax.axhspan(-band, band, color="C1", alpha=0.3, lw=0, zorder=0)
        ax.axhline(0.0, color="k", lw=0.4)
        ax.set_title(f"{_short(o)} ({which})", fontsize=6.5)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    fig.suptitle(
        "Residual ybar - model over one period: library fit (blue) or, when refused,\nthe cross-check fit "
        "(grey); orange band: +-2 sigma/sqrt(N), the noise of the average",
        fontsize=8,
    )
    fig.supxlabel("time from the input's phase zero (s)", fontsize=8)
    if usable:
        fig.supylabel(f"residual ybar - model ({usable[0].record['units']['y']})", fontsize=8)
    return fig


def _on_branch(ref_f: Sequence[float], ref_deg: Sequence[float], f: float, phase: float) -> float:
    """``phase`` (rad) in degrees, on the 360-degree branch nearest the group's unwrapped curve at ``f``
    (in (-180, 180] when the group has no identified point)."""
    deg = math.degrees(_wrap_pi(phase))
    if not len(ref_f):
        return deg
    order = np.argsort(ref_f)
    ref = float(np.interp(math.log(f), np.log(np.asarray(ref_f)[order]), np.asarray(ref_deg)[order]))
    return deg + 360.0 * round((ref - deg) / 360.0)


def figure_bode(
    outcomes: Sequence[Outcome], joints: Sequence[Joint], group_of: Callable[[Outcome], str]
) -> Figure:
    """|G| and phi at each experiment's frequency: single fits (95 % CI), joint fits, cross-checks; the
    phase lag in degrees, unwrapped along frequency within each group."""
    from bouc_wen_id.plotting import unwrapped_degrees

    fig, (ax_g, ax_p) = panel_grid(2, 1, (5.9, 2.75))
    fig.subplots_adjust(left=1.25 / fig.get_figwidth())  # room for |G|'s long tick labels (B-H: 4.8e-8)
    groups: dict[str, list[Outcome]] = {}
    for o in outcomes:
        if o.averaged is not None:
            groups.setdefault(group_of(o), []).append(o)
    curves: dict[str, tuple[list[float], list[float]]] = {}
    for k, (name, members) in enumerate(groups.items()):
        color = f"C{k % 10}"
        fit = [o for o in members if o.record["identification"]["outcome"] == "identified"]
        fs = [float(o.record["frequency_hz"]) for o in fit]
        points = [o.record["identification"]["experiments"][0] for o in fit]
        degs = list(unwrapped_degrees(np.array(fs), np.array([e["phase"]["value"] for e in points])))
        curves[name] = (fs, degs)
        for f, e, deg in zip(fs, points, degs):
            g, ph = e["gain"], e["phase"]
            g_err = Z95 * g["se"] if g["se"] is not None else 0.0
            p_err = math.degrees(Z95 * ph["se"]) if ph["se"] is not None else 0.0
            ax_g.errorbar([f], [g["value"]], yerr=[g_err], fmt="o", color=color, ms=4, capsize=2)
            ax_p.errorbar([f], [deg], yerr=[p_err], fmt="o", color=color, ms=4, capsize=2)
        for o in members:
            if o.cross is not None:
                f = float(o.record["frequency_hz"])
                ax_g.plot([f], [o.cross.gain], "x", color=color, ms=5)
                ax_p.plot([f], [_on_branch(fs, degs, f, o.cross.phase)], "x", color=color, ms=5)
        ax_g.plot([], [], "s", color=color, label=name)
    for j in joints:
        if j.result is None:
            continue
        name = group_of(j.members[0])
        k = list(groups).index(name) if name in groups else 0
        fs = [e.frequency / TWO_PI for e in j.result.experiments]
        ref = curves.get(name, ([], []))
        ax_g.plot(fs, j.result.gains, "s--", mfc="none", color=f"C{k % 10}", ms=6, lw=0.6)
        ax_p.plot(
            fs,
            [_on_branch(*ref, f, p) for f, p in zip(fs, j.result.phases)],
            "s--",
            mfc="none",
            color=f"C{k % 10}",
            ms=6,
            lw=0.6,
        )
    ax_g.plot([], [], "o", color="0.4", label="single refined fit (95 % CI)")
    ax_g.plot([], [], "s", mfc="none", color="0.4", label="joint refined fit")
    ax_g.plot([], [], "x", color="0.4", label="cross-check (no CI)")
    from matplotlib.ticker import NullFormatter

    ax_g.set_xscale("log")
    ax_g.set_yscale("log")
    ax_p.set_xscale("log")
    for ax in (ax_g, ax_p):
        ax.xaxis.set_minor_formatter(NullFormatter())
    units = next((o.record["units"] for o in outcomes), {"u": "[u]", "y": "[y]"})
    ax_g.set_ylabel(f"|G(j omega)| ({units['y']}/{units['u']},\nalpha-normalised)")
    ax_p.set_ylabel("phase lag phi = -arg G (deg)")
    ax_p.set_xlabel("frequency found (Hz)")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    ax_g.legend(fontsize=6)
    ax_g.set_title("Identified points of the linear part G", fontsize=9)
    return fig


def write_figures(
    dataset: str,
    specs: Sequence[Spec],
    outcomes: Sequence[Outcome],
    joints: Sequence[Joint],
    out: Path,
) -> list[str]:
    """The dataset's PNGs (segments, loops, residuals, Bode, and the library's loops of joint fits)."""
    from bouc_wen_id.plotting import plot_loops

    ncols = 5 if dataset == "mr-damper" else 3 if dataset in ("friction-damper", "wire-rope") else 2
    group_of: Callable[[Outcome], str]
    if dataset == "mr-damper":

        def group_of(o: Outcome) -> str:
            return f"{o.record['metadata']['coil_current_A']} A"

    elif dataset == "wire-rope":

        def group_of(o: Outcome) -> str:
            return f"level {o.record['metadata']['amplitude_level']}"

    elif dataset == "friction-damper":

        def group_of(o: Outcome) -> str:
            return f"{o.record['metadata']['nominal_amplitude_in']} in"

    else:

        def group_of(o: Outcome) -> str:
            return "B-H"

    figs: list[tuple[str, Figure]] = [
        (f"{dataset}-segments.png", figure_segments(specs, outcomes, ncols)),
        (f"{dataset}-loops.png", figure_loops(outcomes, ncols)),
        (f"{dataset}-residuals.png", figure_residuals(outcomes, ncols)),
        (f"{dataset}-bode.png", figure_bode(outcomes, joints, group_of)),
    ]
    for j in joints:
        if j.result is not None:
            slug = j.record["label"].split(",")[0].replace(" ", "").replace(".", "p")
            units = j.members[0].record["units"]
            fig = plot_loops(j.result, u_unit=units["u"], y_unit=units["y"])
            fig.suptitle(f"Joint fit {j.record['label']}: measured (solid), model (dashed)", fontsize=9)
            figs.append((f"{dataset}-joint-{slug}.png", fig))
    names = []
    for name, fig in figs:
        fig.savefig(out / name, dpi=72, metadata={"Software": None})
        names.append(name)
    return names

"""Figures of an identification result.  matplotlib is imported here only, and only when asked for."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Optional

import numpy as np

from .errors import InvalidParameterError
from .validation import z_value

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import IdentificationResult

__all__ = ["plot_loop", "plot_loops", "plot_bode", "plot_residuals", "panel_grid"]


#: Fixed margins (inches) of every figure: a lean layout computed once, instead of matplotlib's
#: constrained layout, whose search over every text extent at each draw was most of a report's time
#: (issue #8).
_MARGIN_LEFT, _MARGIN_RIGHT, _MARGIN_BOTTOM, _MARGIN_TOP = 0.75, 0.2, 0.55, 0.6
#: Gaps between panels, as fractions of a panel's width and height.
_WSPACE, _HSPACE = 0.35, 0.6


def _new_figure(
    ncols: int = 1,
    nrows: int = 1,
    size: tuple[float, float] = (6.0, 4.5),
    sharex: bool = False,
    hspace: float = _HSPACE,
    left: float = _MARGIN_LEFT,
) -> tuple[Figure, list[Axes]]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=size)
    w, h = size
    fig.subplots_adjust(
        left=left / w,
        right=1.0 - _MARGIN_RIGHT / w,
        bottom=_MARGIN_BOTTOM / h,
        top=1.0 - _MARGIN_TOP / h,
        wspace=_WSPACE,
        hspace=hspace,
    )
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=sharex)
    return fig, list(axes.ravel())


def plot_loop(
    result: IdentificationResult, experiment: Optional[int] = None, ax: Optional[Axes] = None
) -> Figure:
    """Averaged output ybar (solid) and the identified model's steady loop (dashed, black) against the
    identified steady input x = U|G|cos(omega t - phi)."""
    if ax is None:
        fig, (ax,) = _new_figure()
    else:
        fig = ax.get_figure()  # type: ignore[assignment]
    chosen = range(len(result.experiments)) if experiment is None else [experiment]
    for i in chosen:
        e = result.experiments[i]
        x = np.append(e.model_input(), e.model_input()[:1])
        y = np.append(e.ybar, e.ybar[:1])
        ax.plot(x, y, lw=1.4, label=f"omega = {e.frequency:.3g} rad/s (NRMSE {e.nrmse:.2g})")
        if e.model is not None:
            ax.plot(x, np.append(e.model, e.model[:1]), "--", color="k", lw=0.8, alpha=0.8)
    ax.set_xlabel("identified x = U|G| cos(omega t - phi)")
    ax.set_ylabel("averaged output ybar (solid), model (dashed)")
    ax.set_title(
        f"Averaged hysteresis loops (beta={result.beta:.3g}, gamma={result.gamma:.3g}, mu={result.mu:.3g})"
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return fig


def plot_bode(result: IdentificationResult, axes: Optional[Sequence[Axes]] = None) -> Figure:
    """Identified |G(j omega_i)| and phi(omega_i), with the true curves when the plant is known."""
    if axes is None:
        # Gain over phase on one shared frequency axis, close together.
        fig, axes = _new_figure(nrows=2, size=(6.0, 6.0), sharex=True, hspace=0.08, left=0.95)
    else:
        fig = axes[0].get_figure()  # type: ignore[assignment]
    ax_g, ax_p = axes[0], axes[1]
    w = result.frequencies
    phases = result.phases
    if result.truth is not None:
        wd = np.geomspace(w.min() / 2, w.max() * 2, 400)
        g, ph = result.truth.plant.linear.gain_phase(wd)
        ax_g.loglog(wd, g, "k-", lw=1, label="truth (alpha-normalised)")
        ax_p.semilogx(wd, ph, "k-", lw=1, label="truth")
        # Put each estimated phase on the truth's branch so that the points sit on the curve.
        _, ph_true = result.truth.plant.linear.gain_phase(w)
        phases = ph_true + (np.pi - np.mod(np.pi - (phases - ph_true), 2 * np.pi))
    z = z_value(0.95)
    g_err = [z * (e.gain_se or 0.0) for e in result.experiments]
    p_err = [z * (e.phase_se or 0.0) for e in result.experiments]
    label = "identified (95 % CI)" if result.standard_errors is not None else "identified"
    ax_g.errorbar(w, result.gains, yerr=g_err, fmt="o", color="C3", capsize=3, label=label)
    ax_p.errorbar(w, phases, yerr=p_err, fmt="o", color="C3", capsize=3, label=label)
    ax_g.set_xscale("log")
    ax_g.set_yscale("log")
    if ax_p.get_shared_x_axes().joined(ax_g, ax_p):
        ax_g.set_xlabel("")
    else:
        ax_p.set_xscale("log")
    ax_g.set_ylabel("|G(j omega)|")
    ax_p.set_ylabel("phi = -angle G (rad)")
    ax_p.set_xlabel("omega (rad/s)")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax_g.set_title("Frequency response of the linear part")
    return fig


#: Most tick intervals per axis of a small panel: every tick is a full artist, built and laid out at each
#: draw, and a report's panels need only a few.
_GRID_NBINS = 4


def panel_grid(n: int, ncols: int = 5, size: tuple[float, float] = (2.6, 2.6)) -> tuple[Figure, list[Axes]]:
    """A figure of ``n`` panels, ``ncols`` per row, each ``size`` inches; the spare panels are hidden."""
    ncols = max(1, min(n, ncols))
    nrows = -(-max(n, 1) // ncols)
    fig, axes = _new_figure(ncols=ncols, nrows=nrows, size=(size[0] * ncols + 0.5, size[1] * nrows + 0.5))
    for ax in axes:
        ax.locator_params(nbins=_GRID_NBINS)
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, axes


def _panels(n: int, axes: Optional[Sequence[Axes]]) -> tuple[Figure, list[Axes]]:
    if axes is None:
        return panel_grid(n)
    if len(axes) < n:
        raise InvalidParameterError(f"{n} experiments need {n} axes, got {len(axes)}")
    return axes[0].get_figure(), list(axes)  # type: ignore[return-value]


def plot_loops(result: IdentificationResult, axes: Optional[Sequence[Axes]] = None) -> Figure:
    """One panel per experiment: the measured averaged loop (solid) and the model's (dashed).

    ``axes``: one per experiment (default: a new figure, :func:`panel_grid`).
    """
    fig, axes = _panels(len(result.experiments), axes)
    for i, (ax, e) in enumerate(zip(axes, result.experiments)):
        x = np.append(e.model_input(), e.model_input()[:1])
        ax.plot(x, np.append(e.ybar, e.ybar[:1]), lw=1.2, color="C0", label="measured")
        if e.model is not None:
            ax.plot(x, np.append(e.model, e.model[:1]), "--", lw=1.0, color="C3", label="model")
        title = e.source or f"experiment {i}"
        ax.set_title(f"{title}\nomega={e.frequency:.3g}, NRMSE={e.nrmse:.2g}", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6)
    fig.suptitle("Averaged loops against the identified x: measured (solid), model (dashed)", fontsize=9)
    return fig


def plot_residuals(result: IdentificationResult, axes: Optional[Sequence[Axes]] = None) -> Figure:
    """One panel per experiment: the averaged output minus the model over one period, against time,
    with the +-2 sigma band of the averaged noise (sigma / sqrt(N)).

    ``axes``: one per experiment (default: a new figure, :func:`panel_grid`).
    """
    fig, axes = _panels(len(result.experiments), axes)
    for i, (ax, e) in enumerate(zip(axes, result.experiments)):
        t = e.times()
        if e.model is not None:
            ax.plot(t, e.ybar - e.model, lw=1.0, color="C0")
        if np.isfinite(e.noise_sd) and e.periods > 0:
            band = 2 * e.noise_sd / np.sqrt(e.periods)
            ax.axhspan(-band, band, color="0.85", zorder=0)
        ax.set_title(e.source or f"experiment {i}", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    fig.suptitle("Residual ybar - model over one period (grey: +-2 sigma/sqrt(N) noise band)", fontsize=9)
    fig.supxlabel("time within the period (s)", fontsize=8)
    return fig

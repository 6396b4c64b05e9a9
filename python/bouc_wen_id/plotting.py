"""Figures of an identification result.  matplotlib is imported here only, and only when asked for."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import NDArray

from .errors import InvalidParameterError
from .validation import z_value

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .result import ExperimentEstimate, IdentificationResult

__all__ = [
    "plot_loop",
    "plot_loops",
    "plot_bode",
    "plot_residuals",
    "panel_grid",
    "input_grid",
    "unwrapped_degrees",
    "BODE_UNITS",
]

FloatArray = NDArray[np.float64]


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


def _unit(what: str, unit: str) -> str:
    """An axis label with its unit: the data's own when known, else said to be the data's."""
    return f"{what} ({unit})" if unit else f"{what} (units of the data)"


def _gain_unit(y_unit: str, u_unit: str) -> str:
    """|G|'s unit: x is in the output's units once alpha = 1 (y = z, dz/dx = 1 at the origin)."""
    return f"{y_unit or '[y]'}/{u_unit or '[u]'}"


def input_grid(e: ExperimentEstimate) -> FloatArray:
    """The applied input ``u = U cos(omega t)`` (its DC removed) on the averaged period's grid: the loop's
    physical x-axis, in the data's units (the identified ``x = U|G| cos(omega t - phi)`` is
    alpha-normalised and has no physical scale of its own)."""
    z = 2.0 * np.pi * np.arange(e.samples_per_period) / e.samples_per_period + e.grid_phase
    out: FloatArray = e.amplitude * np.cos(z)
    return out


def _closed(v: FloatArray) -> FloatArray:
    out: FloatArray = np.append(v, v[:1])
    return out


def plot_loop(
    result: IdentificationResult,
    experiment: Optional[int] = None,
    ax: Optional[Axes] = None,
    *,
    u_unit: str = "",
    y_unit: str = "",
) -> Figure:
    """Averaged output ybar (solid) and the identified model's steady loop (dashed, black) against the
    applied input u = U cos(omega t), in the data's units (``u_unit``, ``y_unit`` label the axes)."""
    if ax is None:
        fig, (ax,) = _new_figure()
    else:
        fig = ax.get_figure()  # type: ignore[assignment]
    chosen = range(len(result.experiments)) if experiment is None else [experiment]
    for i in chosen:
        e = result.experiments[i]
        u = _closed(input_grid(e))
        ax.plot(u, _closed(e.ybar), lw=1.4, label=f"omega = {e.frequency:.3g} rad/s (NRMSE {e.nrmse:.2g})")
        if e.model is not None:
            ax.plot(u, _closed(e.model), "--", color="k", lw=0.8, alpha=0.8)
    ax.set_xlabel(_unit("input u - its mean", u_unit))
    ax.set_ylabel(_unit("averaged output ybar - its mean", y_unit))
    ax.set_title(
        f"Averaged hysteresis loops (beta={result.beta:.3g}, gamma={result.gamma:.3g}, mu={result.mu:.3g})"
        "\nmeasured (solid), model (dashed)",
        fontsize=9,
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return fig


#: The units :func:`plot_bode` draws in: ``"linear"`` |G| on a log axis against omega in rad/s (the
#: library's own units), ``"dB"`` 20 log10 |G| against f in Hz; the phase in degrees, unwrapped, in both.
BODE_UNITS = ("linear", "dB")


def unwrapped_degrees(frequencies: FloatArray, phases: FloatArray) -> FloatArray:
    """Phases (rad) in degrees, unwrapped along increasing frequency, the lowest one's in (-180, 180]."""
    order = np.argsort(frequencies, kind="stable")
    ph = np.asarray(phases, dtype=np.float64)[order]
    if ph.size:
        ph = np.unwrap(ph)
        ph = ph - 2.0 * np.pi * np.ceil((ph[0] - np.pi) / (2.0 * np.pi))
    out = np.empty_like(ph)
    out[order] = np.degrees(ph)
    return out


def plot_bode(
    result: IdentificationResult,
    axes: Optional[Sequence[Axes]] = None,
    *,
    units: str = "linear",
    u_unit: str = "",
    y_unit: str = "",
) -> Figure:
    """Identified |G(j omega_i)| and phi(omega_i) (95 % intervals), with the true curves when the plant is
    known.

    ``units``: ``"linear"`` (default: |G| on a log axis against omega in rad/s, the units of every number
    the library prints) or ``"dB"`` (20 log10 |G| against f in Hz); the phase lag is in degrees, unwrapped
    along frequency, in both.  ``u_unit``, ``y_unit``: the data's units, for |G|'s.
    """
    if units not in BODE_UNITS:
        raise InvalidParameterError(f"units = {units!r}: expected one of {', '.join(BODE_UNITS)}")
    db = units == "dB"
    if axes is None:
        # Gain over phase on one shared frequency axis, close together.
        fig, axes = _new_figure(nrows=2, size=(6.0, 6.0), sharex=True, hspace=0.08, left=0.95)
    else:
        fig = axes[0].get_figure()  # type: ignore[assignment]
    ax_g, ax_p = axes[0], axes[1]
    w = result.frequencies
    fx = w / (2.0 * np.pi) if db else w
    phases = result.phases
    if result.truth is not None:
        wd = np.geomspace(w.min() / 2, w.max() * 2, 400)
        g, ph = result.truth.plant.linear.gain_phase(wd)
        ph_deg = unwrapped_degrees(wd, ph)
        xd = wd / (2.0 * np.pi) if db else wd
        ax_g.plot(xd, 20.0 * np.log10(g) if db else g, "k-", lw=1, label="truth (alpha-normalised)")
        ax_p.plot(xd, ph_deg, "k-", lw=1, label="truth")
        # Put each estimated phase on the truth curve's branch so that the points sit on the curve.
        ph_true = np.radians(np.interp(np.log(w), np.log(wd), ph_deg))
        phases_deg = np.degrees(ph_true + (np.pi - np.mod(np.pi - (phases - ph_true), 2 * np.pi)))
    else:
        phases_deg = unwrapped_degrees(w, phases)
    z = z_value(0.95)
    g_se = np.array([z * (e.gain_se or 0.0) for e in result.experiments])
    p_err = np.degrees([z * (e.phase_se or 0.0) for e in result.experiments])
    gains = result.gains
    if db:
        g_plot = 20.0 * np.log10(gains)
        lo = 20.0 * np.log10(np.maximum(gains - g_se, gains * 1e-3))
        g_err: Any = np.vstack([g_plot - lo, 20.0 * np.log10(gains + g_se) - g_plot])
    else:
        g_plot, g_err = gains, g_se
    label = "identified (95 % CI)" if result.standard_errors is not None else "identified"
    ax_g.errorbar(fx, g_plot, yerr=g_err, fmt="o", color="C3", capsize=3, label=label)
    ax_p.errorbar(fx, phases_deg, yerr=p_err, fmt="o", color="C3", capsize=3, label=label)
    ax_g.set_xscale("log")
    if not db:
        ax_g.set_yscale("log")
    if ax_p.get_shared_x_axes().joined(ax_g, ax_p):
        ax_g.set_xlabel("")
    else:
        ax_p.set_xscale("log")
    gunit = _gain_unit(y_unit, u_unit)
    ax_g.set_ylabel(f"20 log10 |G| (dB re 1 {gunit})" if db else f"|G(j omega)| ({gunit})")
    ax_p.set_ylabel("phase lag phi = -arg G (deg)")
    ax_p.set_xlabel("frequency f (Hz)" if db else "angular frequency omega (rad/s)")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax_g.set_title("Frequency response of the linear part (alpha-normalised)")
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


def plot_loops(
    result: IdentificationResult,
    axes: Optional[Sequence[Axes]] = None,
    *,
    u_unit: str = "",
    y_unit: str = "",
) -> Figure:
    """One panel per experiment: the measured averaged loop (solid) and the model's (dashed), against the
    applied input u in the data's units (``u_unit``, ``y_unit`` label the axes).

    ``axes``: one per experiment (default: a new figure, :func:`panel_grid`).
    """
    fig, axes = _panels(len(result.experiments), axes)
    for i, (ax, e) in enumerate(zip(axes, result.experiments)):
        u = _closed(input_grid(e))
        ax.plot(u, _closed(e.ybar), lw=1.2, color="C0", label="measured")
        if e.model is not None:
            ax.plot(u, _closed(e.model), "--", lw=1.0, color="C3", label="model")
        title = e.source or f"experiment {i}"
        ax.set_title(f"{title}\nomega={e.frequency:.3g} rad/s, NRMSE={e.nrmse:.2g}", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6)
    fig.suptitle("Averaged loops against the applied input: measured (solid), model (dashed)", fontsize=9)
    fig.supxlabel(_unit("input u - its mean", u_unit), fontsize=8)
    fig.supylabel(_unit("averaged output ybar - its mean", y_unit), fontsize=8)
    return fig


def plot_residuals(
    result: IdentificationResult, axes: Optional[Sequence[Axes]] = None, *, y_unit: str = ""
) -> Figure:
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
    fig.supylabel(_unit("residual ybar - model", y_unit), fontsize=8)
    return fig

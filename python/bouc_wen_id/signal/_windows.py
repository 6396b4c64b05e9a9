"""One period of a record, and how far two periods are apart: the steady-segment detector's measure.

A window is one input period: the input's fundamental (amplitude, offset, phase) and the output's first
harmonics relative to the input's phase (its waveform) and offset, fitted by least squares, with the residual
noise.  :func:`distance` says how far two windows (or the medians of two runs) are in units of the
steadiness tolerance; :func:`trim_edges` and :func:`trim_settling` drop the end windows of a run that stand
out of it (design.md section 8.2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from .._backend import current_lab
from ._harmonic_ls import harmonic_basis, phase_angle

__all__ = [
    "Window",
    "Level",
    "window_features",
    "block_windows",
    "level_of",
    "distance",
    "wrap",
    "trim_edges",
    "trim_settling",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Relative tolerance of "steady" for the input amplitude and offset (relative to the amplitude).
STEADY_RTOL_U = 0.05
#: Relative tolerance of "steady" for the output's harmonics and offset (relative to their norm).
STEADY_RTOL_Y = 0.08
#: Tolerance (rad) on the change of the input's phase advance from one period to the next.
STEADY_PHASE_TOL = 0.05
#: Differences within this many noise standard deviations are always steady.
STEADY_NOISE_Z = 4.0
#: An end window of a steady run is dropped when further from the run's median than this many robust
#: standard deviations of the run's own period-to-period scatter ...
EDGE_Z = 4.0
#: ... and than these fractions of its median input amplitude and output harmonic norm (plus noise).
EDGE_RTOL_U = 0.01
EDGE_RTOL_Y = 0.02
#: A run's leading (trailing) windows are dropped while their mean output waveform differs from the mean
#: of the rest of the run at this significance (a chi-square test at the precision of the average, with
#: the per-period scatter from successive differences): an output still settling after the ramp, which
#: the per-window test above misses when it is small against one period's noise but not against N's.
SETTLE_ALPHA = 1e-3
#: ... but at most this fraction of a run is dropped from each end that way (slow drift is not settling).
SETTLE_MAX_FRACTION = 0.25
#: ... and only in runs of at least this many periods (the scatter of a shorter run is not known well).
SETTLE_MIN_WINDOWS = 8


@dataclass
class Window:
    """One input period of a block: the features compared from period to period."""

    block: int
    start: int
    stop: int
    amp_u: float
    off_u: float
    phase_u: float
    var_u: float
    harm_y: NDArray[np.complex128]
    off_y: float
    var_y: float
    idle: bool = False
    run: int = -1
    label: str = ""

    @property
    def size(self) -> int:
        return self.stop - self.start

    @property
    def norm_y(self) -> float:
        return _norm(self.harm_y)


def window_features(
    block: int, start: int, stop: int, basis: FloatArray, u: FloatArray, y: FloatArray
) -> Window:
    """The features of one window from its basis (the NumPy reference of :func:`block_windows`)."""
    rhs = np.column_stack([u, y])
    # Over one period the harmonics are orthogonal to within about 1/P (the Gram matrix is nearly
    # diagonal), so the small normal equations lose nothing here and are much cheaper than an SVD.
    try:
        coef = np.linalg.solve(basis.T @ basis, basis.T @ rhs)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(basis, rhs, rcond=None)[0]
    resid = rhs - basis @ coef
    dof = max(u.size - basis.shape[1], 1)
    var_u, var_y = (float(v) for v in np.sum(resid**2, axis=0) / dof)
    return _features(block, start, stop, coef[:, 0], coef[:, 1], var_u, var_y)


def _features(
    block: int, start: int, stop: int, coef_u: FloatArray, coef_y: FloatArray, var_u: float, var_y: float
) -> Window:
    """A window from the harmonic coefficients ``[c, a_1, b_1, ...]`` of its ``u`` and ``y``."""
    k_w = (coef_u.size - 1) // 2
    c_u = complex(coef_u[1], -coef_u[2])
    h_y = coef_y[1::2] - 1j * coef_y[2::2]
    ph = math.atan2(c_u.imag, c_u.real)
    # The output's harmonics relative to the input's phase: the waveform, whatever the window's start.
    h_rel = h_y * np.exp(-1j * np.arange(1, k_w + 1) * ph)
    return Window(block, start, stop, abs(c_u), float(coef_u[0]), ph, var_u, h_rel, float(coef_y[0]), var_y)


def block_windows(
    block: int,
    offset: int,
    tau: FloatArray,
    omega: float,
    u: FloatArray,
    y: FloatArray,
    spans: Sequence[tuple[int, int]],
    k_w: int,
) -> list[Window]:
    """The windows ``[s, e)`` of ``spans`` of one block (``tau``, ``u``, ``y``: the block's times from its
    start and samples; ``offset``: its first sample in the record), each fitted on ``k_w`` harmonics of
    ``omega``.

    On the Rust kernels every window's fit is the fused moment fit of ``window_fits`` (the block's phasors
    computed once); a window whose Gram matrix that path refuses, and the NumPy backend, solve the normal
    equations of the explicit basis (:func:`window_features`).
    """
    if not spans:
        return []
    starts, stops = [s for s, _ in spans], [e for _, e in spans]
    fast = current_lab().window_fits(tau, u, y, starts, stops, k_w, omega)
    if fast is None:
        full = harmonic_basis(phase_angle(omega, tau), k_w)
        return [window_features(block, offset + s, offset + e, full[s:e], u[s:e], y[s:e]) for s, e in spans]
    coef, rss = fast
    m = 2 * k_w + 1
    out = []
    basis: Optional[FloatArray] = None
    for (s, e), row, r in zip(spans, coef, rss):
        if not np.isfinite(r[0]):
            if basis is None:
                basis = harmonic_basis(phase_angle(omega, tau), k_w)
            out.append(window_features(block, offset + s, offset + e, basis[s:e], u[s:e], y[s:e]))
            continue
        dof = max(e - s - m, 1)
        out.append(
            _features(block, offset + s, offset + e, row[:m], row[m:], float(r[0]) / dof, float(r[1]) / dof)
        )
    return out


def wrap(x: float) -> float:
    return (x + math.pi) % TWO_PI - math.pi


@dataclass
class Level:
    """Median features of a run of windows (or a single window)."""

    amp_u: float
    off_u: float
    harm_y: NDArray[np.complex128]
    off_y: float
    var_u: float
    var_y: float
    size: int

    @property
    def norm_y(self) -> float:
        return _norm(self.harm_y)


def _norm(h: NDArray[np.complex128]) -> float:
    """The Euclidean norm of a short complex vector (``np.linalg.norm``'s value, without its overhead)."""
    return math.sqrt(float(np.vdot(h, h).real))


def level_of(ws: Sequence[Window]) -> Level:
    h = np.array([w.harm_y for w in ws])
    return Level(
        float(np.median([w.amp_u for w in ws])),
        float(np.median([w.off_u for w in ws])),
        np.median(h.real, axis=0) + 1j * np.median(h.imag, axis=0),
        float(np.median([w.off_y for w in ws])),
        float(np.median([w.var_u for w in ws])),
        float(np.median([w.var_y for w in ws])),
        int(np.median([w.size for w in ws])),
    )


def distance(a: Level | Window, b: Level | Window) -> float:
    """How far apart two periods (or levels) are, in units of the steadiness tolerance (> 1: not steady)."""
    size = min(a.size, b.size)
    noise_u = math.sqrt(2.0 * (a.var_u + b.var_u) / size)
    noise_y = math.sqrt(2.0 * (a.var_y + b.var_y) / size)
    k_w = a.harm_y.size
    amp = max(a.amp_u, b.amp_u)
    d_amp = abs(a.amp_u - b.amp_u) / (STEADY_RTOL_U * amp + STEADY_NOISE_Z * noise_u)
    d_off = abs(a.off_u - b.off_u) / (STEADY_RTOL_U * amp + STEADY_NOISE_Z * noise_u)
    norm_y = max(a.norm_y, b.norm_y)
    d_wave = _norm(a.harm_y - b.harm_y) / (
        STEADY_RTOL_Y * norm_y + STEADY_NOISE_Z * noise_y * math.sqrt(k_w) + 1e-300
    )
    d_off_y = abs(a.off_y - b.off_y) / (STEADY_RTOL_Y * norm_y + STEADY_NOISE_Z * noise_y + 1e-300)
    return max(d_amp, d_off, d_wave, d_off_y)


def trim_edges(windows: Sequence[Window], i: int, j: int) -> tuple[int, int]:
    """Drop the end windows of a run ``[i, j)`` that stand out from its interior: the last period of a
    ramp or the output still settling, within the general tolerance but beyond the run's own scatter."""
    while j - i >= 2:
        bad = _outliers(windows[i:j])
        if bad[0]:
            i += 1
        elif bad[-1]:
            j -= 1
        else:
            break
    return i, j


def trim_settling(windows: Sequence[Window], i: int, j: int) -> tuple[int, int]:
    """Drop the leading and trailing windows of a run ``[i, j)`` whose mean output waveform differs from
    the mean of the rest at the precision of the final average (see :data:`SETTLE_ALPHA`).

    Harmonic by harmonic (settling of the linear part shows mostly in the fundamental, and a test on all
    harmonics at once would dilute it), the mean of the first ``k`` windows is compared with the mean of
    the others for every split ``k`` up to half the run: a chi-square statistic on 2 degrees of freedom
    with the harmonic's per-window scatter from successive differences (noise and fast wander, not a slow
    trend), Bonferroni-corrected over the splits and harmonics scanned.
    """
    n0 = j - i
    if n0 < SETTLE_MIN_WINDOWS:
        return i, j
    cap = max(1, int(SETTLE_MAX_FRACTION * n0))
    h_all = np.array([w.harm_y for w in windows[i:j]])  # (n, K) complex
    # E|d|^2 of a successive difference is 2 * (2 s^2) per harmonic; the median of chi2_2 is 2 ln 2.
    # White noise has the same scatter at every harmonic (an orthogonal basis): the pooled estimate is the
    # stable one on a short run, the per-harmonic one keeps a harmonic's own wander.
    d2 = np.abs(np.diff(h_all, axis=0)) ** 2 / (4.0 * math.log(2.0))
    s2 = np.maximum(np.median(d2, axis=0), float(np.median(d2)))
    usable = s2 > 0.0
    if not np.any(usable):
        return i, j
    h_all, s2 = h_all[:, usable], s2[usable]

    def head_differs(h: NDArray[np.complex128]) -> bool:
        n = h.shape[0]
        if n < 4:
            return False
        m = n // 2
        csum = np.cumsum(h, axis=0)
        k = np.arange(1, m + 1)
        head = csum[:m] / k[:, None]
        tail = (csum[-1] - csum[:m]) / (n - k)[:, None]
        q = np.abs(head - tail) ** 2 / (s2[None, :] * (1.0 / k + 1.0 / (n - k))[:, None])
        from scipy.special import chdtri  # type: ignore[import-untyped]  # on first use: a lean import

        return bool(np.max(q) > float(chdtri(2, SETTLE_ALPHA / q.size)))

    lo, hi = 0, n0
    while lo < cap and head_differs(h_all[lo:hi]):
        lo += 1
    while n0 - hi < cap and head_differs(h_all[lo:hi][::-1]):
        hi -= 1
    return i + lo, i + hi


def _outliers(run: Sequence[Window]) -> NDArray[np.bool_]:
    """Windows of a run off its median by more than 4 robust standard deviations of the run's scatter
    (and more than 1 % of the input amplitude or 2 % of the output's harmonics, and their noise)."""
    amps = np.array([w.amp_u for w in run])
    med = float(np.median(amps))
    spread_u = 1.4826 * float(np.median(np.abs(amps - med)))
    harm = np.array([w.harm_y for w in run])
    h_med = np.median(harm.real, axis=0) + 1j * np.median(harm.imag, axis=0)
    dev_h = np.linalg.norm(harm - h_med, axis=1)
    spread_h = 1.4826 * float(np.median(dev_h))
    sizes = np.array([w.size for w in run], dtype=np.float64)
    noise_u = STEADY_NOISE_Z * np.sqrt(2.0 * np.array([w.var_u for w in run]) / sizes)
    noise_y = STEADY_NOISE_Z * np.sqrt(2.0 * h_med.size * np.array([w.var_y for w in run]) / sizes)
    bad_u = np.abs(amps - med) > max(EDGE_Z * spread_u, EDGE_RTOL_U * med) + noise_u
    bad_y = dev_h > max(EDGE_Z * spread_h, EDGE_RTOL_Y * float(np.linalg.norm(h_med))) + noise_y
    out: NDArray[np.bool_] = bad_u | bad_y
    return out

"""Steady segments: cut a record into its steady stretches of whole input periods (design.md section 8.2).

:func:`find_steady_segments` runs in named phases: check the record, split it into blocks at the gaps of
its time axis and estimate the frequency, cut the blocks into period-long windows
(:mod:`._windows`), mark the idle ones, link consecutive windows that are steady together, form steady runs
and trim their ends, keep the runs long enough whose input fits a sine, and say why everything else was
dropped.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    NotPeriodicError,
    UndersampledError,
    ZeroAmplitudeError,
)
from ..validation import MIN_SAMPLES_PER_PERIOD, check_time_axis, finite_arrays
from ._sine import (
    NYQUIST_MARGIN,
    SineFit,
    analyse_input,
    check_periodic,
    check_sampling,
    dft_peak,
    warn_distortion,
)
from ._windows import (
    STEADY_NOISE_Z,
    STEADY_PHASE_TOL,
    STEADY_RTOL_U,
    Level,
    Window,
    block_windows,
    distance,
    level_of,
    trim_edges,
    trim_settling,
    wrap,
)

__all__ = ["Segment", "SegmentReport", "find_steady_segments"]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: A time step longer than this multiple of the median step is a gap (a DAQ pause) in
#: :func:`find_steady_segments`; everywhere else it is a :class:`TimeAxisError`.
TIME_GAP_FACTOR = 1.5
#: A window whose input fundamental is below this fraction of the record's steady amplitude is idle.
IDLE_FRACTION = 0.05
#: Harmonics of ``y`` compared from period to period (the waveform).
WINDOW_HARMONICS = 8
#: Most passes of cutting windows off their run's median until nothing changes.
MAX_RUN_PASSES = 50


@dataclass(frozen=True)
class Segment:
    """A steady stretch ``[start, stop)`` of whole input periods (``periods`` of them, to rounding)."""

    start: int
    stop: int
    periods: float

    @property
    def slice(self) -> slice:
        """``slice(start, stop)``, to index the record's arrays."""
        return slice(self.start, self.stop)


@dataclass(frozen=True)
class SegmentReport:
    """What :func:`find_steady_segments` kept and dropped.

    ``dropped`` holds ``(start, stop, reason)`` for every stretch of samples not kept, in record order; the
    reasons are listed in the module documentation.  ``fits`` holds one :class:`SineFit` of the input per
    kept segment, fitted on that segment.
    """

    kept: tuple[Segment, ...]
    dropped: tuple[tuple[int, int, str], ...]
    fits: tuple[SineFit, ...]

    def summary(self) -> str:
        lines = [f"{len(self.kept)} steady segment(s):"]
        for seg, fit in zip(self.kept, self.fits):
            lines.append(
                f"  [{seg.start}, {seg.stop}): {seg.periods:.2f} periods at {fit.frequency / TWO_PI:.6g} Hz, "
                f"U = {fit.amplitude:.4g}, THD = {fit.thd:.3g}"
            )
        for start, stop, reason in self.dropped:
            lines.append(f"  dropped [{start}, {stop}): {reason}")
        return "\n".join(lines)


def find_steady_segments(
    t: ArrayLike,
    u: ArrayLike,
    y: ArrayLike,
    *,
    nominal_frequency: Optional[float] = None,
    min_periods: float = 2.0,
) -> SegmentReport:
    """Cut a record into its steady stretches of whole input periods, one experiment each.

    The time axis may have gaps (a step longer than 1.5 times the median, e.g. a DAQ pause); the record is
    analysed block by block between them.  In each block the input frequency is estimated (DFT peak), the
    block is cut into period-long windows, and in each window the input's fundamental (amplitude, offset,
    phase) and the output's first 8 harmonics relative to the input's phase (its waveform) and offset are
    fitted by least squares, with the residual noise.

    - A window is *idle* when its input amplitude is below 5 % of the record's steady amplitude (the
      largest median of three consecutive windows) or below 4 noise standard deviations.
    - Two consecutive non-idle windows are *steady together* when their input amplitudes and offsets differ
      by less than 5 % of the amplitude, their output harmonic vectors and offsets by less than 8 % of the
      output's harmonic norm (plus 4 noise standard deviations in each case: what white noise explains),
      and the input's phase advance from one period to the next stays within 0.05 rad (plus noise) of the
      block's typical advance (a phase jump or a change of frequency breaks the run).  The relative
      tolerances absorb the period-to-period wander of real actuators (1-3 %), which white noise does not
      explain.
    - Maximal runs of windows steady together, whose every window also lies within the same tolerances of
      the run's median, are the steady stretches.  Their end windows are then dropped while they stand out
      of the run: further from its median than 4 robust standard deviations of the run's own scatter and
      than 1 % (input amplitude) or 2 % (output harmonics) of it, plus noise (the last period of a ramp, an
      output still settling).
    - Steady stretches of at least ``min_periods`` periods are kept (at least two periods are always
      needed to call a stretch steady).  Each starts at its first window and spans a whole number of
      periods of its own frequency, fitted on it as by :func:`analyse_sine`.

    Parameters
    ----------
    t, u, y : array_like
        Time (s), input and output, equal lengths.
    nominal_frequency : float, optional
        Hint for the input frequency (rad/s), see :func:`analyse_sine`.
    min_periods : float
        Fewest whole steady periods a kept segment must span (>= 1).

    Returns
    -------
    SegmentReport

    Raises
    ------
    InsufficientDataError
        Nothing steady of ``min_periods`` periods was found (the message says what the record holds).
    UndersampledError, NotPeriodicError, ZeroAmplitudeError, TimeAxisError, NonFiniteError,
    InvalidParameterError
        As :func:`analyse_sine`, for the record as a whole or for a kept segment.

    Warns
    -----
    DistortedInputWarning
        A kept segment's input has a total harmonic distortion above 0.1.
    """
    rec = _check_record(t, u, y, nominal_frequency, min_periods)
    blocks = _split_blocks(rec)
    windows = _cut_windows(rec, blocks)
    a_ref = _mark_idle(windows)
    link = _link_windows(windows, len(blocks.bounds))
    runs = _steady_runs(windows, link)
    kept_runs, kept, fits = _keep_segments(rec, blocks, windows, runs)
    for r, (i, j) in enumerate(runs):
        for k in range(i, j):
            windows[k].run = r
    _classify(windows, runs, kept_runs)
    dropped = _dropped_stretches(windows, blocks.bounds, kept, rec.u, a_ref)
    if not kept:
        raise _nothing_steady(rec, blocks, dropped)
    for fit in fits:
        warn_distortion(fit, stacklevel=3)
    return SegmentReport(tuple(kept), tuple(dropped), tuple(fits))


@dataclass
class _Record:
    """The checked record and what the phases share of it."""

    t: FloatArray
    u: FloatArray
    y: FloatArray
    dt: float
    nominal: Optional[float]
    min_periods: float
    #: Whole periods a kept segment needs.
    need: int


@dataclass
class _Blocks:
    """The record's contiguous blocks (between gaps of the time axis) and their input frequencies."""

    bounds: list[tuple[int, int]]
    main: int
    omega_main: float
    #: Each block's frequency, filled in by :func:`_cut_windows`.
    omega: list[float]

    def total_periods(self, dt: float) -> float:
        return float(sum((b - a) * dt * w / TWO_PI for (a, b), w in zip(self.bounds, self.omega)))


def _check_record(
    t: ArrayLike, u: ArrayLike, y: ArrayLike, nominal_frequency: Optional[float], min_periods: float
) -> _Record:
    """Arrays, ``min_periods``, the hint, and a time axis uniform but for gaps; refuses a constant input."""
    tt, uu, yy = finite_arrays(t=t, u=u, y=y)
    mp = float(min_periods)
    if not math.isfinite(mp) or mp < 1.0:
        raise InvalidParameterError(f"min_periods = {min_periods} must be a finite number >= 1")
    if tt.size < 8:
        raise InsufficientDataError(f"at least 8 samples are needed, got {tt.size}")
    if nominal_frequency is not None and not (
        math.isfinite(float(nominal_frequency)) and float(nominal_frequency) > 0.0
    ):
        raise InvalidParameterError(f"nominal_frequency = {nominal_frequency} rad/s must be finite and > 0")
    dt = check_time_axis(tt, gap_factor=TIME_GAP_FACTOR)
    spread = float(np.ptp(uu))
    if spread == 0.0 or spread <= 1e-12 * float(np.max(np.abs(uu))):
        raise ZeroAmplitudeError(f"the input is constant ({uu[0]:.6g}): there is no sine to find")
    return _Record(tt, uu, yy, dt, nominal_frequency, mp, math.ceil(mp - 1e-9))


def _block_frequency(t: FloatArray, u: FloatArray, dt: float, nominal: Optional[float]) -> Optional[float]:
    """A rough frequency of one contiguous block (DFT peak), or None when it has none."""
    if u.size < 8 or np.ptp(u) == 0.0:
        return None
    try:
        return dft_peak(u, dt, nominal)
    except (InsufficientDataError, NotPeriodicError):
        return None


def _split_blocks(rec: _Record) -> _Blocks:
    """Blocks between the gaps; the record's frequency from the block holding most of the input's energy."""
    gap = np.diff(rec.t) > TIME_GAP_FACTOR * rec.dt
    edges = np.concatenate([[0], np.flatnonzero(gap) + 1, [rec.t.size]])
    bounds = [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]
    energy = [float(np.sum((rec.u[a:b] - rec.u[a:b].mean()) ** 2)) for a, b in bounds]
    main = int(np.argmax(energy))
    a0, b0 = bounds[main]
    omega_main = _block_frequency(rec.t[a0:b0], rec.u[a0:b0], rec.dt, rec.nominal)
    if omega_main is None:
        raise NotPeriodicError("no periodic input found in the record")
    p_main = TWO_PI / (omega_main * rec.dt)
    if p_main < MIN_SAMPLES_PER_PERIOD or omega_main * rec.dt > (1.0 - NYQUIST_MARGIN) * math.pi:
        raise UndersampledError(
            f"the input's frequency {omega_main / TWO_PI:.6g} Hz gives {p_main:.3g} samples per period at "
            f"dt = {rec.dt:.6g} s; at least {MIN_SAMPLES_PER_PERIOD} are needed: sample faster"
        )
    return _Blocks(bounds, main, omega_main, [])


def _cut_windows(rec: _Record, blocks: _Blocks) -> list[Window]:
    """Each block cut into period-long windows of its own frequency, with their features."""
    dt, omega_main = rec.dt, blocks.omega_main
    p_main = TWO_PI / (omega_main * dt)
    windows: list[Window] = []
    for bi, (a, b) in enumerate(blocks.bounds):
        omega = omega_main
        if bi != blocks.main and b - a >= 3 * p_main:
            cand = _block_frequency(rec.t[a:b], rec.u[a:b], dt, rec.nominal)
            if cand is not None:
                p_c = TWO_PI / (cand * dt)
                if p_c >= MIN_SAMPLES_PER_PERIOD and (b - a) >= 2 * p_c:
                    omega = cand
        blocks.omega.append(omega)
        p = TWO_PI / (omega * dt)
        k_w = max(1, min(WINDOW_HARMONICS, int((p - 1.0) // 2) - 1))
        # Whole periods; the last may be up to 5 % short (a record of exactly N periods at a frequency
        # estimated a hair low).
        count = math.floor((b - a) / p + 0.05)
        spans = [(math.floor(i * p), min(math.floor((i + 1) * p), b - a)) for i in range(count)]
        windows.extend(block_windows(bi, a, rec.t[a:b] - rec.t[a], omega, rec.u[a:b], rec.y[a:b], spans, k_w))
    if not windows:
        raise InsufficientDataError(
            f"the record holds {blocks.total_periods(dt):.3g} periods of {omega_main / TWO_PI:.6g} Hz: not "
            "one whole period to analyse"
        )
    return windows


def _mark_idle(windows: Sequence[Window]) -> float:
    """Mark the idle windows; returns the record's steady amplitude (largest median of three windows)."""
    amps = np.array([w.amp_u for w in windows])
    # The median of each window and its neighbours (two at the ends), vectorised over the interior.
    smooth = [float(np.median(amps[:2])), float(np.median(amps[-2:]))]
    if amps.size >= 3:
        smooth.append(float(np.max(np.median(np.stack([amps[:-2], amps[1:-1], amps[2:]]), axis=0))))
    a_ref = max(smooth)
    for w in windows:
        noise = math.sqrt(2.0 * w.var_u / w.size)
        w.idle = w.amp_u < IDLE_FRACTION * a_ref or w.amp_u < STEADY_NOISE_Z * noise
    return a_ref


def _link_windows(windows: Sequence[Window], n_blocks: int) -> list[bool]:
    """``link[i]``: window i is steady together with window i - 1 (same block, neither idle)."""
    link = [False] * len(windows)
    for bi in range(n_blocks):
        pairs = [
            i
            for i, w in enumerate(windows)
            if w.block == bi and i > 0 and windows[i - 1].block == bi and not (w.idle or windows[i - 1].idle)
        ]
        close = {i: distance(windows[i - 1], windows[i]) <= 1.0 for i in pairs}
        adv = {i: wrap(windows[i].phase_u - windows[i - 1].phase_u) for i in pairs}
        # The phase advance per period of the block's steady parts (ramps shift the apparent phase).
        ref = [adv[i] for i in pairs if close[i]] or list(adv.values())
        adv_ref = float(np.median(ref)) if ref else 0.0
        for i in pairs:
            w0, w1 = windows[i - 1], windows[i]
            noise_ph = math.sqrt(2.0 * (w0.var_u + w1.var_u) / min(w0.size, w1.size)) / max(
                min(w0.amp_u, w1.amp_u), 1e-300
            )
            d_ph = abs(wrap(adv[i] - adv_ref)) / (STEADY_PHASE_TOL + STEADY_NOISE_Z * noise_ph)
            link[i] = close[i] and d_ph <= 1.0
    return link


def _steady_runs(windows: Sequence[Window], link: Sequence[bool]) -> list[tuple[int, int]]:
    """Runs of linked windows; windows off their run's median are cut out until nothing changes, then the
    runs' ends are trimmed (:func:`trim_edges`, :func:`trim_settling`)."""
    excluded = [False] * len(windows)
    runs: list[tuple[int, int]] = []
    for _ in range(MAX_RUN_PASSES):
        runs = []
        k0 = 0
        for k in range(1, len(windows) + 1):
            if not (k < len(windows) and link[k] and not excluded[k] and not excluded[k - 1]):
                if k - k0 >= 2:
                    runs.append((k0, k))
                k0 = k
        changed = False
        for i, j in runs:
            lev = level_of(windows[i:j])
            for k in range(i, j):
                if distance(lev, windows[k]) > 1.0:
                    excluded[k] = True
                    changed = True
        if not changed:
            break
    runs = [r for r in (trim_edges(windows, i, j) for i, j in runs) if r[1] - r[0] >= 2]
    return [trim_settling(windows, i, j) for i, j in runs]


def _keep_segments(
    rec: _Record, blocks: _Blocks, windows: Sequence[Window], runs: list[tuple[int, int]]
) -> tuple[list[tuple[int, int]], list[Segment], list[SineFit]]:
    """The runs of at least ``need`` periods whose input fits a sine, as segments of whole periods of their
    own frequency (up to the block's end or the next segment).  A run whose input the fit refuses is not
    steady after all: it is removed from ``runs``."""
    dt = rec.dt
    candidates = [(i, j) for i, j in runs if j - i >= rec.need]
    kept_runs: list[tuple[int, int]] = []
    kept: list[Segment] = []
    fits: list[SineFit] = []
    for r, (i, j) in enumerate(candidates):
        limit = blocks.bounds[windows[i].block][1]
        if r + 1 < len(candidates):
            limit = min(limit, windows[candidates[r + 1][0]].start)
        start, stop0 = windows[i].start, windows[j - 1].stop
        try:
            sub = analyse_input(rec.t[start:stop0], rec.u[start:stop0], rec.nominal, harmonics=False)
            stop = min(start + round((j - i) * TWO_PI / (sub.fit.frequency * dt)), limit)
            ana = analyse_input(
                rec.t[start:stop], rec.u[start:stop], rec.nominal, omega_start=sub.fit.frequency
            )
            check_periodic(ana)
            check_sampling(ana)
        except (NotPeriodicError, UndersampledError, InsufficientDataError, ZeroAmplitudeError):
            runs.remove((i, j))
            continue
        kept_runs.append((i, j))
        kept.append(Segment(start, stop, (stop - start) * dt * ana.fit.frequency / TWO_PI))
        fits.append(ana.fit)
    return kept_runs, kept, fits


def _nothing_steady(
    rec: _Record, blocks: _Blocks, dropped: Sequence[tuple[int, int, str]]
) -> InsufficientDataError:
    """The error when nothing was kept: what the record holds, in periods per reason."""
    omega_main = blocks.omega_main
    tally: dict[str, float] = {}
    for s, e, why in dropped:
        tally[why] = tally.get(why, 0.0) + (e - s) * rec.dt * omega_main / TWO_PI
    what = ", ".join(f"{why} {v:.1f}" for why, v in sorted(tally.items(), key=lambda kv: -kv[1]))
    return InsufficientDataError(
        f"no stretch of >= {rec.min_periods:g} steady periods found: the record holds "
        f"{blocks.total_periods(rec.dt):.1f} periods of {omega_main / TWO_PI:.6g} Hz, in periods: {what}"
    )


def _classify(windows: list[Window], runs: list[tuple[int, int]], kept_runs: list[tuple[int, int]]) -> None:
    """Label every window: "idle", "too short", "amplitude ramp", "level change", "transient", and the
    windows of kept segments ``_LEFTOVER`` (for the sample or two of them a segment may leave out)."""
    kept_set = set(kept_runs)
    labels = [""] * len(windows)
    for i, j in runs:
        for k in range(i, j):
            labels[k] = "kept" if (i, j) in kept_set else "too short"
    for k, w in enumerate(windows):
        if w.idle:
            labels[k] = "idle"
    levels = {r: level_of(windows[i:j]) for r, (i, j) in enumerate(runs)}
    # Unsteady stretches: consecutive unlabelled windows of one block.
    k = 0
    while k < len(windows):
        if labels[k]:
            k += 1
            continue
        e = k
        while e < len(windows) and not labels[e] and windows[e].block == windows[k].block:
            e += 1
        left = windows[k - 1] if k > 0 and windows[k - 1].block == windows[k].block else None
        right = windows[e] if e < len(windows) and windows[e].block == windows[k].block else None

        def side(w: Optional[Window]) -> Optional[float | Level]:
            if w is None:
                return None
            if w.idle:
                return 0.0
            return levels[w.run] if w.run >= 0 else w.amp_u

        lft, rgt = side(left), side(right)
        if isinstance(lft, Level) and isinstance(rgt, Level):
            why = "level change" if distance(lft, rgt) > 1.0 else "transient"
            labels[k:e] = [why] * (e - k)
        else:
            lv = lft.amp_u if isinstance(lft, Level) else lft
            rv = rgt.amp_u if isinstance(rgt, Level) else rgt
            labels[k:e] = _ramp_labels([w.amp_u for w in windows[k:e]], lv, rv)
        k = e
    for w, lab in zip(windows, labels):
        w.label = lab if lab != "kept" else _LEFTOVER


def _ramp_labels(amps: Sequence[float], left: Optional[float], right: Optional[float]) -> list[str]:
    """Unsteady windows next to rest or a steady level: "amplitude ramp" where at least two consecutive
    windows move the input amplitude the same way (each step more than the steadiness tolerance), from
    the neighbour before to the one after; "transient" otherwise (a one-period start or stop, a peak)."""
    ext = [left, *amps, right]
    tol = STEADY_RTOL_U * max(v for v in ext if v is not None)

    def step(i: int) -> int:  # direction of the step from ext[i] to ext[i + 1]; 0: none or too small
        a, b = ext[i], ext[i + 1]
        if a is None or b is None or abs(b - a) <= tol:
            return 0
        return 1 if b > a else -1

    direction = []
    for q in range(len(amps)):
        before, after = step(q), step(q + 1)
        sides = [d for d, v in ((before, ext[q]), (after, ext[q + 2])) if v is not None]
        direction.append(sides[0] if sides and all(d == sides[0] != 0 for d in sides) else 0)
    labels = ["transient"] * len(amps)
    q = 0
    while q < len(amps):
        e = q + 1
        while e < len(amps) and direction[e] == direction[q]:
            e += 1
        if direction[q] != 0 and e - q >= 2:
            labels[q:e] = ["amplitude ramp"] * (e - q)
        q = e
    return labels


#: Placeholder label of the samples of a kept window left outside its segment.
_LEFTOVER = "~"


def _dropped_stretches(
    windows: list[Window], blocks: list[tuple[int, int]], kept: list[Segment], u: FloatArray, a_ref: float
) -> list[tuple[int, int, str]]:
    """Everything outside the kept segments as ``(start, stop, reason)`` stretches, in record order."""
    pieces: list[tuple[int, int, str]] = []
    for bi, (a, b) in enumerate(blocks):
        ws = [w for w in windows if w.block == bi]
        pieces += [(w.start, w.stop, w.label) for w in ws]
        tail = ws[-1].stop if ws else a
        if tail < b:
            if ws:
                why = ws[-1].label  # less than a period left at the block's end
            else:  # a block shorter than one period: idle unless its input moves
                why = "idle" if 0.5 * float(np.ptp(u[a:b])) < IDLE_FRACTION * a_ref else "transient"
            pieces.append((tail, b, why))
    # Idle between two active stretches (gaps of the time axis included) is a pause.
    active = [w for w in windows if not w.idle]
    if active:
        first, last = active[0].start, active[-1].stop
        pieces = [
            (s, e, "pause" if why == "idle" and first <= s and e <= last else why) for s, e, why in pieces
        ]
    # Cut the kept segments out.
    cut: list[tuple[int, int, str]] = []
    for s, e, why in pieces:
        cur = s
        for seg in kept:
            if seg.stop <= cur or seg.start >= e:
                continue
            if seg.start > cur:
                cut.append((cur, seg.start, why))
            cur = max(cur, seg.stop)
        if cur < e:
            cut.append((cur, e, why))
    # What a segment left of its own windows takes the reason of the dropped stretch next to it.
    labels = [why for _, _, why in cut]
    for i, (s, e, why) in enumerate(cut):
        if why != _LEFTOVER:
            continue
        after = labels[i + 1] if i + 1 < len(cut) and cut[i + 1][0] == e else _LEFTOVER
        before = labels[i - 1] if i > 0 and cut[i - 1][1] == s else _LEFTOVER
        labels[i] = after if after != _LEFTOVER else before if before != _LEFTOVER else "partial period"
    out: list[tuple[int, int, str]] = []
    for (s, e, _), why in zip(cut, labels):
        if out and out[-1][1] == s and out[-1][2] == why:
            out[-1] = (out[-1][0], e, why)
        else:
            out.append((s, e, why))
    return out

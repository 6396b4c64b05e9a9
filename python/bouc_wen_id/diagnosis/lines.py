"""Disturbances not locked to the input: a stationary sinusoid (mains hum, a fan) on a recording's output.

Averaging whole periods takes out everything that repeats with the input's period and leaves the noise
reduced N-fold. A sinusoid at a frequency that is no harmonic of the input is neither: its average over N
periods keeps ``|sin(N pi f) / (N sin(pi f))|`` of it (``f`` its phase advance per period, in cycles), a
coherent wave in the averaged period, while the differences of neighbouring periods, the noise floor, see
only ``2 |sin(pi f)|`` of it. On the review's null (50 Hz at 2 noise sd, five experiments of 6-40 periods)
the hum's remainder at 2 rad/s (f = 0.08 per period, 10 periods) was 0.47 noise sd, against a floor of
0.35 sd for the averaged period: "unexplained structure remains" in 4 of 4 seeds, with no physics in it.

A white or coloured noise model cannot describe it (it is deterministic), so it is modelled: each recording's
steady periods minus their mean (what the input's harmonics leave) are searched for the strongest line at
least :data:`GUARD_BINS` record bins from every harmonic of the input; it is kept when it stands out of the
local periodogram level beyond chance (:data:`LINE_ALPHA` per diagnosis, Bonferroni over the recordings and
the bins, corrected for the level's own error: :func:`limit`), when the bin mirrored about its nearest
harmonic holds less than :data:`MIRROR_SHARE` of its power (a loop that drifts or settles modulates its
harmonics: two sidebands of equal power; a line has one) and when its amplitude is the same in both halves of
the record (a free oscillation decays) and it stands out of its own scatter between segments of the record
(:mod:`.line_coherence`: a narrow noise band's phase wanders). Its frequency, refined by least squares, is
then fitted in every recording (jointly with the periodic mean: the line's own average over the periods is not
separable from the loop and stays in the regressors' complement) and taken out of the whole record when
significant there (a line too close to a harmonic to be found alone in one experiment is found in another).
Bins within the guard are searched too when the rest holds no line, about the periodic mean alone
(:func:`near_candidate`: a hum 0.08 cycle a period off a harmonic, review 46). A recording whose measured
input holds a line of its own is neither searched nor cleaned: its output's lines are the response to that
input. The recordings handed to the diagnosis are copies; the user's are not modified.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: False-alarm level of the line search per diagnosis: Bonferroni over the recordings searched and each one's
#: periodogram bins, with the chance that the estimated noise level is low (:func:`limit`). Measured on
#: null draws (/tmp/noise36/lines_null.py of session 36: six recordings of 8 periods at 128 samples, 1000
#: draws each): 0 in 1000 under white, AR(1) 0.8 and Student t3 noise; with the earlier per-recording 1e-4
#: and an uncorrected level, 2.3 % of white-noise diagnoses reported a line (0.42 % of recordings).
LINE_ALPHA = 1e-3
#: Least distance of a searched line from every harmonic of the input, in bins of the whole record (a
#: drifting loop's sidebands sit within a bin or two of its harmonics; the mirror test handles the rest).
GUARD_BINS = 2.5
#: Largest share of the line's periodogram power its mirror about the nearest harmonic may hold.
MIRROR_SHARE = 0.1
#: Most lines searched per recording.
MAX_LINES = 3
#: Fewest steady periods searched for a line (the quadratic drift takes three per sample of the period);
#: a line found elsewhere is fitted in any recording of 3 or more.
MIN_PERIODS = 5
#: Lowest frequency searched or fitted, in harmonics of the input.
MIN_HARMONIC = 2.0
#: Half-width of the band whose median is a line's local noise level, in harmonics of the input ...
LEVEL_HARMONICS = 2
#: ... and at least this many record bins (a median of ~12 searched bins, as at 8 periods before, was low
#: by a third often enough to make the search's chance 40 times its design).
LEVEL_BINS = 48
#: Efficiency of the median of exponential periodogram bins as a level estimate, relative to their mean
#: (its variance ``1 / (K ln(2)^2)`` against ``1 / K``): K bins' median is worth ``MEDIAN_EFFICIENCY K``.
MEDIAN_EFFICIENCY = math.log(2.0) ** 2
#: Zero padding of the search periodogram.
PAD = 4
#: What the padded periodogram's maximum exceeds that of its independent bins by (in units of the level).
PAD_EXCESS = 1.0
#: Largest coherence of a line with the periodic mean (its average over the periods, relative to itself)
#: at which it is still fitted: above, the line and the loop cannot be told apart in the record.
MAX_COHERENCE = 0.95


def _orth(sig: FloatArray, n: int, p: int, drift: bool = True) -> FloatArray:
    """``sig`` (n whole periods) less what the periodic mean and a quadratic drift of it in the period
    index can take (each sample of the period a series over the periods, as the colour check's trend): a
    loop that drifts or settles is taken up there and leaves no line. ``drift=False``: the mean alone (the
    fit of a line already found, whose frequency is known: one near a harmonic is taken up by a drift)."""
    rows = sig.reshape(n, p)
    idx = np.arange(n, dtype=np.float64)
    trend = np.vander(idx - idx.mean(), min(3, n - 1) if drift else 1)
    out: FloatArray = (rows - trend @ np.linalg.lstsq(trend, rows, rcond=None)[0]).ravel()
    return out


def _fit(r: FloatArray, f: float, n: int, p: int, drift: bool = True) -> tuple[complex, float, float]:
    """``(amplitude, explained power, coherence)`` of a line at ``f`` cycles per sample fitted to the
    residual ``r`` (periodic mean taken out), jointly with the periodic mean."""
    j = np.arange(r.size, dtype=np.float64)
    c, s = np.cos(2 * math.pi * f * j), np.sin(2 * math.pi * f * j)
    x = np.column_stack([_orth(c, n, p, drift), _orth(s, n, p, drift)])
    norm = float(np.sum(c * c + s * s))
    coh = math.sqrt(max(0.0, 1.0 - float(np.sum(x * x)) / norm)) if norm > 0 else 1.0
    beta = np.linalg.lstsq(x, r, rcond=None)[0]
    fitted = x @ beta
    return complex(beta[0], -beta[1]), float(fitted @ fitted), coh


def _spectrum(
    r: FloatArray, n: int, p: int, low: float = MIN_HARMONIC
) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
    """The padded periodogram of ``r`` (white noise of variance s2: mean s2), its frequencies (cycles per
    sample), each one's nearest harmonic of the input, and the bins searched: :data:`GUARD_BINS` from every
    harmonic and above :data:`MIN_HARMONIC` (a red noise and a loop's slow wander live below)."""
    m = r.size
    size = PAD * m
    per: FloatArray = np.abs(np.fft.rfft(r, size)) ** 2 / m
    freq: FloatArray = np.arange(per.size) / size
    harm: FloatArray = np.round(freq * p) / p
    far = (np.abs(freq - harm) * m >= GUARD_BINS) & (freq * p >= low)
    return per, freq, harm, far


def _level(per: FloatArray, far: NDArray[np.bool_], k: int, n: int) -> tuple[float, float]:
    """The noise's periodogram level about bin ``k``: the median of the searched bins within
    :data:`LEVEL_HARMONICS` harmonics or :data:`LEVEL_BINS` record bins (a coloured noise's level changes
    over the band), over ln 2; and how many independent exponential bins' mean it is worth."""
    half = max(LEVEL_BINS, LEVEL_HARMONICS * n) * PAD
    lo, hi = max(0, k - half), min(per.size, k + half + 1)
    near = per[lo:hi][far[lo:hi]]  # the bins the search sees (the drift's projection dips at harmonics)
    if not near.size:
        return 0.0, 0.0
    return float(np.median(near)) / math.log(2.0), MEDIAN_EFFICIENCY * near.size / PAD


def limit(chance: float, worth: float) -> float:
    """The ratio of a bin's periodogram to the estimated level that noise exceeds with ``chance``: for an
    exponential bin over a level worth ``worth`` independent bins (F with 2 and ``2 worth`` degrees of
    freedom) ``worth (chance^(-1/worth) - 1)``, the exponential's ``ln(1 / chance)`` as ``worth`` grows,
    plus :data:`PAD_EXCESS` for the padded periodogram's maximum."""
    w = max(worth, 1.0)
    return w * math.expm1(-math.log(chance) / w) + PAD_EXCESS


def chance(ratio: float, worth: float) -> float:
    """The chance that one bin of noise reaches ``ratio`` times the estimated level (:func:`limit`'s
    inverse)."""
    return f_tail(ratio - PAD_EXCESS, worth)


def f_tail(x: float, worth: float) -> float:
    """The chance that F with 2 and ``2 worth`` degrees of freedom exceeds ``x``: ``(1 + x / w)^-w``."""
    w = max(worth, 1.0)
    return math.exp(-w * math.log1p(max(x, 0.0) / w))


def wanders(r: FloatArray, f: float, n: int, p: int, chance_: float, drift: bool = True) -> bool:
    """Whether the line at ``f`` fails to stand out, at ``chance_``, of its own scatter between segments of
    the record (:func:`.line_coherence.segment_f`): a narrow noise band, not a steady line. The segments see
    the whole line (fitted jointly with the periodic mean) and the fit's residual: the residual ``r`` about
    the mean alone holds the line less its own average over the periods, which near a harmonic is most of it
    and turns with the period index."""
    from .line_coherence import segment_f

    amp = _fit(r, f, n, p, drift)[0]
    whole = (amp * np.exp(2j * math.pi * f * np.arange(r.size, dtype=np.float64))).real
    ratio, dof = segment_f(r - _line(r, f, n, p, drift) + whole, f, n, p)
    return dof > 0 and f_tail(ratio, dof) > chance_


def _candidate(
    r: FloatArray, n: int, p: int, low: float = MIN_HARMONIC, alpha: float = LINE_ALPHA
) -> Optional[float]:
    """The strongest line of ``r`` that passes the search's tests at chance ``alpha`` (Bonferroni over the
    bins searched), in cycles per sample, or None; searched from ``low`` harmonics of the input up."""
    from scipy.optimize import minimize_scalar  # type: ignore[import-untyped]

    m = r.size
    per, freq, harm, far = _spectrum(r, n, p, low)
    if not far.any():
        return None
    size = PAD * m
    k = int(np.argmax(np.where(far, per, 0.0)))
    level, worth = _level(per, far, k, n)
    bins = max(2.0, float(np.count_nonzero(far)) / PAD)  # independent bins searched
    if not level > 0 or per[k] / level < limit(alpha / bins, worth):
        return None
    mirror = int(round((2 * harm[k] - freq[k]) * size))
    if 0 <= mirror < per.size and per[mirror] > MIRROR_SHARE * per[k]:
        return None
    step = 1.0 / size
    best = minimize_scalar(
        lambda f: -_fit(r, f, n, p)[1], bounds=(freq[k] - step, freq[k] + step), method="bounded"
    )
    f0 = float(best.x)
    mid = (n // 2) * p
    if n >= 4:  # the same amplitude in both halves: a stationary line, no decaying free oscillation
        a1 = _fit(r[:mid], f0, n // 2, p)[0] if n // 2 >= 2 else None
        off = np.exp(-2j * math.pi * f0 * mid)  # back to the first half's origin
        a2 = _fit(r[mid : n * p], f0, n - n // 2, p)[0]
        if a1 is not None and abs(a1 - a2 * off) > 0.5 * max(abs(a1), abs(a2)):
            return None
    if wanders(r, f0, n, p, alpha / bins):  # a narrow noise band: its phase wanders between segments
        return None
    return f0


#: The input is searched from this many harmonics up (the output from :data:`MIN_HARMONIC`): a tone in u
#: below the output's band still mixes with the input's harmonics into lines inside it.
INPUT_LOW = 0.25
#: ... and a line there counts above this share of the input's peak (a float32 record rounds at 6e-8).
INPUT_SHARE = 1e-5


def input_carries_a_line(rec: Any) -> bool:
    """Whether the recording's measured input holds a line of its own (the search's tests on its steady
    periods): then the output's lines are the plant's response to it (and, through the loop, its products
    with the input's harmonics), not a disturbance; nothing is taken out of that recording (review 33: a
    3 % tone at 1.7 Hz in u was removed from y as "mains hum", y then no longer the response to u).
    ``rec``: a Recording or one :class:`.line_stretch.Stretch` of a record."""
    from .line_stretch import Stretch, stretches

    st = rec if isinstance(rec, Stretch) else stretches(rec)[0]
    u, n, p = st.u, st.n, st.p
    if n < 3 or u.size != n * p:
        return False
    ru = _orth(u, n, p)
    f = _candidate(ru, n, p, INPUT_LOW)
    if f is None:
        return False
    # A material line, not the rounding of an exact sine (whose residual, 1e-16 of it, has structure too).
    return abs(_fit(ru, f, n, p)[0]) > INPUT_SHARE * float(np.max(np.abs(u)))


def _lines(st: Any, alpha: float = LINE_ALPHA) -> list[float]:
    """Lines found in one steady stretch (:class:`.line_stretch.Stretch`) at chance ``alpha`` for it, in
    cycles per sample (each its alias in [0, 1/2]); none where its input carries a line
    (:func:`input_carries_a_line`)."""
    y, p, n = st.y, st.p, st.n
    if n < MIN_PERIODS or not (st.dt > 0) or input_carries_a_line(st):
        return []
    r = _orth(y, n, p)
    found: list[float] = []
    for _ in range(MAX_LINES):
        f = _candidate(r, n, p, alpha=alpha)
        if f is None:  # a line nearly locked to a harmonic, which the search above skips
            f = near_candidate(y, n, p, alpha)
        if f is None:
            break
        found.append(f)
        r = r - _line(r, f, n, p)
        y = without(y, f, n, p)
    return found


def _line(r: FloatArray, f: float, n: int, p: int, drift: bool = True) -> FloatArray:
    """The least-squares line at ``f`` in ``r`` (its part the periodic mean cannot take)."""
    j = np.arange(r.size, dtype=np.float64)
    x = np.column_stack(
        [_orth(np.cos(2 * math.pi * f * j), n, p, drift), _orth(np.sin(2 * math.pi * f * j), n, p, drift)]
    )
    out: FloatArray = x @ np.linalg.lstsq(x, r, rcond=None)[0]
    return out


def _alias(hz: float, dt: float) -> float:
    a = (hz * dt) % 1.0
    return min(a, 1.0 - a)


#: Highest multiple of a recording's sampling rate tried as a line's frequency when resolving its alias.
MAX_FOLD = 64


def _hits(found: Sequence[tuple[float, float, int]], hz: float) -> list[int]:
    """Which lines ``found`` (as in :func:`_resolved`) are aliases of ``hz``, within a record bin."""
    return [i for i, (f, dt, m) in enumerate(found) if abs(_alias(hz, dt) - f) * m <= 1.0]


def _resolved(found: Sequence[tuple[float, float, int]]) -> list[tuple[float, bool]]:
    """Frequencies (cycles per unit of t) of the lines ``found`` as ``(cycles per sample, dt, samples)`` in
    single recordings, with whether the samples leave it ambiguous. Each is sampled at its recording's
    rate, so it is known only up to an alias; recordings sampled at other rates tell them apart. The
    frequency that explains most detections (the lowest among equals) is taken first, then the rest."""
    left = list(found)
    out: list[tuple[float, bool]] = []
    while left:
        cands = sorted(
            {abs(k + sgn * f) / dt for f, dt, _m in left for k in range(MAX_FOLD + 1) for sgn in (-1.0, 1.0)}
        )
        scored = [(len(_hits(left, hz)), hz) for hz in cands if hz > 0]
        top = max(c for c, _ in scored)
        best = [hz for c, hz in scored if c == top]
        out.append((best[0], len(_merged(best)) > 1))
        gone = set(_hits(left, best[0]))
        left = [d for i, d in enumerate(left) if i not in gone]
    return out


def _merged(freqs: Sequence[float]) -> list[float]:
    out: list[float] = []
    for f in sorted(freqs):
        if not out or abs(f - out[-1]) > 1e-3 * abs(f):
            out.append(f)
    return out


def removed(items: Any, alpha: float = LINE_ALPHA) -> tuple[Any, list[str]]:
    """``(items, notes)``: copies of the Recordings and Measurements in ``items`` with the lines found taken
    out of their outputs, and one note per line (what, where, how large); ``items`` as given when none is
    found. A Measurement is searched in each of its steady segments (:mod:`.line_stretch`) and the line
    taken out of that segment's samples. Averaged periods are passed on unchanged. ``alpha``: the search's
    false-alarm level for these items (:data:`LINE_ALPHA` for one diagnosis; a share of it when several
    sets are searched for one verdict, as diagnose_across's conditions)."""
    from ..model import Recording
    from .line_stretch import raw_amplitude, stretches

    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    parts = [(i, st) for i, it in enumerate(seq) for st in stretches(it)]
    each = alpha / max(1, len(parts))  # the search's chance per diagnosis, shared by the stretches
    found = [(f, st.dt, st.y.size) for _i, st in parts for f in _lines(st, each)]
    resolved = [(_refined(hz, [st for _i, st in parts]), vague) for hz, vague in _resolved(found)]
    freqs = [hz for hz, _ in resolved]
    if not freqs:
        return items, []
    out = list(seq)
    ys = {i: np.array(seq[i].y, dtype=np.float64) for i, _st in parts}
    where: dict[float, list[tuple[int, float]]] = {f: [] for f in freqs}
    odds = {f: 1.0 for f in freqs}  # the chance of the strongest fit under noise alone, searched everywhere
    level = alpha / max(1, len(freqs) * len(parts))
    for i, st in parts:
        p, n, dt = st.p, st.n, st.dt
        if n < 3 or not (dt > 0) or input_carries_a_line(st):
            continue
        r = _orth(st.y, n, p, drift=False)
        per, _freq, _h, far = _spectrum(r, n, p)
        searched = len(parts) * max(2.0, float(np.count_nonzero(far)) / PAD)
        t = np.asarray(seq[i].t, dtype=np.float64)[st.span[0] : st.span[1]]
        for hz in freqs:
            f, a = hz * dt, _alias(hz, dt)
            amp, _power, coh = _fit(r, f, n, p, drift=False)
            k = int(round(a * PAD * r.size))
            if coh > MAX_COHERENCE or a * p < MIN_HARMONIC or k >= per.size:
                continue
            lev, worth = _level(per, far, k, n)  # the line against the noise's own level at its frequency
            top = float(np.max(per[max(0, k - PAD) : k + PAD + 1]))
            if not lev > 0 or top / lev < limit(level, worth):
                continue
            if not isinstance(seq[i], Recording):  # a lab segment's grid is interpolated: its own samples
                amp = raw_amplitude(seq[i], st, hz)
            ys[i][st.span[0] : st.span[1]] -= (amp * np.exp(2j * math.pi * hz * (t - st.t0))).real
            r = r - _line(r, f, n, p, drift=False)
            per, _freq, _h, far = _spectrum(r, n, p)
            where[hz].append((i, abs(amp)))
            odds[hz] = min(odds[hz], searched * chance(top / lev, worth))
    for i in {i for hits in where.values() for i, _a in hits}:
        out[i] = _with_output(seq[i], ys[i])
    vague = dict(resolved)
    notes = [_note(hz, seq, hits, vague[hz], odds[hz]) for hz, hits in where.items() if hits]
    if not notes:
        return items, []
    return (out if isinstance(items, (list, tuple)) else out[0]), notes


def _with_output(item: Any, y: FloatArray) -> Any:
    """A copy of the Recording or Measurement ``item`` with the output ``y``."""
    from ..measurement import Measurement

    if not isinstance(item, Measurement):
        return replace(item, y=y)
    return item._replace(item.t, item.u, y)  # the Measurement's own copy (its checks, its fields)


def _refined(hz: float, parts: Sequence[Any]) -> float:
    """The frequency near ``hz`` (cycles per unit of t) at which a line explains most of the stretches'
    ``parts`` power together, within half a bin of the longest. One detection's own estimate (what
    :func:`_resolved` returns) put review 46's hum 0.002 Hz off: over a lab record's 28 s, 0.35 rad of phase,
    and a tenth of the hum was left in (its average then "unexplained structure" at p ~ 1e-14)."""
    from scipy.optimize import minimize_scalar

    use = [(st, _orth(st.y, st.n, st.p, drift=False)) for st in parts if st.n >= 3 and st.dt > 0]
    use = [(st, r) for st, r in use if _alias(hz, st.dt) * st.p >= MIN_HARMONIC]
    if not use:
        return hz
    half = 0.5 / max(st.y.size * st.dt for st, _r in use)

    def power(h: float) -> float:
        return -sum(_fit(r, h * st.dt, st.n, st.p, drift=False)[1] for st, r in use)

    best = minimize_scalar(
        power, bounds=(hz - half, hz + half), method="bounded", options={"xatol": half * 1e-4}
    )
    return float(best.x) if power(float(best.x)) <= power(hz) else hz


def _name(seq: Sequence[Any], i: int) -> str:
    meta = getattr(seq[i], "metadata", {})
    return str(meta.get("name", getattr(seq[i], "name", "") or f"recording {i}"))


def _note(hz: float, seq: Sequence[Any], hits: Sequence[tuple[int, float]], vague: bool, odds: float) -> str:
    names = ", ".join(f"{_name(seq, i)} (amplitude {a:.3g} [y])" for i, a in hits)
    names += (
        f" (p = {min(odds, 1.0):.2g} that noise alone, searched over every recording, shows so strong a line)"
    )
    alias = " or one of its aliases: these sampling rates cannot tell them apart" if vague else ""
    return (
        f"a disturbance not locked to the input (a steady sinusoid at {hz:.4g} cycles per unit of t{alias}, "
        f"e.g. mains hum at {hz:.3g} Hz with t in seconds) in {names}: fitted and taken out of the output "
        "before the "
        "periods were averaged (it is no harmonic of the input: averaging leaves part of it and the "
        "period-to-period noise floor does not hold it)"
    )


def clause(notes: Sequence[str]) -> str:
    """The verdict's clause for the lines taken out ('' without)."""
    if not notes:
        return ""
    return "; " + "; ".join(n.split(": fitted")[0] + " was taken out before the test" for n in notes)


# A line nearly locked to the input: a steady sinusoid within :data:`~.lines.GUARD_BINS` record bins of a
# harmonic of the input, which the search of :mod:`.lines` skips.
#
# Review 46: 50 Hz mains hum on a 2 rad/s drive is 157.08 cycles a period; over 6 steady periods it sits 0.48
# record bins from the 157th harmonic, inside the guard that keeps a drifting loop's sidebands out of the
# search, and the search's quadratic drift in the period index takes most of it too. The period average keeps
# 0.67 of it (a coherent wave in the averaged period) while the neighbouring-period differences see a quarter
# of its power: every such null read "unexplained structure remains spread over the cycle" (p ~ 1e-190).
#
# Here the residual about the periodic mean alone (no drift) is searched in the guarded bins. A line is kept
# when its least-squares fit (jointly with the periodic mean, frequency refined) stands out of the noise's
# level beyond chance (Bonferroni over the guarded bins and the far ones) and when the loop's own harmonic
# next to it (the periodic mean after the line is taken out) is smaller than the line: a drifting or
# settling loop makes sidebands only at harmonics it has, and at most as large as them; and when the line
# mirrored about its harmonic (fitted jointly) holds under :data:`~.lines.MIRROR_SHARE` of its power, and
# when its amplitude and phase agree in both halves of the record (AR(2) noise in a narrow band near
# harmonic 2 passed the rest in 7 of review 46's 8 H nulls).

#: Least distance of a searched near-harmonic line from its harmonic, in record bins (closer, its fit and
#: the periodic mean cannot be told apart: :data:`~.lines.MAX_COHERENCE`).
NEAR_LEAST_BINS = 0.2


def _loop_harmonic(y: FloatArray, f: float, amp: complex, n: int, p: int) -> float:
    """Amplitude of the periodic mean's harmonic nearest ``f`` once the line ``amp`` at ``f`` is taken out."""
    j = np.arange(y.size, dtype=np.float64)
    ybar = (y - (amp * np.exp(2j * math.pi * f * j)).real).reshape(n, p).mean(axis=0)
    k = int(round(f * p))
    return float(2.0 * abs(np.sum(ybar * np.exp(-2j * math.pi * k * np.arange(p) / p))) / p)


def without(y: FloatArray, f: float, n: int, p: int) -> FloatArray:
    """The steady record ``y`` less its line at ``f`` (fitted jointly with the periodic mean)."""
    amp = _fit(_orth(y, n, p, drift=False), f, n, p, drift=False)[0]
    j = np.arange(y.size, dtype=np.float64)
    out: FloatArray = y - (amp * np.exp(2j * math.pi * f * j)).real
    return out


def near_candidate(y: FloatArray, n: int, p: int, alpha: float) -> Optional[float]:
    """The strongest line of the steady record ``y`` (``n`` periods of ``p`` samples) in the bins the far
    search skips near the input's harmonics, in cycles per sample, or None (see the module docstring)."""
    from scipy.optimize import minimize_scalar

    m = y.size
    r = _orth(y, n, p, drift=False)
    per, freq, harm, far = _spectrum(r, n, p)
    off = np.abs(freq - harm) * m
    near = ~far & (freq * p >= MIN_HARMONIC) & (off >= NEAR_LEAST_BINS)
    if not near.any() or not far.any():
        return None
    k = int(np.argmax(np.where(near, per, 0.0)))
    level, worth = _level(per, far, k, n)
    if not level > 0:
        return None
    step = 1.0 / (PAD * m)
    best = minimize_scalar(
        lambda f: -_fit(r, f, n, p, drift=False)[1], bounds=(freq[k] - step, freq[k] + step), method="bounded"
    )
    f0 = float(best.x)
    amp, power, coh = _fit(r, f0, n, p, drift=False)
    if coh > MAX_COHERENCE or abs(f0 - round(f0 * p) / p) * m < NEAR_LEAST_BINS:
        return None
    bins = float(np.count_nonzero(near) + np.count_nonzero(far)) / PAD  # independent bins, both searches
    if 0.5 * power / level < limit(alpha / bins, worth):  # the fit's power is twice a periodogram bin's
        return None
    if _loop_harmonic(y, f0, amp, n, p) >= abs(amp):  # a sideband of the loop's own harmonic
        return None
    if _mirror_share(r, f0, n, p) > MIRROR_SHARE:  # two sidebands: a drifting loop or a narrow noise band
        return None
    if not _steady_halves(r, f0, n, p):  # a free oscillation decays, a narrow noise band wanders
        return None
    if wanders(r, f0, n, p, alpha / bins, drift=False):
        return None
    return f0


def _steady_halves(r: FloatArray, f: float, n: int, p: int) -> bool:
    """Whether the line at ``f`` has the same amplitude and phase in both halves of the record (within half
    its size, as the far search asks), each fitted jointly with its own periodic mean; True where a half is
    too short to fit it apart from that mean."""
    h = n // 2
    if h < 2:
        return True
    a1, _p1, c1 = _fit(_orth(r[: h * p], h, p, drift=False), f, h, p, drift=False)
    a2, _p2, c2 = _fit(_orth(r[h * p : n * p], n - h, p, drift=False), f, n - h, p, drift=False)
    if max(c1, c2) > MAX_COHERENCE:
        return True
    a2 = a2 * np.exp(-2j * math.pi * f * h * p)  # back to the first half's origin
    return bool(abs(a1 - a2) <= 0.5 * max(abs(a1), abs(a2)))


def _mirror_share(r: FloatArray, f: float, n: int, p: int) -> float:
    """Power of the line mirrored about its harmonic over the line's, the two fitted jointly with the
    periodic mean (a loop that drifts, or noise in a narrow band, has both; a line has one)."""
    j = np.arange(r.size, dtype=np.float64)
    fm = 2.0 * round(f * p) / p - f
    cols = [g(2 * math.pi * q * j) for q in (f, fm) for g in (np.cos, np.sin)]
    x = np.column_stack([_orth(c, n, p, drift=False) for c in cols])
    b = np.linalg.lstsq(x, r, rcond=None)[0]
    return float((b[2] ** 2 + b[3] ** 2) / max(b[0] ** 2 + b[1] ** 2, 1e-300))


__all__ = ["removed", "clause", "LINE_ALPHA", "GUARD_BINS", "MIRROR_SHARE"]

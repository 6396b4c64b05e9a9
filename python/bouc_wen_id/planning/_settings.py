"""The planner's input checked by name, and the candidate grid on the lab's sampling rate."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .._backend import Backend
from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..validation import count, nonnegative_number, positive_number, real_number
from ._result import TARGETS

FloatArray = NDArray[np.float64]

#: Fewest samples per period a candidate may have: the averaged period must resolve the loop's
#: harmonics (the identification's spectral derivative and phase search work on it).
MIN_SAMPLES_PER_PERIOD = 16
#: Largest candidate grid: the exchange phase weighs O(frequencies^2 x amplitudes) moves per iteration, so
#: a careless ``n_frequencies=10**6`` is refused at once instead of running for hours.
MAX_FREQUENCIES = 200
MAX_AMPLITUDES = 50
#: For ``"G"`` every grid point is an experiment, so the exchange phase weighs O(frequencies^2) moves
#: over designs of that many experiments: 200 took over 100 s (44 s with the vectorised score, and the
#: local search no longer beat the naive design), 100 take 7 s, 40 about 1 s.
MAX_FREQUENCIES_G = 40
#: Largest budget, s (about three years of test time): beyond it the periods and the information overflow
#: long before a design could be run (a budget of 1e300 s ran the search forever).
MAX_BUDGET = 1e8
#: Noise levels the planner computes with, in the output's units: the bound scales as noise_sd^2, whose
#: square must stay a float (1e-200 divided by zero, 1e300 overflowed); rescale the output's units outside.
NOISE_SD_RANGE = (1e-100, 1e100)
#: Largest lab sample rate, Hz (the CLI's ``--sample-rate`` cap too): beyond it the samples per period of the
#: lowest frequency overflow an integer (``sample_rate=1e308`` raised OverflowError).
MAX_SAMPLE_RATE = 1e12


@dataclass(frozen=True)
class _Settings:
    """The validated lab limits and search settings of one plan (:func:`plan_experiment`'s keywords)."""

    target: str
    lo: float
    hi: float
    max_amplitude: float
    noise_sd: float
    sample_rate: float
    max_rate: Optional[float]
    n_freq: int
    n_amp: int
    settle: int
    overhead: float
    p_cap: int
    min_n: int
    max_exp: int
    substeps: int
    backend: Backend

    @property
    def rate(self) -> float:
        """The rate limit, inf when there is none."""
        return math.inf if self.max_rate is None else self.max_rate

    @property
    def top(self) -> float:
        """The band's top, cut where the sampling rate no longer gives MIN_SAMPLES_PER_PERIOD per period."""
        return min(self.hi, 2.0 * math.pi * self.sample_rate / MIN_SAMPLES_PER_PERIOD)

    def to_dict(self, candidates: FloatArray) -> dict[str, Any]:
        return {
            "band": [self.lo, self.hi],
            "max_amplitude": self.max_amplitude,
            "max_rate": self.max_rate,
            "noise_sd": self.noise_sd,
            "sample_rate": self.sample_rate,
            "n_frequencies": self.n_freq,
            "n_amplitudes": self.n_amp,
            "settle_periods": self.settle,
            "overhead": self.overhead,
            "max_samples_per_period": self.p_cap,
            "min_periods": self.min_n,
            "max_experiments": self.max_exp,
            "substeps": self.substeps,
            "candidate_frequencies": candidates.tolist(),
        }


@dataclass(frozen=True)
class _Grid:
    """The candidates: frequencies on the lab's sampling rate, their samples per period and amplitudes."""

    omegas: FloatArray
    samples: NDArray[np.int64]
    amps: FloatArray
    lo: float  # the usable band: frequencies the budget can afford, sampled well enough
    top: float

    @property
    def period(self) -> FloatArray:
        out: FloatArray = 2.0 * np.pi / self.omegas
        return out


def _budget(budget: object) -> float:
    """The test-time budget, s: positive and at most :data:`MAX_BUDGET`."""
    out = positive_number("budget", budget)
    if out > MAX_BUDGET:
        raise InvalidParameterError(
            f"budget = {out:g} s is more than {MAX_BUDGET:g} s (about three years of test time): plan a "
            "part of it and repeat the design"
        )
    return out


def _check_prior(prior_plant: object, target: object) -> None:
    """The prior must be a plain Wiener-Bouc-Wen plant and the target one of :data:`TARGETS`."""
    if not isinstance(prior_plant, WienerPlant):
        raise InvalidParameterError(f"prior_plant must be a WienerPlant, got {type(prior_plant).__name__}")
    if prior_plant.terms:
        raise InvalidParameterError(
            "plan_experiment plans for the plain Wiener-Bouc-Wen model (its Cramer-Rao bound); pass the "
            "prior plant without terms"
        )
    if target not in TARGETS:
        raise InvalidParameterError(f"target = {target!r} must be one of {', '.join(TARGETS)}")


def _settings(
    target: str,
    band: tuple[float, float],
    max_amplitude: float,
    noise_sd: float,
    sample_rate: float,
    max_rate: Optional[float],
    n_frequencies: int,
    n_amplitudes: int,
    settle_periods: int,
    overhead: float,
    max_samples_per_period: int,
    min_periods: int,
    max_experiments: Optional[int],
    substeps: int,
    backend: Backend,
) -> _Settings:
    """Every keyword of :func:`plan_experiment` checked, by name."""
    if isinstance(band, (str, bytes)) or np.ndim(band) != 1 or len(band) != 2:
        raise InvalidParameterError(f"band must be two frequencies (low, high) in rad/s, got {band!r}")
    lo, hi = real_number("band low", band[0]), real_number("band high", band[1])
    if not 0 < lo < hi:
        raise InvalidParameterError(f"band = ({lo}, {hi}) must satisfy 0 < low < high (rad/s): it is empty")
    noise = positive_number("noise_sd", noise_sd)
    if not NOISE_SD_RANGE[0] <= noise <= NOISE_SD_RANGE[1]:
        raise InvalidParameterError(
            f"noise_sd = {noise:g} is outside {NOISE_SD_RANGE[0]:g}..{NOISE_SD_RANGE[1]:g}, where the bound "
            "(which scales as noise_sd^2) stays a float: express the output in other units"
        )
    n_freq = count("n_frequencies", n_frequencies, 2, MAX_FREQUENCIES_G if target == "G" else MAX_FREQUENCIES)
    n_amp = count("n_amplitudes", n_amplitudes, 1, MAX_AMPLITUDES)
    return _Settings(
        target=target,
        lo=lo,
        hi=hi,
        max_amplitude=positive_number("max_amplitude", max_amplitude),
        noise_sd=noise,
        sample_rate=_sample_rate(sample_rate),
        max_rate=None if max_rate is None else positive_number("max_rate", max_rate),
        n_freq=n_freq,
        n_amp=n_amp,
        settle=count("settle_periods", settle_periods, 0),
        overhead=nonnegative_number("overhead", overhead),
        p_cap=count("max_samples_per_period", max_samples_per_period, MIN_SAMPLES_PER_PERIOD),
        min_n=count("min_periods", min_periods, 2),
        max_exp=n_freq if max_experiments is None else count("max_experiments", max_experiments, 2),
        substeps=count("substeps", substeps, 1),
        backend=backend,
    )


def _grid(st: _Settings, budget: float) -> _Grid:
    """The candidate frequencies, log-spaced over the band's usable part and put on the lab's rate."""
    top = st.top
    if top < st.lo:
        raise InvalidParameterError(
            f"sample_rate = {st.sample_rate:g} Hz gives fewer than {MIN_SAMPLES_PER_PERIOD} samples per "
            f"period at every frequency of the band ({st.lo:g}, {st.hi:g}) rad/s"
        )
    lo = st.lo
    if st.target == "G":
        _check_g_budget(st, np.geomspace(lo, top, st.n_freq) if top > lo else np.array([lo]), budget)
    else:
        # A frequency whose settling and fewest periods alone exceed the budget is no candidate.
        lo = max(lo, 2.0 * math.pi * (st.settle + st.min_n) / max(budget - st.overhead, 1e-300))
        if lo > top:
            _too_small(st, budget, top)
    omegas = np.unique(np.geomspace(lo, top, st.n_freq)) if top > lo else np.array([lo])
    omegas, samples = _on_lab_rate(omegas, st.sample_rate, st.p_cap, lo, top)
    u_max = np.minimum(st.max_amplitude, st.rate / omegas)
    amps = u_max[:, None] * (np.arange(1, st.n_amp + 1) / st.n_amp)[None, :]
    cheapest = float(np.min(st.overhead + (st.settle + st.min_n) * 2.0 * np.pi / omegas))
    if budget < cheapest:
        _too_small(st, budget, float(omegas[-1]))
    return _Grid(omegas, samples, amps, lo, top)


def _too_small(st: _Settings, budget: float, omega: float) -> None:
    cheapest = st.overhead + (st.settle + st.min_n) * 2.0 * math.pi / omega
    raise InvalidParameterError(
        f"budget = {budget:g} s is too small for even one experiment: the cheapest takes "
        f"{cheapest:.4g} s ({st.overhead:g} s overhead + {st.settle} settling + {st.min_n} measured "
        f"periods at {omega:.4g} rad/s)"
    )


def _sample_rate(value: object) -> float:
    """The lab's sample rate, positive and at most :data:`MAX_SAMPLE_RATE`."""
    rate = positive_number("sample_rate", value)
    if rate > MAX_SAMPLE_RATE:
        raise InvalidParameterError(
            f"sample_rate = {rate:g} Hz is above {MAX_SAMPLE_RATE:g} Hz, beyond any data acquisition; give "
            "the lab's rate in Hz"
        )
    return rate


def _check_g_budget(st: _Settings, omegas: FloatArray, budget: float) -> None:
    """Target "G" tests every grid point: the budget must hold each at ``min_periods``."""
    need = float(np.sum(st.overhead + (st.settle + st.min_n) * 2.0 * np.pi / omegas))
    if budget < need:
        raise InvalidParameterError(
            f"budget = {budget:g} s is too small to test every one of the {len(omegas)} grid frequencies "
            f"of target 'G' ({need:.4g} s at {st.min_n} periods each); raise the budget or lower "
            "n_frequencies"
        )


def _on_lab_rate(
    omegas: FloatArray, sample_rate: float, p_cap: int, lo: float, top: float
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Frequencies moved so that a period holds a whole number P of samples at the lab's rate
    ``sample_rate / d`` (d = 1 unless P would exceed ``p_cap``), kept within ``[lo, top]``."""
    out_w: list[float] = []
    out_p: list[int] = []
    for w in omegas:
        full = 2.0 * math.pi * sample_rate / float(w)  # samples per period at the lab's rate
        d = max(1, math.ceil(full / p_cap * (1.0 - 1e-12)))
        p = max(MIN_SAMPLES_PER_PERIOD, min(p_cap, round(full / d)))
        for cand in (p, p - 1, p + 1):
            wc = 2.0 * math.pi * sample_rate / (d * cand)
            if MIN_SAMPLES_PER_PERIOD <= cand <= p_cap and lo * (1 - 1e-12) <= wc <= top * (1 + 1e-12):
                out_w.append(wc)
                out_p.append(cand)
                break
    if not out_w:
        raise InvalidParameterError(
            f"no frequency of the band ({lo:g}, {top:g}) rad/s holds a whole number of samples per period "
            f"at {sample_rate:g} Hz within {MIN_SAMPLES_PER_PERIOD}..{p_cap}; widen the band"
        )
    w_arr, idx = np.unique(np.array(out_w), return_index=True)
    return w_arr, np.array(out_p, dtype=np.int64)[idx]

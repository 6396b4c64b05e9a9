"""Value types: the linear part, the Bouc-Wen element, the plant, the sine plan and a recording.

All are frozen dataclasses that validate themselves on construction, so a bad value is refused where it
is written rather than deep inside a simulation.  Arrays handed in are copied and made read-only: nothing
the user passes is modified, and a recording cannot be changed behind the library's back.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import (
    FrequencyMismatchError,
    InsufficientDataError,
    InvalidParameterError,
    ZeroAmplitudeError,
)
from .terms import Asymmetry, Term, term_from_dict
from .validation import (
    EXACT_GRID_RTOL,
    check_bouc_wen,
    check_time_axis,
    check_transfer_function,
)
from .validation import frozen_array as _frozen_array
from .validation import real_number as _finite

__all__ = ["TransferFunction", "BoucWen", "WienerPlant", "SinePlan", "Recording"]

FloatArray = NDArray[np.float64]

#: Relative tolerance for "the period holds a whole number of samples".
GRID_RTOL = 1e-6


def _is_count(v: object) -> bool:
    """A whole number (int, numpy integer, or an integral finite float), not a bool."""
    if isinstance(v, bool):
        return False
    if isinstance(v, (int, np.integer)):
        return True
    return isinstance(v, (float, np.floating)) and math.isfinite(v) and float(v).is_integer()


def _refreeze(obj: object, state: Mapping[str, Any]) -> None:
    """``__setstate__`` of the frozen value types: unpickled arrays come back writeable, so freeze them."""
    for name, value in state.items():
        if isinstance(value, np.ndarray):
            value = np.array(value, dtype=value.dtype, copy=True)
            value.setflags(write=False)
        object.__setattr__(obj, name, value)


@dataclass(frozen=True, eq=False, init=False)
class TransferFunction:
    """``G(s) = exp(-delay s) num(s) / den(s)``: proper, asymptotically stable, with a pure delay.

    Parameters
    ----------
    num, den : array_like
        Polynomial coefficients, highest power of ``s`` first (the ``scipy.signal`` convention).
    delay : float
        Pure input delay in seconds, >= 0.  It makes G irrational, as the paper allows.
    """

    num: FloatArray
    den: FloatArray
    delay: float

    def __setstate__(self, state: Mapping[str, Any]) -> None:
        _refreeze(self, state)

    def __init__(self, num: ArrayLike, den: ArrayLike, delay: float = 0.0) -> None:
        object.__setattr__(self, "num", _frozen_array("num", num))
        object.__setattr__(self, "den", _frozen_array("den", den))
        object.__setattr__(self, "delay", _finite("delay", delay))
        # One validation path for both backends: proper, stable, finite, delay >= 0.
        check_transfer_function(self.num, self.den, self.delay)

    def __call__(self, s: ArrayLike) -> NDArray[np.complex128]:
        """Evaluate ``G(s)`` at complex ``s``."""
        ss = np.asarray(s, dtype=np.complex128)
        return np.polyval(self.num, ss) / np.polyval(self.den, ss) * np.exp(-self.delay * ss)

    def freqresp(self, omega: ArrayLike) -> NDArray[np.complex128]:
        """``G(j omega)`` at angular frequencies ``omega`` (rad/s)."""
        return self(1j * np.asarray(omega, dtype=np.float64))

    def gain_phase(self, omega: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``(|G(j omega)|, phi(omega))`` with the paper's convention ``phi = -angle G``, unwrapped."""
        g = self.freqresp(omega)
        return np.abs(g), -np.unwrap(np.angle(g))

    def scaled(self, k: float) -> TransferFunction:
        """``k G(s)``."""
        return TransferFunction(self.num * k, self.den, self.delay)

    def to_dict(self) -> dict[str, Any]:
        return {"num": self.num.tolist(), "den": self.den.tolist(), "delay": self.delay}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TransferFunction:
        return cls(d["num"], d["den"], d.get("delay", 0.0))

    def __repr__(self) -> str:
        return f"TransferFunction(num={self.num.tolist()}, den={self.den.tolist()}, delay={self.delay:g})"

    # python-control interop (bouc_wen_id.interop; needs the optional "control" extra).
    def to_control(self, pade_order: Optional[int] = None) -> Any:
        """This G as a ``control.TransferFunction``; a delay needs ``pade_order`` (see
        :func:`bouc_wen_id.interop.to_control`)."""
        from .interop import to_control

        return to_control(self, pade_order)

    @classmethod
    def from_control(cls, sys: Any, delay: float = 0.0) -> TransferFunction:
        """From a SISO continuous-time ``control`` tf or ss, with an optional delay (s).

        Raises InvalidParameterError (not SISO, discrete time, not a control system), and this class's
        own errors (UnstableSystemError, ImproperTransferFunctionError).
        """
        from .interop import tf_coefficients

        num, den = tf_coefficients(sys)
        return cls(num, den, delay)


@dataclass(frozen=True)
class BoucWen:
    """Bouc-Wen hysteresis (2a): ``wdot = alpha xdot - beta |xdot| |w|^(mu-1) w - gamma xdot |w|^mu``.

    Requires alpha > 0, beta + gamma > 0, beta >= gamma and mu >= 1 (the identification model needs
    mu > 1, checked by the search bracket).  ``w0`` is the initial state.
    """

    beta: float
    gamma: float
    mu: float
    alpha: float = 1.0
    w0: float = 0.0

    def __post_init__(self) -> None:
        for name in ("beta", "gamma", "mu", "alpha", "w0"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        check_bouc_wen(self.alpha, self.beta, self.gamma, self.mu, self.w0)

    @property
    def w_bound(self) -> float:
        """Upper bound ``(alpha / (beta + gamma))^(1/mu)`` of the steady |w| (Proposition 1)."""
        return float((self.alpha / (self.beta + self.gamma)) ** (1.0 / self.mu))

    def to_dict(self) -> dict[str, float]:
        return {"alpha": self.alpha, "beta": self.beta, "gamma": self.gamma, "mu": self.mu, "w0": self.w0}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> BoucWen:
        return cls(d["beta"], d["gamma"], d["mu"], d.get("alpha", 1.0), d.get("w0", 0.0))


@dataclass(frozen=True)
class WienerPlant:
    """The Wiener system ``x = g * u``, ``w = F[x]``, ``y = w + noise``, with optional physical terms.

    ``terms`` (design.md 9.1, :mod:`bouc_wen_id.terms`) make it the augmented model
    ``y = y0 + Lag[w + k u + c udot + m uddot + f tanh(udot/(eps Vmax))]`` with ``w`` the asymmetric
    Bouc-Wen output of the played ``xp = Play_b[x]``; each kind at most once, and an asymmetry needs
    ``beta + gamma > |delta|``.  Any sequence of terms is stored as a tuple, in the order given.

    ``units`` (``{"u": "mm", "y": "N"}``) are those the plant was fitted in (a fit sets them from its
    records; empty: not known): its parameters hold only in them, and ``validate`` converts or refuses
    records in others (:func:`bouc_wen_id.units.against_model`).  They do not take part in ``==``.
    """

    linear: TransferFunction
    hysteresis: BoucWen
    terms: tuple[Term, ...] = ()
    units: Mapping[str, str] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if isinstance(self.terms, Term):
            raise InvalidParameterError("terms must be a sequence of terms: wrap a single one as (term,)")
        if isinstance(self.terms, (str, bytes)) or not hasattr(self.terms, "__iter__"):
            # None, a number, a string (issue 19: a raw TypeError before): () is the plant without terms.
            raise InvalidParameterError(
                f"terms must be a sequence of bouc_wen_id.terms objects (() for none), got {self.terms!r}"
            )
        terms = tuple(self.terms)
        seen: set[str] = set()
        for t in terms:
            if not isinstance(t, Term):
                raise InvalidParameterError(
                    f"terms must be bouc_wen_id.terms objects, got {type(t).__name__}"
                )
            if t.kind in seen:
                raise InvalidParameterError(f"the term {t.kind!r} is given twice; each kind at most once")
            seen.add(t.kind)
            if isinstance(t, Asymmetry):
                bound = self.hysteresis.beta + self.hysteresis.gamma
                if not abs(t.delta) < bound:
                    raise InvalidParameterError(
                        f"asymmetry |delta| = {abs(t.delta)} must be < beta + gamma = {bound} "
                        "for a bounded output on both sides"
                    )
        object.__setattr__(self, "terms", terms)
        object.__setattr__(self, "units", _plant_units(self.units))

    def term(self, kind: str) -> Optional[Term]:
        """The plant's term of code name ``kind`` (e.g. ``"play"``), or None."""
        return next((t for t in self.terms if t.kind == kind), None)

    def normalized(self) -> WienerPlant:
        """The equivalent plant with alpha = 1: ``G -> alpha G, beta -> beta/alpha, gamma -> gamma/alpha``.

        Terms follow: ``delta -> delta/alpha``, ``b -> alpha b`` (play is in units of x), ``delta_nu ->
        delta_nu/alpha`` (the dissipated energy is in units of x); the output
        terms are unchanged.
        """
        h = self.hysteresis
        return WienerPlant(
            self.linear.scaled(h.alpha),
            BoucWen(h.beta / h.alpha, h.gamma / h.alpha, h.mu, 1.0, h.w0),
            tuple(t.normalized(h.alpha) for t in self.terms),
            self.units,
        )

    def with_units(self, units: Mapping[str, str]) -> WienerPlant:
        """The same plant, stating that it holds in ``units`` (``{"u": "mm", "y": "N"}``)."""
        return WienerPlant(self.linear, self.hysteresis, self.terms, units)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"linear": self.linear.to_dict(), "hysteresis": self.hysteresis.to_dict()}
        if self.terms:  # a plain plant's dict stays as it was
            out["terms"] = [t.to_dict() for t in self.terms]
        if self.units:
            out["units"] = dict(self.units)
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> WienerPlant:
        terms = tuple(term_from_dict(t) for t in d.get("terms", ()))
        lin, hys = TransferFunction.from_dict(d["linear"]), BoucWen.from_dict(d["hysteresis"])
        return cls(lin, hys, terms, d.get("units") or {})


def _plant_units(units: Any) -> dict[str, str]:
    """A plant's units checked: a mapping of ``"u"``/``"y"`` to unit strings (``"t"`` only as ``"s"``)."""
    if not isinstance(units, Mapping):
        raise InvalidParameterError(f"units must be a mapping like {{'u': 'mm', 'y': 'N'}}, got {units!r}")
    out = {}
    for k, v in units.items():
        if k not in ("t", "u", "y") or not isinstance(v, str):
            raise InvalidParameterError(f"units must map 'u' and 'y' to unit strings; got {k!r}: {v!r}")
        if k == "t" and v.strip() != "s":
            raise InvalidParameterError(f"a plant's time is in seconds; units['t'] = {v!r}")
        if k != "t" and v.strip():
            out[k] = v.strip()
    return out


@dataclass(frozen=True, eq=False, init=False)
class SinePlan:
    """A set of sine experiments ``u = U_i cos(omega_i t)``, one per frequency.

    Parameters
    ----------
    frequencies : array_like
        Angular frequencies omega_i (rad/s), > 0.  The first one is the reference experiment of the
        separable least-squares fit (Section 3.2 of the paper).
    amplitudes : float or array_like
        Input amplitudes U_i, non-zero; a scalar applies to every experiment.
    settle_periods : int
        Periods simulated and then discarded so that the response is in steady state.
    periods : int
        Periods N averaged by (4a-b).
    samples_per_period : int
        Samples P per period: the grid step is ``2 pi / (omega P)``.
    substeps : int
        RK4 steps per sample.
    noise_sd : float
        Standard deviation of the white Gaussian measurement noise added to w.
    seed : int or None
        Seed of the noise generator; each experiment draws from its own child stream.
    """

    frequencies: FloatArray
    amplitudes: FloatArray
    settle_periods: int
    periods: int
    samples_per_period: int
    substeps: int
    noise_sd: float
    seed: Optional[int]

    def __setstate__(self, state: Mapping[str, Any]) -> None:
        _refreeze(self, state)

    def __init__(
        self,
        frequencies: ArrayLike,
        amplitudes: ArrayLike = 1.0,
        settle_periods: int = 20,
        periods: int = 50,
        samples_per_period: int = 256,
        substeps: int = 4,
        noise_sd: float = 0.0,
        seed: Optional[int] = 0,
    ) -> None:
        object.__setattr__(self, "settle_periods", settle_periods)
        object.__setattr__(self, "periods", periods)
        object.__setattr__(self, "samples_per_period", samples_per_period)
        object.__setattr__(self, "substeps", substeps)
        object.__setattr__(self, "noise_sd", noise_sd)
        object.__setattr__(self, "seed", seed)
        freqs = _frozen_array("frequencies", frequencies, at_least_1d=True)
        if freqs.size == 0:
            raise InvalidParameterError("the plan needs at least one frequency")
        if np.any(freqs <= 0):
            raise InvalidParameterError(f"frequencies must be > 0 rad/s, got {freqs.tolist()}")
        amps_raw = _frozen_array("amplitudes", amplitudes, at_least_1d=True)
        if amps_raw.size not in (1, freqs.size):
            raise InvalidParameterError(
                f"amplitudes: {amps_raw.size} values for {freqs.size} frequencies; give one amplitude per "
                "frequency, or a single one for all"
            )
        amps = _frozen_array("amplitudes", np.broadcast_to(amps_raw, freqs.shape))
        if np.any(amps == 0):
            raise ZeroAmplitudeError("every experiment needs a non-zero amplitude U")
        object.__setattr__(self, "frequencies", freqs)
        object.__setattr__(self, "amplitudes", amps)
        for name, low in (("settle_periods", 0), ("periods", 1), ("samples_per_period", 8), ("substeps", 1)):
            v = getattr(self, name)
            if not _is_count(v) or v < low:
                raise InvalidParameterError(f"{name} = {v} must be an integer >= {low}")
            object.__setattr__(self, name, int(v))
        noise = _finite("noise_sd", self.noise_sd)
        if noise < 0:
            raise InvalidParameterError(f"noise_sd = {noise} must be >= 0")
        object.__setattr__(self, "noise_sd", noise)
        if seed is not None:
            # numpy's SeedSequence takes only non-negative integers; say so here, not at simulate time.
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
                raise InvalidParameterError(f"seed = {seed!r} must be a non-negative integer or None")
            object.__setattr__(self, "seed", int(seed))

    def __len__(self) -> int:
        return int(self.frequencies.size)

    def to_dict(self) -> dict[str, Any]:
        return {
            "frequencies": self.frequencies.tolist(),
            "amplitudes": self.amplitudes.tolist(),
            "settle_periods": self.settle_periods,
            "periods": self.periods,
            "samples_per_period": self.samples_per_period,
            "substeps": self.substeps,
            "noise_sd": self.noise_sd,
            "seed": self.seed,
        }

    def __repr__(self) -> str:
        return (
            f"SinePlan(frequencies={self.frequencies.tolist()}, amplitudes={self.amplitudes.tolist()}, "
            f"settle_periods={self.settle_periods}, periods={self.periods}, "
            f"samples_per_period={self.samples_per_period}, substeps={self.substeps}, "
            f"noise_sd={self.noise_sd:g}, seed={self.seed})"
        )


@dataclass(frozen=True, eq=False, init=False)
class Recording:
    """One sine experiment as measured: time, input and output samples, and the known U and omega.

    Parameters
    ----------
    t, u, y : array_like
        Uniformly sampled time (s), input and output, equal lengths.  Copied and frozen.
    amplitude : float
        The known input amplitude U (u = U cos(omega t)).
    frequency : float
        The known angular frequency omega (rad/s).  ``2 pi / (omega dt)`` must be a whole number of
        samples per period for the paper's averaging (4a-b).
    settle_periods : int
        Leading periods to discard as transient (the identification may override it).
    x, w : array_like, optional
        The inner signals, when known (simulated data only).
    plant : WienerPlant, optional
        The true plant, when known: the identification result then compares itself with it.
    metadata : mapping, optional
        Free-form strings: units, channel names, provenance.
    """

    t: FloatArray
    u: FloatArray
    y: FloatArray
    amplitude: float
    frequency: float
    settle_periods: int
    x: Optional[FloatArray]
    w: Optional[FloatArray]
    plant: Optional[WienerPlant]
    metadata: Mapping[str, str]

    def __setstate__(self, state: Mapping[str, Any]) -> None:
        _refreeze(self, state)

    def __init__(
        self,
        t: ArrayLike,
        u: ArrayLike,
        y: ArrayLike,
        amplitude: float,
        frequency: float,
        settle_periods: int = 0,
        x: Optional[ArrayLike] = None,
        w: Optional[ArrayLike] = None,
        plant: Optional[WienerPlant] = None,
        metadata: Optional[Mapping[str, str]] = None,
    ) -> None:
        for name, v in (("t", t), ("u", u), ("y", y)):
            object.__setattr__(self, name, _frozen_array(name, v))
        for name, inner in (("x", x), ("w", w)):
            object.__setattr__(self, name, None if inner is None else _frozen_array(name, inner))
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "frequency", frequency)
        object.__setattr__(self, "settle_periods", settle_periods)
        if plant is not None and not isinstance(plant, WienerPlant):
            raise InvalidParameterError(f"plant must be a WienerPlant or None, got {type(plant).__name__}")
        object.__setattr__(self, "plant", plant)
        if metadata is not None and not isinstance(metadata, Mapping):
            raise InvalidParameterError(
                f"metadata must be a mapping of strings, got {type(metadata).__name__}"
            )
        object.__setattr__(self, "metadata", dict(metadata or {}))
        lengths = {
            n: getattr(self, n).size for n in ("t", "u", "y", "x", "w") if getattr(self, n) is not None
        }
        if len(set(lengths.values())) != 1:
            raise InvalidParameterError(f"t, u, y (and x, w) must have equal lengths, got {lengths}")
        if self.t.size < 8:
            raise InsufficientDataError(f"a recording needs at least 8 samples, got {self.t.size}")
        amp = _finite("amplitude", self.amplitude)
        if amp == 0.0:
            raise ZeroAmplitudeError("the recording's input amplitude U is 0: nothing can be identified")
        omega = _finite("frequency", self.frequency)
        if omega <= 0.0:
            raise InvalidParameterError(f"frequency = {omega} rad/s must be > 0")
        object.__setattr__(self, "amplitude", amp)
        object.__setattr__(self, "frequency", omega)
        settle = _finite("settle_periods", self.settle_periods)
        if int(settle) != settle or settle < 0:
            raise InvalidParameterError(f"settle_periods = {self.settle_periods} must be an integer >= 0")
        object.__setattr__(self, "settle_periods", int(settle))
        check_time_axis(self.t, rtol=EXACT_GRID_RTOL)

    @property
    def dt(self) -> float:
        """Sampling step (s)."""
        return float((self.t[-1] - self.t[0]) / (self.t.size - 1))

    @property
    def period(self) -> float:
        """Excitation period ``2 pi / omega`` (s)."""
        return 2.0 * math.pi / self.frequency

    @property
    def samples_per_period(self) -> int:
        """Whole number of samples per period; raises :class:`FrequencyMismatchError` otherwise."""
        p = self.period / self.dt
        pr = round(p)
        if pr < 1 or abs(p - pr) > GRID_RTOL * p:
            from ._timehint import hint

            name = self.metadata.get("name")
            raise hint(
                FrequencyMismatchError(
                    f"{f'{name}: ' if name else ''}omega = {self.frequency:.9g} rad/s gives {p:.6f} samples "
                    f"per period at dt = {self.dt:.9g} s; the paper's averaging (4a-b) needs a whole number. "
                    "Check the frequency (rad/s, not Hz?) or the time column; if both are right and the "
                    "sampling rate is simply not a multiple of the frequency, give the record as a "
                    "Measurement (bw.Measurement(t, u, y), or a file without the amplitude and frequency "
                    "header keys): the lab path estimates the frequency itself and needs no whole number of "
                    "samples per period"
                ),
                self.t,
                self.u,
                self.frequency,
            )
        return int(pr)

    @property
    def whole_periods(self) -> int:
        """Number of whole periods in the recording."""
        return self.t.size // self.samples_per_period

    def __repr__(self) -> str:
        return (
            f"Recording(n={self.t.size}, U={self.amplitude:g}, omega={self.frequency:g} rad/s, "
            f"dt={self.dt:.4g} s, settle_periods={self.settle_periods})"
        )


def as_recordings(recordings: Recording | Sequence[Recording]) -> list[Recording]:
    """Accept one recording or a sequence of them."""
    if isinstance(recordings, Recording):
        return [recordings]
    out = list(recordings)
    if not out:
        raise InsufficientDataError("no recordings were given")
    for r in out:
        if not isinstance(r, Recording):
            raise InvalidParameterError(f"expected Recording objects, got {type(r).__name__}")
    return out

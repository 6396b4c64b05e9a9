"""NumPy reference of ``rust/augmented.rs``: the augmented model (``docs/design.md`` 9.1 and 9.3).

Written line by line from the design text, readable and unoptimised, to hold the Rust core
(``_core.augmented_output`` and ``_core.augmented_refine``, ``rust/augmented.rs``) to account: same
signatures, same named errors. The output terms act on the measured input ``u_j = U cos(2 pi j/P + psi)``,
the sensor lag is applied on the DFT of the period, and the hysteresis is the plain steady loop of
:mod:`.steady` (7.2) unless asymmetry or play is active, then the loop along the input path (9.2). The
Levenberg-Marquardt follows :func:`.refine.refine` (same damping schedule, stopping rules and projections)
with a shared block of size ``3 + T``; like it, it solves the full damped normal equations instead of their
Schur complement (the same step up to rounding).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError, ZeroAmplitudeError
from ..validation import finite_array as _finite_array
from ..validation import finite_scalar as _finite_scalar
from .dahl import dahl_loop
from .path_loop import path_loop, path_loop_distorted
from .refine import (
    Constraint,
    admissible_bouc_wen,
    bouc_wen_constraints,
    levenberg_marquardt,
    project_bouc_wen,
)
from .series_loop import series_loop
from .steady import steady_loop
from .terms import (
    ASYMMETRY,
    COULOMB,
    COULOMB_SMOOTHING,
    COULOMB_SMOOTHING_MAX,
    DAHL,
    DAHL_SIGMA,
    DISTORTION,
    INERTIA,
    OFFSET,
    ON_X_TERMS,
    PINCHING,
    PINCHING_MAX,
    PLACE_X,
    PLAY,
    SENSOR_LAG,
    SERIES_DASHPOT,
    STEADY_TERM_NAMES,
    STIFFNESS,
    VISCOUS,
    split_place,
)

__all__ = [
    "TERM_NAMES",
    "COULOMB_SMOOTHING",
    "PLAY_MAX_FRACTION",
    "parse_terms",
    "lag_filter",
    "augmented_output",
    "augmented_refine",
]

FloatArray = NDArray[np.float64]

TERM_NAMES = STEADY_TERM_NAMES
#: Largest play as a fraction of the smallest |A_i| during a refinement.
PLAY_MAX_FRACTION = 0.95


def parse_terms(terms: Sequence[str]) -> tuple[str, ...]:
    """The term names as a tuple; an unknown or repeated name is :class:`InvalidParameterError`."""
    if isinstance(terms, str):
        raise InvalidParameterError(f"terms must be a sequence of names, not the string {terms!r}")
    out: list[str] = []
    for name in terms:
        base, tag = split_place(name)
        if base not in TERM_NAMES:
            raise InvalidParameterError(f"unknown term {name!r}; the terms are {', '.join(TERM_NAMES)}")
        if tag and tag != PLACE_X:
            raise InvalidParameterError(f"unknown place {tag!r} in term {name!r}; the places are {PLACE_X}")
        if tag and base not in ON_X_TERMS:
            raise InvalidParameterError(
                f"term {base!r} cannot act at place {tag!r}: only the mechanical terms do"
            )
        if name in out:
            raise InvalidParameterError(
                f"term {name!r} is given twice; each term has one parameter and may appear once"
            )
        out.append(name)
    _check_pairs(tuple(out))
    return tuple(out)


def _placed(name: str, tag: str) -> str:
    return f"{name}@{tag}" if tag else name


def _check_pairs(names: tuple[str, ...]) -> None:
    """Dahl friction's level and pre-sliding stiffness come together, at the same place."""
    pair = {DAHL: DAHL_SIGMA, DAHL_SIGMA: DAHL}
    for name in names:
        base, tag = split_place(name)
        if base in pair and _placed(pair[base], tag) not in names:
            raise InvalidParameterError(
                f"term {name!r} needs {_placed(pair[base], tag)!r}: Dahl friction's level and pre-sliding "
                "stiffness are given together"
            )


#: Dahl friction's parameters at each place, in the order of the core's constraints.
_DAHL_NAMES = (DAHL, DAHL_SIGMA, _placed(DAHL, PLACE_X), _placed(DAHL_SIGMA, PLACE_X))


def check_smoothing(eps: float) -> float:
    """The Coulomb smoothing ``eps`` checked as the core checks it: finite, in ``(0, 0.5]``."""
    eps = _finite_scalar("coulomb_smoothing", eps)
    if not 0.0 < eps <= COULOMB_SMOOTHING_MAX:
        raise InvalidParameterError(f"coulomb_smoothing eps = {eps} must be in (0, {COULOMB_SMOOTHING_MAX}]")
    return eps


def _value(terms: tuple[str, ...], shared: FloatArray, name: str) -> float:
    return float(shared[3 + terms.index(name)]) if name in terms else 0.0


def _on_x_regressors(
    a: float, omega: float, z: FloatArray, eps: float = COULOMB_SMOOTHING
) -> dict[str, tuple[FloatArray, ...]]:
    """Each mechanical term on ``x = a cos z`` (``z = theta_j - phi``): its regressor and d/da, d/dphi.

    Written from the formulas: ``x``, ``xdot = -a omega sin z``, ``xddot = -a omega^2 cos z`` and
    ``tanh(xdot / (eps |a| omega))``.
    """
    s, c = np.sin(z), np.cos(z)
    x, xdot, xddot = a * c, -a * omega * s, -a * omega**2 * c
    arg = xdot / (eps * abs(a) * omega)
    fric = np.tanh(arg)
    # d arg/dphi: d(-a omega sin(theta - phi))/dphi = a omega cos z.
    dfric_dphi = (1.0 - fric**2) * (a * omega * c) / (eps * abs(a) * omega)
    return {
        STIFFNESS: (x, c, a * s),
        VISCOUS: (xdot, -omega * s, a * omega * c),
        INERTIA: (xddot, -(omega**2) * c, -a * omega**2 * s),
        COULOMB: (fric, np.zeros_like(z), dfric_dphi),
    }


def _check_shared(terms: tuple[str, ...], shared: FloatArray) -> None:
    if shared.size != 3 + len(terms):
        raise InvalidParameterError(
            f"the shared parameters hold {shared.size} values but [beta, gamma, mu] and {len(terms)} terms "
            f"need {3 + len(terms)}"
        )
    _finite_array("shared parameters", shared)
    tau = _value(terms, shared, SENSOR_LAG)
    if tau < 0.0:
        raise InvalidParameterError(f"sensor_lag tau = {tau} s must be >= 0")
    b = _value(terms, shared, PLAY)
    if b < 0.0:
        raise InvalidParameterError(f"play b = {b} must be >= 0 (the half-width of the backlash)")
    zeta1 = _value(terms, shared, PINCHING)
    if not 0.0 <= zeta1 < 1.0:
        raise InvalidParameterError(f"pinching zeta1 = {zeta1} must be in [0, 1)")
    rho = _value(terms, shared, SERIES_DASHPOT)
    if rho < 0.0:
        raise InvalidParameterError(f"series_dashpot rho = {rho} must be >= 0")
    for name in _DAHL_NAMES:
        if _value(terms, shared, name) < 0.0:
            raise InvalidParameterError(f"{name} = {_value(terms, shared, name)} must be >= 0")
    delta = _value(terms, shared, ASYMMETRY)
    if ASYMMETRY in terms and abs(delta) >= shared[0] + shared[1]:
        raise InvalidParameterError(
            f"asymmetry |delta| = {abs(delta)} must be below beta + gamma = {shared[0] + shared[1]}"
        )


def _check_excitation(amplitude: float, frequency: float, grid_phase: float) -> None:
    _finite_scalar("amplitude", amplitude)
    _finite_scalar("frequency", frequency)
    _finite_scalar("grid_phase", grid_phase)
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the input amplitude U is 0: nothing excites the plant")
    if frequency <= 0.0:
        raise InvalidParameterError(f"frequency = {frequency} rad/s must be > 0")


def lag_filter(p: int, omega: float, tau: float) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
    """The first-order lag on the bins of a P-point DFT and its tau-derivative.

    ``H_k = 1/(1 + i k omega tau)`` with ``k = n`` below P/2 and ``n - P`` above; the Nyquist bin of an even
    P takes the real ``Re H``.  ``dH_k/dtau = -i k omega H_k^2``.
    """
    n = np.arange(p)
    k = np.where(2 * n < p, n, n - p).astype(np.float64)
    iw = 1j * k * omega
    h: NDArray[np.complex128] = np.asarray(1.0 / (1.0 + iw * tau), dtype=np.complex128)
    dh: NDArray[np.complex128] = np.asarray(-iw * h * h, dtype=np.complex128)
    if p % 2 == 0:
        a = (p // 2) * omega
        d = 1.0 + a * a * tau * tau
        h[p // 2] = 1.0 / d
        dh[p // 2] = -2.0 * a * a * tau / (d * d)
    return h, dh


def _apply(filt: NDArray[np.complex128], cols: FloatArray) -> FloatArray:
    """The filter applied to every column of ``cols`` (P, n) on the DFT of the period."""
    return np.real(np.fft.ifft(np.fft.fft(cols, axis=0) * filt[:, None], axis=0))


def _hysteresis(
    terms: tuple[str, ...],
    shared: FloatArray,
    amplitude: float,
    phi: float,
    p: int,
    substeps: int,
    waveform: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """``w`` and its columns ``d/d(beta, gamma, mu, A, phi, delta, b, lambda, zeta1)`` (0 where inactive)."""
    beta, gamma, mu = (float(v) for v in shared[:3])
    if PINCHING in terms:
        # Pinching: Foliente's factor on the path loop's h(w, s), with its d/dzeta1 column.
        delta, b = _value(terms, shared, ASYMMETRY), _value(terms, shared, PLAY)
        zeta1 = _value(terms, shared, PINCHING)
        if DISTORTION in terms:
            lam = _value(terms, shared, DISTORTION)
            w, jac, _ = path_loop_distorted(
                amplitude, beta, gamma, mu, delta, b, phi, lam, waveform, p, substeps, pinch=zeta1
            )
        else:
            w, jac, _ = path_loop(amplitude, beta, gamma, mu, delta, b, phi, p, substeps, pinch=zeta1)
        return w, jac
    if DISTORTION in terms:
        delta, b = _value(terms, shared, ASYMMETRY), _value(terms, shared, PLAY)
        lam = _value(terms, shared, DISTORTION)
        w, jac8, _ = path_loop_distorted(
            amplitude, beta, gamma, mu, delta, b, phi, lam, waveform, p, substeps
        )
        return w, np.column_stack([jac8, np.zeros(p)])
    if ASYMMETRY in terms or PLAY in terms:
        delta, b = _value(terms, shared, ASYMMETRY), _value(terms, shared, PLAY)
        w, jac7, _ = path_loop(amplitude, beta, gamma, mu, delta, b, phi, p, substeps)
        return w, np.column_stack([jac7, np.zeros((p, 2))])
    w, jac5, _, _ = steady_loop(amplitude, beta, gamma, mu, phi, p, substeps)
    jac = np.zeros((p, 9))
    jac[:, :5] = jac5
    return w, jac


def _series_hysteresis(
    terms: tuple[str, ...],
    shared: FloatArray,
    amplitude: float,
    phi: float,
    omega: float,
    p: int,
    substeps: int,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The loop behind the series dashpot (:mod:`.series_loop`): ``w``, its columns as :func:`_hysteresis`'s
    (``d/d(beta, gamma, mu, A, phi, delta)``, the rest 0) and ``d w / d rho``; asymmetry only rides along."""
    for other in (PLAY, PINCHING, DISTORTION):
        if other in terms:
            raise InvalidParameterError(
                f"term {SERIES_DASHPOT!r} with {other!r}: the series dashpot's steady loop carries the "
                "asymmetry only"
            )
    beta, gamma, mu = (float(v) for v in shared[:3])
    delta, rho = _value(terms, shared, ASYMMETRY), _value(terms, shared, SERIES_DASHPOT)
    w, jac7, _ = series_loop(amplitude, beta, gamma, mu, delta, phi, rho / omega, p, substeps)
    jac = np.zeros((p, 9))
    jac[:, :6] = jac7[:, :6]
    return w, jac, jac7[:, 6] / omega


def measured_input(
    shape: Optional[ArrayLike], theta: FloatArray, amplitude: float, frequency: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(u, udot, uddot)`` on the grid as the terms on u see the measured input: ``shape = [dc, Re c_2, Im
    c_2, ...]`` (its mean relative to U, in u only: a spring sees it, a dashpot and a mass do not; then its
    harmonics as ``waveform``'s); None or empty: the pure sine (rust/augmented.rs ``MeasuredInput``)."""
    a = np.zeros(1) if shape is None else np.asarray(shape, dtype=np.float64).ravel()
    if a.size == 0:
        a = np.zeros(1)
    if a.size % 2 == 0 or not np.all(np.isfinite(a)):
        raise InvalidParameterError(
            "input_shape must hold the input's finite mean relative to U, then (re, im) pairs of its "
            f"harmonics 2, 3, ... (an odd length); got {a.size} values"
        )
    u, ud, udd = np.cos(theta) + a[0], -np.sin(theta), -np.cos(theta)
    for i, (re, im) in enumerate(a[1:].reshape(-1, 2)):
        k = i + 2.0
        ck, sk = np.cos(k * theta), np.sin(k * theta)
        u = u + re * ck - im * sk
        ud = ud - k * (re * sk + im * ck)
        udd = udd - k * k * (re * ck - im * sk)
    return amplitude * u, amplitude * frequency * ud, amplitude * frequency**2 * udd


def augmented_output(
    ybar_len: int,
    amplitude: float,
    frequency: float,
    grid_phase: float,
    terms: Sequence[str],
    shared: ArrayLike,
    gain: float,
    phase: float,
    substeps: int,
    waveform: Optional[ArrayLike] = None,
    input_shape: Optional[ArrayLike] = None,
    coulomb_smoothing: float = COULOMB_SMOOTHING,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The augmented model's output of one experiment (design.md 9.1) and its Jacobian.

    ``waveform``: the measured input's harmonics ``[Re c_2, Im c_2, ...]`` for the ``distortion`` term
    (design.md 9.5); None or empty for a pure sine. ``coulomb_smoothing``: the dry friction's ``eps``,
    ``f tanh(v / (eps Vmax))`` at either place.

    Returns ``(y (P,), jac_shared (P, 3 + T), jac_own (P, 2))``: shared columns
    ``[beta, gamma, mu, q_1 .. q_T]`` in the order of ``terms``, own columns ``[g, phi]``.
    """
    names = parse_terms(terms)
    sh = np.asarray(shared, dtype=np.float64).ravel()
    if ybar_len < 0:
        raise InvalidParameterError(f"ybar_len = {ybar_len} must be >= 0")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    _check_excitation(amplitude, frequency, grid_phase)
    _check_shared(names, sh)
    _finite_scalar("gain", gain)
    _finite_scalar("phase", phase)
    eps = check_smoothing(coulomb_smoothing)
    p = int(ybar_len)
    wave = np.zeros(0) if waveform is None else np.asarray(waveform, dtype=np.float64).ravel()
    if SERIES_DASHPOT in names:
        w, hj, d_rho = _series_hysteresis(names, sh, amplitude * gain, phase, frequency, p, substeps)
    else:
        w, hj = _hysteresis(names, sh, amplitude * gain, phase, p, substeps, wave)
    theta = 2.0 * np.pi * np.arange(p) / p + grid_phase
    u, udot, uddot = measured_input(input_shape, theta, amplitude, frequency)
    fric = np.tanh(udot / (eps * abs(amplitude) * frequency))
    inputs = {STIFFNESS: u, VISCOUS: udot, INERTIA: uddot, COULOMB: fric}
    ns = 3 + len(names)
    f = w.copy()
    jac_shared = np.zeros((p, ns))
    jac_shared[:, :3] = hj[:, :3]
    jac_own = np.column_stack([amplitude * hj[:, 3], hj[:, 4]])
    on_x = _on_x_regressors(amplitude * gain, frequency, 2.0 * np.pi * np.arange(p) / p - phase, eps)
    dahl = {
        tag: dahl_loop(
            a, psi0, _value(names, sh, _placed(DAHL, tag)), _value(names, sh, _placed(DAHL_SIGMA, tag)), p
        )
        for tag, a, psi0 in (("", amplitude, grid_phase), (PLACE_X, amplitude * gain, -phase))
        if _placed(DAHL, tag) in names
    }
    for t, name in enumerate(names):
        base, tag = split_place(name)
        if base == DAHL:
            fd, d_fc, _, d_a, d_psi = dahl[tag]
            f = f + fd
            jac_shared[:, 3 + t] = d_fc
            if tag == PLACE_X:
                jac_own = jac_own + np.column_stack([amplitude * d_a, -d_psi])
        elif base == DAHL_SIGMA:
            jac_shared[:, 3 + t] = dahl[tag][2]
        elif tag == PLACE_X:
            v, dv_da, dv_dphi = on_x[base]
            f = f + sh[3 + t] * v
            jac_shared[:, 3 + t] = v
            jac_own = jac_own + sh[3 + t] * np.column_stack([amplitude * dv_da, dv_dphi])
        elif name in inputs:
            f = f + sh[3 + t] * inputs[name]
            jac_shared[:, 3 + t] = inputs[name]
        elif name == ASYMMETRY:
            jac_shared[:, 3 + t] = hj[:, 5]
        elif name == PLAY:
            jac_shared[:, 3 + t] = hj[:, 6]
        elif name == DISTORTION:
            jac_shared[:, 3 + t] = hj[:, 7]
        elif name == PINCHING:
            jac_shared[:, 3 + t] = hj[:, 8]
        elif name == SERIES_DASHPOT:
            jac_shared[:, 3 + t] = d_rho
    y = f
    if SENSOR_LAG in names:
        col = 3 + names.index(SENSOR_LAG)
        h, dh = lag_filter(p, frequency, sh[col])
        y = _apply(h, f[:, None])[:, 0]
        jac_shared = _apply(h, jac_shared)
        jac_own = _apply(h, jac_own)
        jac_shared[:, col] = _apply(dh, f[:, None])[:, 0]
    if OFFSET in names:
        col = 3 + names.index(OFFSET)
        y = y + sh[col]
        jac_shared[:, col] = 1.0
    _finite_array("model output", y)
    return y, jac_shared, jac_own


class _Problem(NamedTuple):
    """The checked data of :func:`augmented_refine`, and the model's constraints and cost on them."""

    ys: list[FloatArray]
    amps: FloatArray
    freqs: FloatArray
    psis: FloatArray
    wts: FloatArray
    names: tuple[str, ...]
    substeps: tuple[int, ...]
    mu_lo: float
    mu_hi: float
    waveforms: Optional[Sequence[ArrayLike]]
    input_shapes: Optional[Sequence[ArrayLike]] = None
    smoothing: float = COULOMB_SMOOTHING

    @property
    def ns(self) -> int:
        """Size of the shared block ``[beta, gamma, mu, q_1 .. q_T]``."""
        return 3 + len(self.names)

    def col(self, name: str) -> int:
        return 3 + self.names.index(name)

    def play_max(self, par: FloatArray) -> float:
        return PLAY_MAX_FRACTION * float(np.min(np.abs(self.amps * par[self.ns :: 2])))

    def admissible(self, par: FloatArray) -> bool:
        ok = admissible_bouc_wen(par, self.mu_lo, self.mu_hi)
        if ASYMMETRY in self.names:
            ok = ok and abs(par[self.col(ASYMMETRY)]) < par[0] + par[1]
        if SENSOR_LAG in self.names:
            ok = ok and par[self.col(SENSOR_LAG)] >= 0.0
        if PLAY in self.names:
            ok = ok and 0.0 <= par[self.col(PLAY)] <= self.play_max(par)
        if PINCHING in self.names:
            ok = ok and 0.0 <= par[self.col(PINCHING)] <= PINCHING_MAX
        if SERIES_DASHPOT in self.names:
            ok = ok and par[self.col(SERIES_DASHPOT)] >= 0.0
        return ok and all(par[self.col(n)] >= 0.0 for n in _DAHL_NAMES if n in self.names)

    def evaluate(self, par: FloatArray) -> tuple[float, tuple[list[FloatArray], FloatArray, FloatArray]]:
        """``(cost, (outputs, J'WJ, J'Wr))`` at ``par``."""
        n, ns = par.size, self.ns
        cost = 0.0
        outputs = []
        fisher = np.zeros((n, n))
        grad = np.zeros(n)
        for i, yi in enumerate(self.ys):
            y, js, jo = augmented_output(
                yi.size,
                self.amps[i],
                self.freqs[i],
                self.psis[i],
                self.names,
                par[:ns],
                par[ns + 2 * i],
                par[ns + 1 + 2 * i],
                self.substeps[i],
                None if self.waveforms is None else self.waveforms[i],
                None if not self.input_shapes else self.input_shapes[i],
                self.smoothing,
            )
            r = yi - y
            cost += self.wts[i] * float(np.sum(r * r))
            full = np.zeros((yi.size, n))
            full[:, :ns] = js
            full[:, ns + 2 * i : ns + 2 * i + 2] = jo
            fisher += self.wts[i] * full.T @ full
            grad += self.wts[i] * full.T @ r
            outputs.append(y)
        return cost, (outputs, fisher, grad)

    def constraints(self, par: FloatArray) -> list[Constraint]:
        """The closed constraints of ``rust/augmented.rs``: the Bouc-Wen ones, then ``name=0`` and
        ``name=upper`` of the sensor lag, the play (up to :meth:`play_max`) and the pinching."""
        cons = bouc_wen_constraints(par.size, self.mu_lo, self.mu_hi)
        play = self.play_max(par)
        for name, upper in (
            (SENSOR_LAG, None),
            (PLAY, play),
            (PINCHING, PINCHING_MAX),
            (SERIES_DASHPOT, None),
        ):
            if name in self.names:
                e = np.zeros(par.size)
                e[self.col(name)] = 1.0
                cons.append((f"{name}=0", e, 0.0))
                if upper is not None:
                    cons.append((f"{name}=upper", -e, -upper))
        for name in _DAHL_NAMES:
            if name in self.names:
                e = np.zeros(par.size)
                e[self.col(name)] = 1.0
                cons.append((f"{name}=0", e, 0.0))
        return cons

    def project(self, trial: FloatArray) -> None:
        """The projections of :func:`.refine.refine`, then tau and b clipped into their ranges."""
        project_bouc_wen(trial, self.mu_lo, self.mu_hi)
        if SENSOR_LAG in self.names:
            trial[self.col(SENSOR_LAG)] = max(trial[self.col(SENSOR_LAG)], 0.0)
        if PLAY in self.names:
            trial[self.col(PLAY)] = max(min(trial[self.col(PLAY)], self.play_max(trial)), 0.0)
        if PINCHING in self.names:
            trial[self.col(PINCHING)] = min(max(trial[self.col(PINCHING)], 0.0), PINCHING_MAX)
        if SERIES_DASHPOT in self.names:
            trial[self.col(SERIES_DASHPOT)] = max(trial[self.col(SERIES_DASHPOT)], 0.0)
        for name in _DAHL_NAMES:
            if name in self.names:
                trial[self.col(name)] = max(trial[self.col(name)], 0.0)


def _check_refine(
    ybars: Sequence[ArrayLike],
    vectors: tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike],
    terms: Sequence[str],
    start: tuple[ArrayLike, ArrayLike, ArrayLike],
    max_iter: int,
    substeps: int,
    mu_lo: float,
    mu_hi: float,
    waveforms: Optional[Sequence[ArrayLike]],
    experiment_substeps: Optional[Sequence[int]] = None,
    input_shapes: Optional[Sequence[ArrayLike]] = None,
    smoothing: float = COULOMB_SMOOTHING,
) -> tuple[_Problem, FloatArray, FloatArray, FloatArray]:
    """The arguments of :func:`augmented_refine` checked in the core's order: the problem and the start
    ``(shared0, gains0, phases0)``."""
    names = parse_terms(terms)
    ys = [np.asarray(y, dtype=np.float64) for y in ybars]
    m = len(ys)
    amps, freqs, psis, wts = (np.asarray(v, dtype=np.float64).ravel() for v in vectors)
    if not (amps.size == freqs.size == psis.size == wts.size == m):
        raise InvalidParameterError(
            f"{m} experiments but {amps.size} amplitudes, {freqs.size} frequencies, {psis.size} grid phases "
            f"and {wts.size} weights"
        )
    if max_iter < 1 or substeps < 1:
        raise InvalidParameterError("max_iter and substeps must be >= 1")
    sh0, g0, p0 = (np.asarray(v, dtype=np.float64).ravel() for v in start)
    if m == 0:
        raise InsufficientDataError("the refinement needs at least one experiment")
    if g0.size != m or p0.size != m:
        raise InvalidParameterError(f"{m} experiments but {g0.size} gains and {p0.size} phases")
    for i in range(m):
        _finite_array(f"ybar[{i}]", ys[i])
        _check_excitation(float(amps[i]), float(freqs[i]), float(psis[i]))
        _finite_scalar("weight", float(wts[i]))
        if wts[i] <= 0.0:
            raise InvalidParameterError(f"experiment {i}: weight {wts[i]} must be > 0 (N / noise variance)")
    _finite_array("gains", g0)
    _finite_array("phases", p0)
    if not np.isfinite(mu_lo) or mu_lo < 1.0 or np.isnan(mu_hi) or mu_hi <= mu_lo:
        raise InvalidParameterError(
            f"the mu bracket ({mu_lo}, {mu_hi}] must have a finite lower end >= 1 below its upper end"
        )
    _check_shared(names, sh0)
    if waveforms is not None and len(waveforms) != m:
        raise InvalidParameterError(f"{m} experiments but {len(waveforms)} waveforms")
    own = [substeps] * m if experiment_substeps is None else [int(k) for k in experiment_substeps]
    if len(own) != m:
        raise InvalidParameterError(f"{m} experiments but {len(own)} substep counts")
    if any(k < 1 for k in own):
        raise InvalidParameterError(f"experiment_substeps = {own} must all be >= 1")
    if input_shapes and len(input_shapes) != m:
        raise InvalidParameterError(f"{m} experiments but {len(input_shapes)} input shapes")
    problem = _Problem(
        ys, amps, freqs, psis, wts, names, tuple(own), mu_lo, mu_hi, waveforms, input_shapes, smoothing
    )
    return problem, sh0, g0, p0


def augmented_refine(
    ybars: Sequence[ArrayLike],
    amplitudes: ArrayLike,
    frequencies: ArrayLike,
    grid_phases: ArrayLike,
    weights: ArrayLike,
    terms: Sequence[str],
    shared0: ArrayLike,
    gains0: ArrayLike,
    phases0: ArrayLike,
    *,
    max_iter: int = 200,
    substeps: int = 4,
    mu_lo: float = 1.0,
    mu_hi: float = float("inf"),
    waveforms: Optional[Sequence[ArrayLike]] = None,
    experiment_substeps: Optional[Sequence[int]] = None,
    input_shapes: Optional[Sequence[ArrayLike]] = None,
    coulomb_smoothing: float = COULOMB_SMOOTHING,
    stall_window: int = 0,
    stall_rtol: float = 0.0,
    step_rtol: float = 0.0,
) -> tuple[
    FloatArray, FloatArray, FloatArray, float, int, bool, FloatArray, list[FloatArray], str, list[str]
]:
    """Joint Levenberg-Marquardt of the augmented model over every experiment (design.md 9.3).

    Returns ``(shared, gains, phases, cost, iterations, converged, fisher, outputs, stop, active)`` with
    ``fisher`` ordered ``[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]``, ``stop`` the stopping
    rule and ``active`` the constraints the fit ends on (:func:`.refine.levenberg_marquardt`).
    ``experiment_substeps``, one count per experiment, overrides ``substeps`` for each. ``stall_window``,
    ``stall_rtol``, ``step_rtol``: the stall rules (0: off; :func:`.refine.levenberg_marquardt`'s ``stall``).
    """
    ftol, xtol = 1e-12, 1e-10
    if stall_window < 0 or not all(np.isfinite(v) and v >= 0.0 for v in (stall_rtol, step_rtol)):
        raise InvalidParameterError(
            f"stall_window = {stall_window} must be >= 0 and the stall rules' rtol ({stall_rtol}, "
            f"{step_rtol}) finite and >= 0"
        )
    vectors = (amplitudes, frequencies, grid_phases, weights)
    start = (shared0, gains0, phases0)
    prob, sh0, g0, p0 = _check_refine(
        ybars,
        vectors,
        terms,
        start,
        max_iter,
        substeps,
        mu_lo,
        mu_hi,
        waveforms,
        experiment_substeps,
        input_shapes,
        check_smoothing(coulomb_smoothing),
    )
    ns = prob.ns
    params = np.concatenate([sh0, np.column_stack([g0, p0]).ravel()])
    if not prob.admissible(np.concatenate([params[:3], np.zeros(len(prob.names)), params[ns:]])):
        raise InvalidParameterError(
            f"the starting point (beta = {sh0[0]}, gamma = {sh0[1]}, mu = {sh0[2]}) must satisfy "
            f"beta >= |gamma|, beta + gamma > 0 and {mu_lo} < mu <= {mu_hi}"
        )
    if PLAY in prob.names and params[prob.col(PLAY)] > prob.play_max(params):
        raise InvalidParameterError(
            f"the starting play b = {params[prob.col(PLAY)]} must be below {PLAY_MAX_FRACTION} min "
            f"|U_i g_i| = {prob.play_max(params)}"
        )
    params, cost, it, converged, fisher, (outputs, _, _), stop, active = levenberg_marquardt(
        params,
        prob.evaluate,
        lambda state: (state[1], state[2]),
        prob.project,
        prob.admissible,
        max_iter=max_iter,
        ftol=ftol,
        xtol=xtol,
        constraints=prob.constraints,
        stall=(int(stall_window), float(stall_rtol), float(step_rtol)),
    )
    return (
        params[:ns].copy(),
        params[ns::2].copy(),
        params[ns + 1 :: 2].copy(),
        float(cost),
        it,
        converged,
        fisher,
        outputs,
        stop,
        active,
    )

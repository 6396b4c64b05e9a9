"""Feedforward hysteresis compensation (issue 21, item 1): the input that makes a model follow a reference.

:func:`compensate` inverts the model ``u -> G -> x -> Bouc-Wen -> w -> (terms) -> y`` stage by stage, from the
output back to the input, on the whole reference at once (it is known ahead, so nothing needs to be causal):

1. **Output terms** (``y = y0 + Lag_tau[F]``): the offset is subtracted and the sensor lag inverted,
   ``F = v + tau dv/dt`` (the reference's derivative by second-order finite differences).
2. **Terms on u** (``F = w + k u + c udot + m uddot + f tanh(udot/(eps Vmax))``): the input appears on both
   sides, so the whole chain is solved jointly by model-based iterative inversion (iterative learning
   control run on the model, not on the plant): from the direct inverse of the hysteresis and G,
   ``u <- u + lam P^-1 (F - Y(u))`` with ``Y`` the model's own simulation (the library's RK4) and ``P`` its
   linear part with the hysteresis at its largest slope (``alpha G + k + c s + m s^2``, applied by FFT through
   the same zero-phase low-pass), ``lam`` halved until the residual falls.  The same refinement is available
   for any model (``refine=``).  The same terms across the hysteretic element (on ``x = G u``: ``F = w + k x
   + c xdot + f tanh(...)``, what ``Diagnosis.to_model`` writes for a term named "on x") are solved the
   same way, their share of ``P`` taken through G (``(k + c s) G``); inertia on x is refused (the
   refinement stalls on it).
3. **Hysteresis**: the Bouc-Wen equation has the multiplicative structure
   ``wdot = xdot h(w, sgn xdot)``, ``h = alpha - |w|^mu (beta sgn(xdot w) + gamma + delta sgn w)``, and
   ``h > 0`` on the open range ``-w_sat- < w < w_sat+``; there the operator is invertible and
   ``dx = dw / h(w, sgn dw)``.  Rate independence makes this exact sample to sample: over a sample interval
   where ``w`` moves monotonically from ``w_a`` to ``w_b``, ``x`` moves by ``int_{w_a}^{w_b} dw / h``,
   computed by Gauss-Legendre quadrature (8 nodes, split at ``w = 0``, on 16 panels where ``1/h`` varies by
   more than 20 % over the interval).  No loop over samples: it is a cumulative sum.
4. **Linear part** ``G(s) = exp(-T s) N(s)/D(s)``: the zeros of ``N`` split into left-half-plane ones
   (inverted directly) and right-half-plane ones, which by default (``nmp="stable"``) are inverted exactly by
   a stable *anti-causal* filter (run backward in time over the known reference: stable inversion), or with
   ``nmp="mirror"`` replaced by their mirror images ``-conj(z)`` (same gain, a phase error, causal).  The
   improper ``D/N`` is made proper by a zero-phase low-pass ``F(s) = (wf^2/(wf^2 - s^2))^q`` split as ``q``
   causal and ``q`` anti-causal poles at ``wf``, with ``q`` the smallest order that makes both halves proper
   (the relative degree plus the number of right-half-plane zeros; none when ``q = 0``).  Its gain at a
   frequency ``omega`` is ``(1 + omega^2/wf^2)^-q``: no phase lag.  Each filter is discretised exactly for
   a piecewise-linear input (first-order hold) and applied by ``scipy.signal.lfilter``.  The pure delay is
   handled by preview: the command is the filtered ``x`` shifted ``T`` earlier (cubic spline between
   samples); beyond the reference's end it is held.
5. **Actuator limits**: the amplitude limit clips the command, the rate limit moves it toward the clipped
   command by at most ``rate_max dt`` per sample; both bind as reported in :class:`LimitHit`.

The predicted output is the model simulated on the final command by :func:`bouc_wen_id.simulate_input`
(the library's RK4), so it shows what the filter, the limits and the discretisation leave.

Terms the inverse does not handle (play, degradation, pinching, distortion, Dahl
friction, the series dashpot, inertia on x) are refused with
:class:`~bouc_wen_id.errors.InvalidParameterError`, by name.

References
----------
F. Ikhouane and J. Rodellar, *Systems with Hysteresis*, Wiley 2007 (the inverse multiplicative structure);
S. Devasia, D. Chen and B. Paden, *Nonlinear inversion-based output tracking*, IEEE TAC 41(7), 1996
(stable inversion of non-minimum-phase zeros); M. Tomizuka, *Zero phase error tracking algorithm for digital
control*, J. Dyn. Sys. Meas. Control 109, 1987 (the mirrored zeros).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._backend import Backend, get_backend
from .errors import InvalidParameterError, UnreachableReferenceError
from .model import BoucWen, TransferFunction, WienerPlant
from .result import IdentificationResult
from .simulation import simulate_input
from .terms import (
    Asymmetry,
    Coulomb,
    CoulombX,
    Inertia,
    Offset,
    Place,
    SensorLag,
    Stiffness,
    StiffnessX,
    Term,
    Viscous,
    ViscousX,
)
from .validation import EXACT_GRID_RTOL, check_time_axis, finite_array

__all__ = ["compensate", "Compensation", "LimitHit", "invert_hysteresis", "saturation_levels"]

FloatArray = NDArray[np.float64]

#: Default cutoff of the zero-phase low-pass, as a multiple of the reference's bandwidth ...
CUTOFF_FACTOR = 30.0
#: ... at most this fraction of the Nyquist frequency.
CUTOFF_NYQUIST = 0.1
#: The reference's bandwidth: the frequency below which this share of its (detrended) power lies.
BANDWIDTH_SHARE = 0.999
#: Iterations of the refinement when the model has mechanical terms, on u or on x (``refine`` not given).
REFINE_ITERATIONS = 50
#: Relative Tikhonov floor of the linear model inverted by the refinement (where ``P(j omega)`` vanishes).
REFINE_FLOOR = 1e-3
#: Terms the inverse includes (the others are refused by name).
_SUPPORTED = (Offset, SensorLag, Asymmetry, Stiffness, Viscous, Inertia, Coulomb)
#: The mechanical terms also handled across the hysteretic element (on x = G u): the refinement simulates
#: them with the library's simulator and its linear step adds them through G (:func:`_linear_solve`).
#: Inertia on x is not: its share ``m s^2 G`` of the linear step left the refinement stalled at 1.5-8.5 %
#: predicted error (resonant G with delay, first-order G with delay; on u 0.06-0.09 %).
_ON_X = (Stiffness, Viscous, Coulomb)

Model = Union[WienerPlant, IdentificationResult]


@dataclass(frozen=True)
class LimitHit:
    """Where an actuator limit bound the command.

    ``kind`` is ``"amplitude"`` (``|u| <= limit``) or ``"rate"`` (``|du/dt| <= limit``, per sample step);
    ``samples`` how many samples it changed, ``first_time`` the first of them (s), ``worst_excess`` how far
    the unlimited command went beyond the limit (in units of u, resp. u/s), and ``spans`` the time spans
    ``(start, end)`` where it bound (the first ten).
    """

    kind: str
    limit: float
    samples: int
    fraction: float
    first_time: float
    worst_excess: float
    spans: tuple[tuple[float, float], ...]

    def describe(self) -> str:
        unit = "" if self.kind == "amplitude" else "/s"
        return (
            f"{self.kind} limit {self.limit:g}{unit} bound on {self.samples} samples "
            f"({100 * self.fraction:.1f} %), "
            f"first at t = {self.first_time:.4g} s; the unlimited command exceeded it by up to "
            f"{self.worst_excess:.4g}{unit}"
        )


@dataclass(frozen=True, eq=False)
class Compensation:
    """The feedforward command and what the model predicts it does.

    Attributes
    ----------
    t, u : ndarray
        Time (s) and the command, limits applied.
    y_predicted : ndarray
        The model's output driven by ``u`` (:func:`bouc_wen_id.simulate_input`, from rest).
    y_reference : ndarray
        The reference as given.
    x_reference, w_reference : ndarray
        The hysteresis' input and output the inverse asked for (before the linear part's filter).
    u_unlimited : ndarray
        The command before the actuator limits.
    plant : WienerPlant
        The model inverted (for an identification result: the fitted G and the identified Bouc-Wen).
    choices : dict of str
        How each stage was inverted, in words: ``"hysteresis"``, ``"linear"``, ``"nonminimum_phase"``,
        ``"filter"``, ``"delay"``, ``"terms"``, ``"model"``.
    filter_order : int
        Poles of the zero-phase low-pass in all (``2 q``; 0 when none was needed).
    cutoff : float
        Its corner ``wf`` (rad/s); ``nan`` when no filter was needed.
    preview : float
        The delay handled by preview (s).
    saturation_use : float
        ``max |w_ref| / w_sat`` on the side it was reached (1 would be unreachable).
    iterations : int
        Iterations of the model-based refinement (0: the direct inverse alone).
    limits : tuple of LimitHit
        The limits that bound (empty when none did).
    """

    t: FloatArray
    u: FloatArray
    y_predicted: FloatArray
    y_reference: FloatArray
    x_reference: FloatArray
    w_reference: FloatArray
    u_unlimited: FloatArray
    plant: WienerPlant
    choices: dict[str, str]
    filter_order: int
    cutoff: float
    preview: float
    saturation_use: float
    iterations: int
    limits: tuple[LimitHit, ...] = field(default=())

    @property
    def tracking_error(self) -> float:
        """RMS of ``y_predicted - y_reference`` over RMS of the reference (about its mean)."""
        return _relative_rms(self.y_predicted - self.y_reference, self.y_reference)

    def summary(self) -> str:
        lines = ["Feedforward compensation", *(f"  {k}: {v}" for k, v in self.choices.items())]
        lines.append(f"  saturation use: {100 * self.saturation_use:.1f} % of w_sat")
        lines.append(f"  predicted tracking error: {100 * self.tracking_error:.3g} % RMS")
        lines += [f"  {hit.describe()}" for hit in self.limits] or ["  actuator limits: none bound"]
        return "\n".join(lines)


def _relative_rms(err: FloatArray, ref: FloatArray) -> float:
    scale = float(np.sqrt(np.mean((ref - np.mean(ref)) ** 2)))
    return float(np.sqrt(np.mean(err**2)) / scale) if scale > 0 else float(np.sqrt(np.mean(err**2)))


# ------------------------------------------------------------------------------------------------------
# The hysteresis


def saturation_levels(hysteresis: BoucWen, delta: float = 0.0) -> tuple[float, float]:
    """``(w_sat-, w_sat+)``: the inverse exists for ``-w_sat- < w < w_sat+`` (``h > 0`` when loading).

    ``w_sat+- = (alpha / (beta + gamma +- delta))^(1/mu)``, with ``delta`` the asymmetry (0 without).
    """
    h = hysteresis
    up = (h.alpha / (h.beta + h.gamma + delta)) ** (1.0 / h.mu)
    down = (h.alpha / (h.beta + h.gamma - delta)) ** (1.0 / h.mu)
    return float(down), float(up)


def _h(w: FloatArray, s: FloatArray, hy: BoucWen, delta: float) -> FloatArray:
    """``h(w, s) = alpha - |w|^mu (beta s sgn w + gamma + delta sgn w)``: ``wdot = xdot h``."""
    sw = np.sign(w)
    return np.asarray(hy.alpha - np.abs(w) ** hy.mu * (hy.beta * s * sw + hy.gamma + delta * sw))


def invert_hysteresis(
    w: ArrayLike, hysteresis: BoucWen, delta: float = 0.0, x0: float = 0.0, *, backend: Backend = "rust"
) -> FloatArray:
    """The input ``x`` whose Bouc-Wen output is ``w`` at the samples, from the state ``(x0, hysteresis.w0)``.

    Exact up to quadrature along a path that is monotone between samples (the operator is rate-independent):
    ``x_k = x_{k-1} + int_{w_{k-1}}^{w_k} dw / h(w, sgn(w_k - w_{k-1}))`` by 8-node Gauss-Legendre, split at
    ``w = 0``, on 16 panels where ``h`` varies by more than 20 % over the interval (``rust/compensate.rs``;
    ``backend="numpy"``: its oracle).  ``delta`` is the asymmetry.

    Raises
    ------
    UnreachableReferenceError
        A sample at or beyond the saturation level (``w <= -w_sat-`` or ``w >= w_sat+``).
    NonFiniteError
        A non-finite sample.
    """
    ww = finite_array("w", w)
    hy = hysteresis
    down, up = saturation_levels(hy, delta)
    bad = np.flatnonzero((ww >= up) | (ww <= -down))
    if bad.size or not -down < hy.w0 < up:
        k = int(bad[0]) if bad.size else -1
        value = float(ww[k]) if bad.size else hy.w0
        where = f"sample {k}" if bad.size else "the initial state w0"
        raise UnreachableReferenceError(
            f"the hysteresis would need w = {value:.6g} at {where}, outside its range "
            f"({-down:.6g}, {up:.6g}): "
            "the Bouc-Wen output saturates there (w_sat = (alpha/(beta + gamma +- delta))^(1/mu)); scale the "
            "reference down or remove the offset"
        )
    core = get_backend(backend).compensate
    x = core.invert_path(np.ascontiguousarray(ww), hy.alpha, hy.beta, hy.gamma, hy.mu, delta, hy.w0, x0)
    return np.asarray(x, dtype=np.float64)


# ------------------------------------------------------------------------------------------------------
# The linear part


@dataclass(frozen=True)
class _LinearInverse:
    """Polynomials of the causal and anti-causal halves of ``F/G0`` and what they mean."""

    causal: tuple[FloatArray, FloatArray]
    anticausal: tuple[FloatArray, FloatArray]
    order: int
    cutoff: float
    slowest: float
    choices: dict[str, str]


def _roots_text(z: NDArray[np.complex128]) -> str:
    """Roots in words: real ones as reals, complex ones as ``a+bj`` (6 significant digits)."""
    return "[" + ", ".join(f"{r.real:.6g}" if r.imag == 0 else f"{r:.6g}" for r in z) + "]"


def _f64(v: ArrayLike) -> FloatArray:
    return np.asarray(v, dtype=np.float64)


def _zeros(num: FloatArray) -> tuple[float, NDArray[np.complex128]]:
    nz = np.flatnonzero(num)
    n = num[nz[0] :] if nz.size else num
    return float(n[0]), np.asarray(np.roots(n), dtype=np.complex128)


def _linear_inverse(lin: TransferFunction, cutoff: float, nmp: str) -> _LinearInverse:
    lead, z = _zeros(np.asarray(lin.num, dtype=np.float64))
    den = np.asarray(lin.den, dtype=np.float64)
    scale = np.maximum(1.0, np.abs(z))
    axis = np.abs(z.real) <= 1e-9 * scale
    if np.any(axis):
        raise UnreachableReferenceError(
            f"G has a zero on the imaginary axis ({z[axis][0]:.6g}): it blocks that frequency and cannot be "
            "inverted there"
        )
    right = z[z.real > 0]
    left = z[z.real < 0]
    choices: dict[str, str] = {}
    if right.size and nmp == "mirror":
        left = np.concatenate((left, -np.conj(right)))
        choices["nonminimum_phase"] = (
            f"{right.size} right-half-plane zero(s) {_roots_text(right)} replaced by their mirror "
            "images -conj(z): the gain is inverted exactly, the phase is not (a causal approximation)"
        )
        right = right[:0]
    elif right.size:
        choices["nonminimum_phase"] = (
            f"{right.size} right-half-plane zero(s) {_roots_text(right)} inverted exactly by a "
            "stable anti-causal filter run backward in time over the known reference (stable inversion)"
        )
    else:
        choices["nonminimum_phase"] = "none: G is minimum-phase"
    n_left = np.asarray(np.real(np.poly(left)), dtype=np.float64) if left.size else np.ones(1)
    n_right = np.asarray(np.real(np.poly(right)), dtype=np.float64) if right.size else np.ones(1)
    q = den.size - 1 - left.size
    wf = float(cutoff) if q > 0 else math.nan
    pole = np.array([1.0, wf]) if q > 0 else np.ones(1)
    fc = np.ones(1)
    for _ in range(q):
        fc = np.polymul(fc, pole)
    gain = wf**q if q > 0 else 1.0
    causal = (_f64(den * gain / lead), _f64(np.polymul(n_left, fc)))
    # The anti-causal half in reversed time: 1/(N_right(-s) (s + wf)^q) times wf^q.
    flip = n_right * (-1.0) ** np.arange(n_right.size - 1, -1, -1)
    anticausal = (_f64([gain]), _f64(np.polymul(flip, fc)))
    speeds = [abs(r.real) for r in np.concatenate((left, right))] + ([wf] if q > 0 else [])
    choices["linear"] = (
        f"D(s)/N(s) inverted: {den.size - 1} pole(s) become zeros, {left.size} left-half-plane zero(s) "
        "become poles"
    )
    choices["filter"] = (
        f"zero-phase low-pass (wf^2/(wf^2 - s^2))^{q}: {2 * q} poles at wf = {wf:.6g} rad/s "
        f"({wf / (2 * math.pi):.6g} Hz), {q} causal and {q} anti-causal; gain (1 + omega^2/wf^2)^-{q}, "
        "no phase"
        if q > 0
        else "none needed: D/N is proper (G has relative degree 0 and no right-half-plane zero)"
    )
    return _LinearInverse(causal, anticausal, 2 * q, wf, min(speeds) if speeds else math.inf, choices)


def _apply(tf: tuple[FloatArray, FloatArray], x: FloatArray, dt: float, steady: bool) -> FloatArray:
    """The proper stable ``num/den`` on ``x``, exact for a piecewise-linear input (FOH): from rest, or
    (``steady``) from the steady state of the input held at ``x[0]`` before the start."""
    from scipy.signal import cont2discrete, lfilter, lfilter_zi  # type: ignore[import-untyped]

    num, den = tf
    if den.size == 1:
        return np.asarray(x * (num[-1] / den[0]))
    numd, dend, _ = cont2discrete((num, den), dt, method="foh")
    numd = np.atleast_1d(np.squeeze(numd))
    if not steady:
        return np.asarray(lfilter(numd, dend, x))
    out, _ = lfilter(numd, dend, x, zi=lfilter_zi(numd, dend) * x[0])
    return np.asarray(out)


def _invert_linear(inv: _LinearInverse, x: FloatArray, dt: float, delay: float) -> FloatArray:
    """``u(t) = [F/G0] x (t + delay)`` on the samples: the preview shift, the reference held past its end."""
    from scipy.interpolate import CubicSpline  # type: ignore[import-untyped]

    settle = 12.0 / inv.slowest if math.isfinite(inv.slowest) and inv.slowest > 0 else 0.0
    pad = int(math.ceil((delay + settle) / dt)) + 4
    ext = np.concatenate((x, np.full(pad, x[-1])))
    v = _apply(inv.causal, ext, dt, steady=False)
    # Backward in time from the held end, where the causal half has settled.
    v = _apply(inv.anticausal, v[::-1], dt, steady=True)[::-1]
    n = x.size
    if delay == 0.0:
        return np.asarray(v[:n])
    te = np.arange(ext.size) * dt
    return np.asarray(CubicSpline(te, v)(np.arange(n) * dt + delay))


def _default_cutoff(y: FloatArray, dt: float) -> float:
    """CUTOFF_FACTOR times the reference's bandwidth, at most CUTOFF_NYQUIST of the Nyquist frequency."""
    nyq = math.pi / dt
    spec = np.abs(np.fft.rfft(y - np.linspace(y[0], y[-1], y.size))) ** 2
    om = 2.0 * math.pi * np.fft.rfftfreq(y.size, dt)
    cum = np.cumsum(spec)
    if cum[-1] <= 0:
        return CUTOFF_NYQUIST * nyq
    band = float(om[int(np.searchsorted(cum, BANDWIDTH_SHARE * cum[-1]))])
    return float(min(CUTOFF_FACTOR * max(band, om[1]), CUTOFF_NYQUIST * nyq))


# ------------------------------------------------------------------------------------------------------
# Terms, limits, and the whole chain


def _plant_of(model: Model, linear: Optional[TransferFunction]) -> tuple[WienerPlant, str]:
    if isinstance(model, WienerPlant):
        plant = model if linear is None else WienerPlant(linear, model.hysteresis, model.terms)
        return plant, "the given plant" + (" with the given G" if linear is not None else "")
    if isinstance(model, IdentificationResult):
        hy = BoucWen(model.beta, model.gamma, model.mu)
        if linear is not None:
            return WienerPlant(linear, hy), "identified Bouc-Wen (alpha = 1) with the given G"
        fit = model.fit_transfer_function()
        g = fit.transfer_function
        what = (
            f"identified Bouc-Wen (alpha = 1); G fitted to the identified points: {fit.m} zero(s), {fit.n} "
        )
        what += f"pole(s), delay {g.delay:.4g} s ({'fitted' if fit.delay_fitted else 'none'})"
        return WienerPlant(g, hy), what
    raise InvalidParameterError(
        f"model must be a WienerPlant or an IdentificationResult, got {type(model).__name__}"
    )


def _term(plant: WienerPlant, cls: type[Term]) -> Optional[Term]:
    """The plant's term of class ``cls`` (by class, so that no code name is spelled here), or None."""
    return next((t for t in plant.terms if isinstance(t, cls)), None)


def _check_terms(terms: tuple[Term, ...]) -> None:
    for t in terms:
        if t.companion or t.part_of:  # Dahl friction
            raise InvalidParameterError(
                f"{t.label} ({t.kind}): the feedforward inverse does not handle Dahl friction: its "
                "force has a memory of the travel's own path (a state), so the input that gives y_ref cannot "
                "be read off y stage by stage as for the memoryless terms; it would need the friction solved "
                "inside the inverse. Compensate the plant without it (WienerPlant(linear, hysteresis, "
                "other terms)) and treat the friction as a disturbance, or simulate the plant with it to "
                "check the residual"
            )
        if t.place == Place.X and isinstance(t, Inertia):
            raise InvalidParameterError(
                f"{t.label} ({t.kind}): the feedforward inverse does not handle an inertia across the "
                "hysteretic element: its model-based refinement stalls on it (1.5-8.5 % predicted error "
                "where the same mass on u reaches 0.1 %); simulate the plant with it to check a command, or "
                "compensate without it. Handled on x: "
                + ", ".join(c.kind for c in (StiffnessX, ViscousX, CoulombX))
            )
        if not isinstance(t, _SUPPORTED) or (t.place == Place.X and not isinstance(t, _ON_X)):
            raise InvalidParameterError(
                f"{t.label} ({t.kind}): the feedforward inverse does not handle this term yet; it handles "
                + ", ".join(c.kind for c in _SUPPORTED)
            )


def _output_target(plant: WienerPlant, y: FloatArray, dt: float) -> tuple[FloatArray, list[str]]:
    """``F`` from the reference: the offset removed, the sensor lag inverted."""
    said = []
    v = y.copy()
    off = _term(plant, Offset)
    if isinstance(off, Offset) and off.y0 != 0.0:
        v -= off.y0
        said.append(f"offset y0 = {off.y0:g} subtracted")
    lag = _term(plant, SensorLag)
    if isinstance(lag, SensorLag) and lag.tau > 0.0:
        v = v + lag.tau * np.gradient(v, dt, edge_order=2)
        said.append(f"sensor lag tau = {lag.tau:g} s inverted: F = v + tau dv/dt (finite differences)")
    return v, said


def _hit(kind: str, limit: float, changed: NDArray[np.bool_], excess: FloatArray, dt: float) -> LimitHit:
    idx = np.flatnonzero(changed)
    edges = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate(([idx[0]], idx[edges + 1]))
    ends = np.concatenate((idx[edges], [idx[-1]]))
    spans = tuple((float(a * dt), float(b * dt)) for a, b in zip(starts[:10], ends[:10]))
    return LimitHit(kind, limit, int(idx.size), idx.size / changed.size, float(idx[0] * dt),
                    float(np.max(excess)), spans)  # fmt: skip


def _limits(
    u: FloatArray, dt: float, u_max: Optional[float], rate_max: Optional[float], backend: Backend
) -> tuple[FloatArray, tuple[LimitHit, ...]]:
    hits = []
    out = u
    if u_max is not None:
        out = np.clip(u, -u_max, u_max)
        over = np.abs(u) > u_max
        if over.any():
            hits.append(_hit("amplitude", u_max, over, np.abs(u) - u_max, dt))
    if rate_max is not None:
        core = get_backend(backend).compensate
        limited = np.asarray(core.rate_limit(np.ascontiguousarray(out), rate_max * dt, 0.0), dtype=np.float64)
        moved = np.abs(limited - out) > 1e-12 * max(1.0, float(np.max(np.abs(out))))
        rate = np.abs(np.diff(np.concatenate(([0.0], out)))) / dt
        if moved.any():
            hits.append(_hit("rate", rate_max, moved, np.maximum(rate - rate_max, 0.0), dt))
        out = limited
    return out, tuple(hits)


def _positive(name: str, v: Optional[float]) -> Optional[float]:
    if v is None:
        return None
    f = float(v)
    if not math.isfinite(f) or f <= 0:
        raise InvalidParameterError(f"{name} = {v!r} must be a finite number > 0 (or None: no limit)")
    return f


def compensate(
    model: Model,
    y_ref: ArrayLike,
    t: ArrayLike,
    *,
    cutoff: Optional[float] = None,
    nmp: Literal["stable", "mirror"] = "stable",
    u_max: Optional[float] = None,
    rate_max: Optional[float] = None,
    linear: Optional[TransferFunction] = None,
    refine: Optional[int] = None,
    tol: float = 1e-9,
    substeps: int = 4,
    backend: Backend = "rust",
) -> Compensation:
    """The command ``u(t)`` that makes ``model`` follow ``y_ref(t)``: its feedforward inverse (module doc).

    Parameters
    ----------
    model : WienerPlant or IdentificationResult
        A plant (with terms: the augmented model), or an identification result, whose G is then fitted to
        its points by :func:`bouc_wen_id.fit_transfer_function` (or given as ``linear``).
    y_ref, t : array_like
        The reference output and its uniform time axis (s); the model starts from rest at ``t[0]``, so a
        reference that starts at the model's rest output is followed from the start.
    cutoff : float, optional
        Corner ``wf`` (rad/s) of the zero-phase low-pass that makes ``1/G`` proper.  Default: 30 times the
        frequency below which 99.9 % of the reference's power lies, at most a tenth of the Nyquist frequency
    nmp : {"stable", "mirror"}
        Right-half-plane zeros of G: inverted exactly by an anti-causal filter (default), or mirrored.
    u_max, rate_max : float, optional
        Actuator limits: ``|u| <= u_max``, ``|du/dt| <= rate_max`` (per sample step).
    linear : TransferFunction, optional
        Replace the model's G (e.g. an identification result's, fitted your own way).
    refine : int, optional
        Iterations of the model-based refinement (``u <- u + lam P^-1 (F - Y(u))`` on the model's own
        simulation, :func:`_refine`), stopped when the RMS residual falls below ``tol`` times the target's.
        Default: 50 when the model has mechanical terms, on u or on x (they are solved this way), else 0
        (the direct inverse).
    tol : float
        Its stopping level.
    substeps : int
        RK4 steps per sample of the model's simulations (:func:`bouc_wen_id.simulate_input`).
    backend : {"rust", "numpy"}
        The path inverse, the rate limiter and the simulations: the Rust core or the NumPy reference.

    Raises
    ------
    UnreachableReferenceError
        The reference needs the hysteresis at or beyond its saturation, or G has a zero on the imaginary axis.
    NonFiniteError, TimeAxisError
        A non-finite reference or time; a time axis that is not uniform.
    InvalidParameterError
        A term the inverse does not handle, unequal lengths, a bad limit or option.
    """
    plant, said_model = _plant_of(model, linear)
    _check_terms(plant.terms)
    tt = finite_array("t", t)
    y = finite_array("y_ref", y_ref)
    if tt.size != y.size or tt.size < 8:
        raise InvalidParameterError(f"t and y_ref must have equal lengths >= 8, got {tt.size} and {y.size}")
    check_time_axis(tt, rtol=EXACT_GRID_RTOL)
    if nmp not in ("stable", "mirror"):
        raise InvalidParameterError(f"nmp = {nmp!r} must be 'stable' or 'mirror'")
    dt = float((tt[-1] - tt[0]) / (tt.size - 1))
    lim_u, lim_rate = _positive("u_max", u_max), _positive("rate_max", rate_max)
    wf = _positive("cutoff", cutoff)
    inv = _linear_inverse(plant.linear, _default_cutoff(y, dt) if wf is None else wf, nmp)
    asym = _term(plant, Asymmetry)
    delta = asym.delta if isinstance(asym, Asymmetry) else 0.0
    target, said_terms = _output_target(plant, y, dt)
    mech_terms = tuple(t for t in plant.terms if isinstance(t, (Stiffness, Viscous, Inertia, Coulomb)))
    rounds = (REFINE_ITERATIONS if mech_terms else 0) if refine is None else int(refine)
    if rounds > 0:
        u, x_ref, w_ref, sweeps = _refine(plant, inv, target, dt, delta, rounds, tol, backend)
    else:
        (u, x_ref), w_ref, sweeps = _direct(plant, inv, target, dt, delta, backend), target, 0
    down, up = saturation_levels(plant.hysteresis, delta)
    use = float(max(np.max(w_ref) / up, -np.min(w_ref) / down, 0.0))
    u_final, hits = _limits(u, dt, lim_u, lim_rate, backend)
    _, _, y_pred = simulate_input(plant, tt, u_final, substeps=substeps, backend=backend, output=True)
    choices = _choices(plant, said_model, inv, said_terms, mech_terms, sweeps, delta)
    return Compensation(
        t=tt, u=u_final, y_predicted=np.asarray(y_pred), y_reference=y, x_reference=x_ref, w_reference=w_ref,
        u_unlimited=u, plant=plant, choices=choices, filter_order=inv.order, cutoff=inv.cutoff,
        preview=plant.linear.delay, saturation_use=use, iterations=sweeps, limits=hits,
    )  # fmt: skip


def _direct(
    plant: WienerPlant, inv: _LinearInverse, w_ref: FloatArray, dt: float, delta: float, backend: Backend
) -> tuple[FloatArray, FloatArray]:
    """``(u, x_ref)``: the hysteresis and then G inverted for the hysteresis output ``w_ref``."""
    x_ref = invert_hysteresis(w_ref, plant.hysteresis, delta, backend=backend)
    return _invert_linear(inv, x_ref, dt, plant.linear.delay), x_ref


def _linear_solve(
    plant: WienerPlant, slope: float, wf: float, q: int, e: FloatArray, dt: float, share: bool = False
) -> FloatArray:
    """``P^-1 e`` (or ``share``: ``slope G P^-1 e``) with ``P = slope G + k + c s + m s^2`` (Coulomb left
    out; a term across the hysteretic element acts on x = G u, so it enters as ``(k + c s + m s^2) G``), by
    FFT on a padded, tapered copy, through the zero-phase low-pass of order ``q`` at ``wf`` and a
    Tikhonov floor of REFINE_FLOOR times the largest ``|P|`` below ``wf``."""
    n = e.size
    pad = max(n, 16)
    taper = e[-1] * 0.5 * (1.0 + np.cos(np.linspace(0.0, math.pi, pad)))
    ext = np.concatenate((e, taper, np.zeros(pad)))
    om = 2.0 * math.pi * np.fft.rfftfreq(ext.size, dt)
    s = 1j * om
    g_lin = plant.linear(s)
    g = slope * g_lin
    p_resp = g.copy()
    for t in plant.terms:
        through = g_lin if t.place == Place.X else 1.0
        if isinstance(t, Stiffness):
            p_resp = p_resp + t.k * through
        elif isinstance(t, Viscous):
            p_resp = p_resp + t.c * s * through
        elif isinstance(t, Inertia):
            p_resp = p_resp + t.m * s * s * through
    mag = np.abs(p_resp) ** 2
    band = mag[om <= wf] if np.any(om <= wf) else mag
    gain = np.conj(p_resp) / (mag + (REFINE_FLOOR**2) * float(np.max(band)))
    if share:
        gain = gain * g
    elif q > 0:
        gain = gain * (1.0 + (om / wf) ** 2) ** (-q)
    return np.asarray(np.fft.irfft(np.fft.rfft(ext) * gain, ext.size)[:n])


def _lowpass(e: FloatArray, wf: float, q: int, dt: float) -> FloatArray:
    """The zero-phase low-pass ``(1 + omega^2/wf^2)^-q`` by FFT on a tapered, padded copy."""
    if q == 0 or not math.isfinite(wf):
        return e
    n = e.size
    taper = e[-1] * 0.5 * (1.0 + np.cos(np.linspace(0.0, math.pi, n)))
    ext = np.concatenate((e, taper, np.zeros(n)))
    om = 2.0 * math.pi * np.fft.rfftfreq(ext.size, dt)
    return np.asarray(np.fft.irfft(np.fft.rfft(ext) * (1.0 + (om / wf) ** 2) ** (-q), ext.size)[:n])


def _slope(hy: BoucWen, x: FloatArray, w: FloatArray, delta: float) -> float:
    """Mid-range ``(min h + max h)/2`` of the hysteresis' slope ``dw/dx = h(w, sgn xdot)`` along a path."""
    h = _h(w, np.sign(np.gradient(x)), hy, delta)
    return float(0.5 * (np.min(h) + np.max(h)))


def _refine(
    plant: WienerPlant,
    inv: _LinearInverse,
    target: FloatArray,
    dt: float,
    delta: float,
    iterations: int,
    tol: float,
    backend: Backend,
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """``(u, x, w, iterations)``: model-based iterative inversion (ILC run on the model) of the terms.

    ``u <- Q (u + lam P^-1 (target - Y(u)))``: ``Y`` the model's output before the offset and lag (the
    library's simulator), ``P = h G + k + c s + m s^2`` its linear part with the hysteresis at its mid-range
    slope ``h`` along the current path (:func:`_linear_solve`), ``Q`` the zero-phase low-pass of the direct
    inverse; ``lam`` halved until a step lowers the RMS residual (doubled back after a success).  Starts from
    the direct inverse of the target kept within 90 % of saturation, passed through the hysteresis' share
    ``alpha G / P`` of the linear model.
    """
    hy = plant.hysteresis
    inner = WienerPlant(
        plant.linear, hy, tuple(t for t in plant.terms if not isinstance(t, (Offset, SensorLag)))
    )
    down, up = saturation_levels(hy, delta)
    u, _ = _direct(inner, inv, np.clip(target, -0.9 * down, 0.9 * up), dt, delta, backend)
    q = inv.order // 2
    wf = inv.cutoff if q else math.inf
    # The share of the output the hysteresis gives in the linear model: alpha G / P, applied to the start.
    u = _linear_solve(inner, hy.alpha, wf, q, u, dt, share=True)
    t_axis = np.arange(target.size) * dt

    def residual(u: FloatArray) -> tuple[FloatArray, FloatArray]:
        x, w, y = simulate_input(inner, t_axis, u, output=True, backend=backend)
        return target - y, np.stack((x, w))

    e, xw = residual(u)
    norm, lam = float(np.sqrt(np.mean(e**2))), 1.0
    scale = max(float(np.sqrt(np.mean((target - target.mean()) ** 2))), 1e-300)
    for it in range(1, max(1, iterations) + 1):
        if norm <= tol * scale:
            return u, xw[0], xw[1], it - 1
        step = _linear_solve(inner, _slope(hy, xw[0], xw[1], delta), wf, 0, e, dt)
        while lam > 1e-6:
            trial = _lowpass(u + lam * step, wf, q, dt)
            e_t, xw_t = residual(trial)
            n_t = float(np.sqrt(np.mean(e_t**2)))
            if n_t < norm:
                u, e, xw, norm = trial, e_t, xw_t, n_t
                lam = min(1.0, 2.0 * lam)
                break
            lam *= 0.5
        else:
            return u, xw[0], xw[1], it
    return u, xw[0], xw[1], iterations


def _choices(
    plant: WienerPlant,
    said_model: str,
    inv: _LinearInverse,
    said_terms: list[str],
    mech_terms: tuple[Term, ...],
    sweeps: int,
    delta: float,
) -> dict[str, str]:
    out = {"model": said_model}
    out["hysteresis"] = (
        "Bouc-Wen inverted along the path: dx = dw / h(w, sgn dw) integrated sample to sample "
        "(Gauss-Legendre, exact for a rate-independent element)"
        + (f", asymmetry delta = {delta:g}" if delta else "")
    )
    out.update(inv.choices)
    d = plant.linear.delay
    out["delay"] = (
        f"pure delay {d:g} s handled by preview: the command leads the filtered x by {d:g} s (the reference "
        "is known ahead; held at its last value beyond its end)"
        if d > 0
        else "none"
    )
    parts = list(said_terms)
    if mech_terms:
        parts.append(
            f"terms {[t.kind for t in mech_terms]} solved jointly with the hysteresis by model-based "
            f"iterative inversion ({sweeps} iterations on the model's own simulation, from the direct "
            "inverse)"
        )
    elif sweeps:
        parts.append(f"the direct inverse refined by {sweeps} model-based iterations")
    out["terms"] = "; ".join(parts) if parts else "none"
    return out

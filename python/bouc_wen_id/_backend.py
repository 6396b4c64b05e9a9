"""The one door to the numerics: the Rust extension or the NumPy reference, chosen by ``backend=``.

This is the only module that imports the compiled extension (``_core``) or the NumPy oracle
(:mod:`bouc_wen_id.reference`); ``tests/test_layout.py`` holds every other module to that.  Other modules
ask :func:`get_backend` for a :class:`Parts`, whose typed parts cover one domain of the bindings each:

==============  ===========================================  ================================================
part            Rust (``rust/bindings/``)                    NumPy (``backend="numpy"``)
==============  ===========================================  ================================================
``paper``       simulation, averaging, SLS, loops, refine    :mod:`bouc_wen_id.reference`
``augmented``   ``augmented_output``, ``augmented_refine``   :mod:`bouc_wen_id.reference.augmented`
``multistart``  ``refine_many`` (all cores, GIL released)    ``None``: the starts run one by one
``lab``         the fused harmonic kernels (``rust/lab``)    no kernel: ``signal/`` runs its NumPy paths
``compensate``  ``invert_path``, ``rate_limit``              :mod:`bouc_wen_id.reference.compensate`
``timedomain``  ``timedomain_sensitivities`` (issue #20)     :mod:`bouc_wen_id.reference.timedomain`
==============  ===========================================  ================================================

mypy checks the Rust stub (``_core.pyi``) and the reference against the Protocols (the block at the end), so
the two cannot drift apart in signature.  The lab preprocessing (``signal/``) is reached through public
functions that do not all take a backend; it asks :func:`current_lab`, which :func:`selected` sets for the
duration of an entry point's ``backend=`` (a context variable: per thread and per task, never global).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, Callable, Literal, Optional, Protocol, overload

import numpy as np
from numpy.typing import NDArray

from .errors import InvalidParameterError

Backend = Literal["rust", "numpy"]

__all__ = [
    "Augmented",
    "Backend",
    "Compensate",
    "Feedback",
    "Lab",
    "MultiStart",
    "Paper",
    "TimeDomain",
    "Parts",
    "current_lab",
    "feedback_part",
    "get_backend",
    "push_budget",
    "selected",
]

_F = NDArray[np.float64]


class Paper(Protocol):
    """The paper's routines and the plain model's fits, with the Rust extension's signatures (the reference
    accepts at least as much).

    Arrays are 1-D float64 (``_F``; the Rust side needs them C-contiguous); polynomial coefficients and
    per-experiment vectors may also be sequences of floats.  Shapes and units: ``rust/bindings/``.
    """

    @overload
    def simulate_sine(
        self,
        num: Sequence[float] | _F,
        den: Sequence[float] | _F,
        delay: float,
        alpha: float,
        beta: float,
        gamma: float,
        mu: float,
        w0: float,
        amplitude: float,
        omega: float,
        dt: float,
        n_samples: int,
        substeps: int,
        *,
        terms: None = None,
    ) -> tuple[_F, _F]: ...

    @overload
    def simulate_sine(
        self,
        num: Sequence[float] | _F,
        den: Sequence[float] | _F,
        delay: float,
        alpha: float,
        beta: float,
        gamma: float,
        mu: float,
        w0: float,
        amplitude: float,
        omega: float,
        dt: float,
        n_samples: int,
        substeps: int,
        *,
        terms: Mapping[str, float],
    ) -> tuple[_F, _F, _F]: ...

    @overload
    def simulate_sampled(
        self,
        num: Sequence[float] | _F,
        den: Sequence[float] | _F,
        delay: float,
        alpha: float,
        beta: float,
        gamma: float,
        mu: float,
        w0: float,
        u: _F,
        dt: float,
        substeps: int,
        *,
        terms: None = None,
    ) -> tuple[_F, _F]: ...

    @overload
    def simulate_sampled(
        self,
        num: Sequence[float] | _F,
        den: Sequence[float] | _F,
        delay: float,
        alpha: float,
        beta: float,
        gamma: float,
        mu: float,
        w0: float,
        u: _F,
        dt: float,
        substeps: int,
        *,
        terms: Mapping[str, float],
    ) -> tuple[_F, _F, _F]: ...

    def periodic_average(self, y: _F, samples_per_period: int, settle_periods: int, periods: int) -> _F: ...

    def phase_from_max(self, ybar: _F) -> float: ...

    def spectral_derivative(self, ybar: _F, omega: float, harmonics: int) -> _F: ...

    def sls_regressor(
        self, ybar: _F, ydot: _F, amplitude: float, omega: float, phi: float, nu: float
    ) -> _F: ...

    def solve_normal(self, m: _F, r: _F) -> tuple[_F, float]: ...

    def sls_theta(
        self, ybar: _F, ydot: _F, amplitude: float, omega: float, phi: float, nu: float
    ) -> tuple[_F, float]: ...

    def golden_section(
        self, func: Callable[[float], float], lo: float, hi: float, tol: float, max_iter: int = 200
    ) -> tuple[float, float, int]: ...

    def sls_search(
        self,
        ybar: _F,
        ydot: _F,
        amplitude: float,
        omega: float,
        phi: float,
        lo: float,
        hi: float,
        tol: float,
        max_iter: int = 200,
    ) -> tuple[float, _F, float, int]: ...

    def gain_estimate(
        self,
        ybar: _F,
        ydot: _F,
        amplitude: float,
        omega: float,
        phi: float,
        beta: float,
        gamma: float,
        mu: float,
    ) -> float: ...

    def steady_loop(
        self,
        amplitude: float,
        beta: float,
        gamma: float,
        mu: float,
        phi: float,
        samples_per_period: int,
        substeps: int,
    ) -> tuple[_F, _F, float, int]: ...

    def path_loop(
        self,
        amplitude: float,
        beta: float,
        gamma: float,
        mu: float,
        delta: float,
        play: float,
        phi: float,
        samples_per_period: int,
        substeps: int,
    ) -> tuple[_F, _F, int]: ...

    def path_loop_distorted(
        self,
        amplitude: float,
        beta: float,
        gamma: float,
        mu: float,
        delta: float,
        play: float,
        phi: float,
        lam: float,
        harmonics: _F,
        samples_per_period: int,
        substeps: int,
    ) -> tuple[_F, _F, int]: ...

    def profile_phase_sls(
        self, ybar: _F, ydot: _F, amplitude: float, omega: float, lo: float, hi: float, tol: float, grid: int
    ) -> tuple[float, float, float, float, float, float, int]: ...

    def profile_phase_gain(
        self,
        ybar: _F,
        ydot: _F,
        amplitude: float,
        omega: float,
        beta: float,
        gamma: float,
        mu: float,
        grid: int,
    ) -> tuple[float, float, float]: ...

    def refine(
        self,
        ybars: Sequence[_F],
        amplitudes: Sequence[float] | _F,
        weights: Sequence[float] | _F,
        beta: float,
        gamma: float,
        mu: float,
        gains: Sequence[float] | _F,
        phases: Sequence[float] | _F,
        max_iter: int = 200,
        substeps: int = 4,
        ftol: float = 1e-12,
        xtol: float = 1e-10,
        mu_lo: float = 1.0,
        mu_hi: float = ...,
    ) -> tuple[_F, float, int, bool, _F, list[_F], str, list[str]]: ...


class MultiStart(Protocol):
    """Many refinements from many starts at once (``rust/multistart.rs``); only the Rust core has it."""

    def refine_many(
        self,
        ybars: Sequence[_F],
        amplitudes: Sequence[float] | _F,
        weights: Sequence[float] | _F,
        starts: Sequence[Sequence[float] | _F],
        max_iter: int = 200,
        substeps: int = 4,
        ftol: float = 1e-12,
        xtol: float = 1e-10,
        mu_lo: float = 1.0,
        mu_hi: float = ...,
        abandon_after: int = 0,
        abandon_ratio: float = 10.0,
        threads: int = 0,
    ) -> list[tuple[_F, float, int, bool, bool] | None]: ...


class Augmented(Protocol):
    """The augmented model (design.md 9.1-9.3, ``rust/terms.rs``): its steady output and its joint fit."""

    def augmented_output(
        self,
        ybar_len: int,
        amplitude: float,
        frequency: float,
        grid_phase: float,
        terms: Sequence[str],
        shared: _F,
        gain: float,
        phase: float,
        substeps: int,
        waveform: _F | None = None,
        input_shape: _F | None = None,
        coulomb_smoothing: float = 0.01,
    ) -> tuple[_F, _F, _F]: ...

    def augmented_refine(
        self,
        ybars: Sequence[_F],
        amplitudes: Sequence[float] | _F,
        frequencies: Sequence[float] | _F,
        grid_phases: Sequence[float] | _F,
        weights: Sequence[float] | _F,
        terms: Sequence[str],
        shared0: Sequence[float] | _F,
        gains0: Sequence[float] | _F,
        phases0: Sequence[float] | _F,
        *,
        max_iter: int = 200,
        substeps: int = 4,
        mu_lo: float = 1.0,
        mu_hi: float = ...,
        waveforms: Sequence[_F] | None = None,
        experiment_substeps: Sequence[int] | None = None,
        input_shapes: Sequence[_F] | None = None,
        coulomb_smoothing: float = 0.01,
        stall_window: int = 0,
        stall_rtol: float = 0.0,
        step_rtol: float = 0.0,
    ) -> tuple[_F, _F, _F, float, int, bool, _F, list[_F], str, list[str]]: ...


class Lab(Protocol):
    """The fused kernels of the lab preprocessing (``rust/lab.rs``, ``rust/lab/``), issue #8.

    Each returns ``None`` where it has no answer, and the caller in ``signal/`` then runs its NumPy path
    (the reference ``tests/test_fastlab.py`` holds the kernels to): always on the NumPy backend, and on the
    Rust one when a Gram matrix is too ill-conditioned for the normal equations (``cond > 1e4``).
    """

    def well_conditioned(self, gram: _F) -> Optional[bool]:
        """``cond(D^-1/2 G D^-1/2) <= 1e4`` (and positive definite), the check of the fused fit."""

    def moment_fit(
        self, theta: _F, y: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        """``(R, Q^T y, residual^2)`` of the K-harmonic fit (``signal._harmonic_ls._moment_fit``).  With
        ``omega``, ``theta`` holds times and the phases are ``omega theta``."""

    def harmonic_lsq(
        self, theta: _F, x: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        """``(coef, R, residual^2)`` of the K-harmonic least-squares fit (``R`` the Cholesky factor of the
        Gram matrix: the QR path's R up to the signs of its rows).  ``omega`` as :meth:`moment_fit`."""

    def nls(
        self, tau: _F, x: _F, omega0: float, dt: float, k: int
    ) -> Optional[tuple[float, _F, float, float]]:
        """``(omega, coef, rss, se)`` of ``signal._sine._nls`` (the same Gauss-Newton on omega)."""

    def unscaled_variances(self, r: _F) -> Optional[_F]:
        """Diagonal of ``(R^T R)^-1`` for upper triangular ``R``."""

    def harmonic_rss(self, tau: _F, x: _F, coef: _F, omega: float) -> Optional[float]:
        """``|x - series(coef)|^2`` at phases ``omega tau``."""

    def window_fits(
        self, tau: _F, u: _F, y: _F, starts: Sequence[int], stops: Sequence[int], k: int, omega: float
    ) -> Optional[tuple[_F, _F]]:
        """Per window ``[start, stop)``: the coefficients of ``u`` and ``y`` and the two residual sums (a
        row of NaN where the window's Gram matrix is refused)."""

    def spectral_peak(
        self, x: _F, nfft: int, lo: int, hi: int, band_lo: int, band_hi: int, peak_min: float
    ) -> Optional[tuple[int, float, float, float]]:
        """The peak bin of the detrended, Hann-windowed, padded spectrum and its two neighbours."""


class _RustLab:
    """:class:`Lab` on the Rust kernels (contiguous float64 in, ``None`` when ill-conditioned)."""

    def well_conditioned(self, gram: _F) -> Optional[bool]:
        from . import _core

        g = np.ascontiguousarray(gram, dtype=np.float64)
        return _core.gram_well_conditioned(g.ravel(), g.shape[0])

    def _fit(self, theta: _F, y: _F, kmax: int, omega: Optional[float]) -> Optional[tuple[_F, _F, _F, float]]:
        from . import _core

        th = np.ascontiguousarray(theta, dtype=np.float64)
        yy = np.ascontiguousarray(y, dtype=np.float64)
        out = _core.harmonic_fit(th, yy, kmax, omega)
        if out is None:
            return None
        coef, r, qty, rss = out
        m = coef.size
        return coef, r.reshape(m, m), qty, rss

    def moment_fit(
        self, theta: _F, y: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        out = self._fit(theta, y, kmax, omega)
        return None if out is None else (out[1], out[2], out[3])

    def harmonic_lsq(
        self, theta: _F, x: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        out = self._fit(theta, x, kmax, omega)
        return None if out is None else (out[0], out[1], out[3])

    def nls(
        self, tau: _F, x: _F, omega0: float, dt: float, k: int
    ) -> Optional[tuple[float, _F, float, float]]:
        from . import _core

        tt = np.ascontiguousarray(tau, dtype=np.float64)
        xx = np.ascontiguousarray(x, dtype=np.float64)
        return _core.harmonic_nls(tt, xx, float(omega0), float(dt), int(k))

    def unscaled_variances(self, r: _F) -> Optional[_F]:
        from . import _core

        # R^-1 in one Rust call (m^3/6 multiply-adds) instead of a triangular solve against I (issue #8).
        return _core.unscaled_variances(np.ascontiguousarray(r, dtype=np.float64).ravel(), r.shape[0])

    def harmonic_rss(self, tau: _F, x: _F, coef: _F, omega: float) -> Optional[float]:
        from . import _core

        tt, xx = np.ascontiguousarray(tau), np.ascontiguousarray(x)
        return float(_core.harmonic_rss(tt, xx, np.ascontiguousarray(coef), omega))

    def window_fits(
        self, tau: _F, u: _F, y: _F, starts: Sequence[int], stops: Sequence[int], k: int, omega: float
    ) -> Optional[tuple[_F, _F]]:
        from . import _core

        c = np.ascontiguousarray
        return _core.window_fits(c(tau), c(u), c(y), starts, stops, k, omega)

    def spectral_peak(
        self, x: _F, nfft: int, lo: int, hi: int, band_lo: int, band_hi: int, peak_min: float
    ) -> Optional[tuple[int, float, float, float]]:
        from . import _core

        return _core.spectral_peak(
            np.ascontiguousarray(x, dtype=np.float64), nfft, lo, hi, band_lo, band_hi, peak_min
        )


class _NumpyLab:
    """:class:`Lab` of the NumPy backend: no fused kernel, so ``signal/`` runs its NumPy paths throughout."""

    def well_conditioned(self, gram: _F) -> Optional[bool]:
        return None

    def moment_fit(
        self, theta: _F, y: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        return None

    def harmonic_lsq(
        self, theta: _F, x: _F, kmax: int, omega: Optional[float] = None
    ) -> Optional[tuple[_F, _F, float]]:
        return None

    def nls(
        self, tau: _F, x: _F, omega0: float, dt: float, k: int
    ) -> Optional[tuple[float, _F, float, float]]:
        return None

    def unscaled_variances(self, r: _F) -> Optional[_F]:
        return None

    def harmonic_rss(self, tau: _F, x: _F, coef: _F, omega: float) -> Optional[float]:
        return None

    def window_fits(
        self, tau: _F, u: _F, y: _F, starts: Sequence[int], stops: Sequence[int], k: int, omega: float
    ) -> Optional[tuple[_F, _F]]:
        return None

    def spectral_peak(
        self, x: _F, nfft: int, lo: int, hi: int, band_lo: int, band_hi: int, peak_min: float
    ) -> Optional[tuple[int, float, float, float]]:
        return None


class Compensate(Protocol):
    """The feedforward compensation kernels (``rust/compensate.rs``; NumPy: :mod:`.reference.compensate`)."""

    def invert_path(
        self, w: _F, alpha: float, beta: float, gamma: float, mu: float, delta: float, w0: float, x0: float
    ) -> _F: ...

    def rate_limit(self, target: _F, step: float, start: float) -> _F: ...


# --- time-domain identification (issue #20): the Wiener cascade with its exact Jacobian -------------------
class TimeDomain(Protocol):
    """``rust/bindings/timedomain.rs`` and :mod:`bouc_wen_id.reference.timedomain`."""

    def timedomain_sensitivities(
        self, m: int, n: int, theta: Sequence[float] | _F, u: _F, dt: float, substeps: int
    ) -> tuple[_F, NDArray[np.float64]]:
        """``(y, J)``: the cascade ``[b_0..b_m, a_1..a_n, tau, beta, gamma, mu, w0]`` on the samples ``u``
        from rest, and ``dy/dtheta`` exact for the discrete RK4 map (``(len(u), m + n + 6)``)."""


@cache
def _timedomain(name: Backend) -> TimeDomain:
    if name == "rust":
        from . import _core

        return _core
    from .reference import timedomain

    return timedomain


@dataclass(frozen=True)
class Parts:
    """The numerics of one backend, one typed part per domain (module docstring)."""

    name: Backend
    paper: Paper
    augmented: Augmented
    lab: Lab
    multistart: Optional[MultiStart]
    compensate: Compensate

    @property
    def timedomain(self) -> TimeDomain:
        """The time-domain kernels (issue #20)."""
        return _timedomain(self.name)


def _check_name(name: object) -> Backend:
    if name == "rust":
        return "rust"
    if name == "numpy":
        return "numpy"
    raise InvalidParameterError(f"backend must be 'rust' or 'numpy', got {name!r}")


@cache
def _parts(name: Backend) -> Parts:
    if name == "rust":
        from . import _core

        return Parts("rust", _core, _core, _RustLab(), _core, compensate=_core)
    from . import reference
    from .reference import augmented
    from .reference import compensate as reference_compensate

    return Parts("numpy", reference, augmented, _NumpyLab(), None, compensate=reference_compensate)


def get_backend(name: object) -> Parts:
    """The numerics of ``name`` ("rust" or "numpy"); anything else is :class:`InvalidParameterError`.

    Both backends expose the same routines with the same signatures and the same named errors.
    """
    return _parts(_check_name(name))


#: The backend whose lab kernels ``signal/`` uses (:func:`selected`); the Rust one unless an entry point
#: asked for another.
_LAB: ContextVar[Backend] = ContextVar("bouc_wen_id_lab_backend", default="rust")


def current_lab() -> Lab:
    """The lab kernels of the backend in force (:func:`selected`)."""
    return _parts(_LAB.get()).lab


@contextmanager
def selected(name: object) -> Iterator[Parts]:
    """Run the block with ``name``'s lab kernels in force (for the current thread or task only); yields the
    backend's parts.  A public entry point with ``backend=`` wraps its lab preprocessing in this."""
    parts = get_backend(name)
    token = _LAB.set(parts.name)
    try:
        yield parts
    finally:
        _LAB.reset(token)


def push_budget(max_samples: int, max_steps: int, max_bytes: int) -> None:
    """Write the work limits into the Rust core (the NumPy reference is held to them in Python)."""
    try:
        from . import _core
    except ImportError:  # pragma: no cover - a build without the extension
        return
    _core.set_budget(max_samples, max_steps, max_bytes)


# --- Bouc-Wen in feedback (issue #20; rust/feedback.rs, reference/feedback.py) ---------------------------


class Feedback(Protocol):
    """The feedback system ``m ydd + c yd + k y + z = u`` with Bouc-Wen ``z`` (``rust/feedback.rs``): RK4
    simulation with the forward sensitivities w.r.t. ``[m, c, k, alpha, beta*gamma, beta*delta, nu, x0]``,
    and the periodic steady state under a sine (Newton shooting with the monodromy matrix)."""

    def feedback_simulate(
        self,
        theta: Sequence[float] | _F,
        x0: Sequence[float] | _F,
        u: _F,
        dt: float,
        upsample: int,
        substeps: int,
        sensitivities: bool = True,
    ) -> tuple[_F, _F, _F]: ...

    def feedback_periodic(
        self,
        theta: Sequence[float] | _F,
        amplitude: float,
        omega: float,
        samples: int,
        substeps: int,
        settle_periods: int = 2,
        max_iter: int = 50,
        tol: float = 1e-10,
    ) -> tuple[_F, _F, _F, int]: ...


def feedback_part(name: object) -> Feedback:
    """The feedback kernels of backend ``name`` ("rust" or "numpy"; anything else is
    :class:`InvalidParameterError`)."""
    if _check_name(name) == "rust":
        from . import _core

        return _core
    from .reference import feedback

    return feedback


if TYPE_CHECKING:  # pragma: no cover - both backends implement the feedback part
    from . import _core as _core_fb
    from .reference import feedback as _reference_feedback

    _RUST_FEEDBACK: Feedback = _core_fb
    _NUMPY_FEEDBACK: Feedback = _reference_feedback


if TYPE_CHECKING:  # pragma: no cover - the static check that both backends implement every part
    from . import _core, reference
    from .reference import augmented as _reference_augmented

    _RUST_PAPER: Paper = _core
    _NUMPY_PAPER: Paper = reference
    _RUST_AUGMENTED: Augmented = _core
    _NUMPY_AUGMENTED: Augmented = _reference_augmented
    _RUST_MULTISTART: MultiStart = _core
    _RUST_LAB: Lab = _RustLab()
    _NUMPY_LAB: Lab = _NumpyLab()
    from .reference import compensate as _reference_compensate

    _RUST_COMPENSATE: Compensate = _core
    _NUMPY_COMPENSATE: Compensate = _reference_compensate
    # time-domain identification (issue #20)
    from .reference import timedomain as _reference_timedomain

    _RUST_TIMEDOMAIN: TimeDomain = _core
    _NUMPY_TIMEDOMAIN: TimeDomain = _reference_timedomain

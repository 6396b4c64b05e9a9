"""Type stubs of the Rust extension module (see rust/bindings/ and docs/design.md).

The block marked "test-only" at the end (``rust/bindings/testing.rs``) exists only so that the tests can
hold the lab kernels to their references one by one: no module of the package calls it.
"""

from collections.abc import Mapping, Sequence
from typing import Callable, overload

import numpy as np
from numpy.typing import NDArray

__version__: str
__all__ = [
    "__version__",
    "simulate_sine",
    "simulate_sampled",
    "feedback_simulate",
    "feedback_periodic",
    "periodic_average",
    "phase_from_max",
    "spectral_derivative",
    "sls_regressor",
    "solve_normal",
    "sls_theta",
    "golden_section",
    "sls_search",
    "gain_estimate",
    "steady_loop",
    "path_loop",
    "path_loop_distorted",
    "profile_phase_sls",
    "profile_phase_gain",
    "refine",
    "augmented_output",
    "augmented_refine",
    "get_budget",
    "set_budget",
    "refine_many",
    "harmonic_rss",
    "harmonic_fit",
    "harmonic_nls",
    "gram_well_conditioned",
    "unscaled_variances",
    "window_fits",
    "spectral_peak",
    "timedomain_sensitivities",  # issue #20 (rust/bindings/timedomain.rs)
    # test-only (rust/bindings/testing.rs): not called by the package
    "harmonic_moments",
    "harmonic_series",
    "harmonic_gauss_newton",
    "cholesky_upper",
    "padded_spectrum",
    # feedforward compensation (rust/bindings/compensate.rs)
    "invert_path",
    "rate_limit",
]

_F = NDArray[np.float64]

@overload
def simulate_sine(
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
def periodic_average(y: _F, samples_per_period: int, settle_periods: int, periods: int) -> _F: ...
def phase_from_max(ybar: _F) -> float: ...
def spectral_derivative(ybar: _F, omega: float, harmonics: int) -> _F: ...
def sls_regressor(ybar: _F, ydot: _F, amplitude: float, omega: float, phi: float, nu: float) -> _F: ...
def solve_normal(m: _F, r: _F) -> tuple[_F, float]: ...
def sls_theta(
    ybar: _F, ydot: _F, amplitude: float, omega: float, phi: float, nu: float
) -> tuple[_F, float]: ...
def golden_section(
    func: Callable[[float], float], lo: float, hi: float, tol: float, max_iter: int = 200
) -> tuple[float, float, int]: ...
def sls_search(
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
    ybar: _F, ydot: _F, amplitude: float, omega: float, phi: float, beta: float, gamma: float, mu: float
) -> float: ...
def steady_loop(
    amplitude: float, beta: float, gamma: float, mu: float, phi: float, samples_per_period: int, substeps: int
) -> tuple[_F, _F, float, int]: ...
def path_loop(
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
    ybar: _F, ydot: _F, amplitude: float, omega: float, lo: float, hi: float, tol: float, grid: int
) -> tuple[float, float, float, float, float, float, int]: ...
def profile_phase_gain(
    ybar: _F, ydot: _F, amplitude: float, omega: float, beta: float, gamma: float, mu: float, grid: int
) -> tuple[float, float, float]: ...
def refine(
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
def augmented_output(
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
    coulomb_smoothing: float = ...,
) -> tuple[_F, _F, _F]: ...

# Bouc-Wen in feedback (rust/bindings/feedback.rs, issue #20)
def feedback_simulate(
    theta: Sequence[float] | _F,
    x0: Sequence[float] | _F,
    u: _F,
    dt: float,
    upsample: int,
    substeps: int,
    sensitivities: bool = True,
) -> tuple[_F, _F, _F]: ...
def feedback_periodic(
    theta: Sequence[float] | _F,
    amplitude: float,
    omega: float,
    samples: int,
    substeps: int,
    settle_periods: int = 2,
    max_iter: int = 50,
    tol: float = 1e-10,
) -> tuple[_F, _F, _F, int]: ...
def augmented_refine(
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
    coulomb_smoothing: float = ...,
    stall_window: int = 0,
    stall_rtol: float = 0.0,
    step_rtol: float = 0.0,
) -> tuple[_F, _F, _F, float, int, bool, _F, list[_F], str, list[str]]: ...
def get_budget() -> tuple[int, int, int]: ...
def set_budget(max_samples: int, max_steps: int, max_bytes: int) -> tuple[int, int, int]: ...
def refine_many(
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
def harmonic_rss(theta: _F, y: _F, coef: _F, omega: float | None = None) -> float: ...
def harmonic_fit(
    theta: _F, y: _F, kmax: int, omega: float | None = None
) -> tuple[_F, _F, _F, float] | None: ...
def harmonic_nls(
    tau: _F, x: _F, omega0: float, dt: float, k: int
) -> tuple[float, _F, float, float] | None: ...
def gram_well_conditioned(gram: _F, m: int) -> bool: ...
def unscaled_variances(r: _F, m: int) -> _F: ...
def window_fits(
    theta: _F,
    u: _F,
    y: _F,
    starts: Sequence[int],
    stops: Sequence[int],
    k: int,
    omega: float | None = None,
) -> tuple[_F, _F]: ...
def spectral_peak(
    x: _F, nfft: int, lo: int, hi: int, band_lo: int, band_hi: int, peak_min: float
) -> tuple[int, float, float, float]: ...

# ---- time-domain identification (rust/bindings/timedomain.rs, issue #20) -----------------------------

def timedomain_sensitivities(
    m: int, n: int, theta: Sequence[float] | _F, u: _F, dt: float, substeps: int
) -> tuple[_F, NDArray[np.float64]]: ...

# ---- test-only (rust/bindings/testing.rs) -------------------------------------------------------
# Kernels exported only so that tests/test_fastlab.py can check each one against its NumPy reference; the
# package calls the fused bindings above instead. Not part of the supported surface: they may change.

def harmonic_moments(theta: _F, y: _F, kmax: int) -> tuple[_F, _F, _F, _F]: ...
def harmonic_series(theta: _F, coef: _F) -> _F: ...
def harmonic_gauss_newton(theta: _F, tau: _F, x: _F, coef: _F) -> tuple[float, float, float, _F]: ...
def cholesky_upper(gram: _F, m: int) -> _F: ...
def padded_spectrum(x: _F, nfft: int) -> _F: ...

# ---- feedforward compensation (rust/bindings/compensate.rs, issue 21) ----------------------------------

def invert_path(
    w: _F, alpha: float, beta: float, gamma: float, mu: float, delta: float, w0: float, x0: float
) -> _F: ...
def rate_limit(target: _F, step: float, start: float) -> _F: ...

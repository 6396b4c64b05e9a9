"""Type stubs of the Rust extension module (see rust/python.rs and docs/design.md)."""

from typing import Callable

import numpy as np
from numpy.typing import NDArray

__version__: str

_F = NDArray[np.float64]

def simulate_sine(
    num: _F,
    den: _F,
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
) -> tuple[_F, _F]: ...
def simulate_sampled(
    num: _F,
    den: _F,
    delay: float,
    alpha: float,
    beta: float,
    gamma: float,
    mu: float,
    w0: float,
    u: _F,
    dt: float,
    substeps: int,
) -> tuple[_F, _F]: ...
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

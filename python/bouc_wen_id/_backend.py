"""Choose the implementation of the core routines: the Rust extension or the NumPy reference.

:class:`Core` is the typed boundary between the package and its numerics: mypy checks both the Rust stub
(``_core.pyi``) and :mod:`bouc_wen_id.reference` against it, so the two cannot drift apart in signature.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Callable, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from .errors import InvalidParameterError

Backend = Literal["rust", "numpy"]

__all__ = ["Backend", "Core", "get_backend"]

_F = NDArray[np.float64]


class Core(Protocol):
    """The core routines, with the Rust extension's signatures (the reference accepts at least as much).

    Arrays are 1-D float64 (``_F``; the Rust side needs them C-contiguous); polynomial coefficients and
    per-experiment vectors may also be sequences of floats.  Shapes and units: ``rust/python.rs``.
    """

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
    ) -> tuple[_F, _F]: ...

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
    ) -> tuple[_F, _F]: ...

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
    ) -> tuple[_F, float, int, bool, _F, list[_F]]: ...


def get_backend(name: str) -> Core:
    """Return the module holding the core routines for ``name`` ("rust" or "numpy").

    Both modules expose the same functions with the same signatures and errors.
    """
    if name == "rust":
        from . import _core

        return _core
    if name == "numpy":
        from . import reference

        return reference
    raise InvalidParameterError(f"backend must be 'rust' or 'numpy', got {name!r}")


if TYPE_CHECKING:  # pragma: no cover - the static check that both backends implement Core
    from . import _core, reference

    _RUST: Core = _core
    _NUMPY: Core = reference

"""NumPy reference implementation of every core routine: the oracle the parity tests hold the Rust core to.

Readable, unoptimised, and written line by line from ``docs/design.md`` and the seed paper's equations.  It
exists to hold the Rust core (``bouc_wen_id._core``) to account: the parity tests call both on the same
seeded random inputs and compare.  Signatures match the ``_core`` functions one for one, and errors are the
same named exceptions from :mod:`bouc_wen_id.errors`.

Each module checks the Rust file of the same name (``reference/path_loop.py`` holds ``rust/path_loop.rs`` to
account, ``reference/with_terms.py`` ``rust/simulate/with_terms.rs``); the oracle imports only
:mod:`bouc_wen_id.errors`, :mod:`bouc_wen_id.validation` and itself.  Production code reaches it only through
``bouc_wen_id._backend`` (``identify(..., backend="numpy")`` runs the whole identification on it), and it is
slow: the RK4 loops are plain Python.

=================  ==============================  =====================================================
module             checks                          routines
=================  ==============================  =====================================================
``linear``         ``rust/linear.rs``              ``realize``
``simulate``       ``rust/simulate.rs``            ``simulate_sine``, ``simulate_sampled``
``with_terms``     ``rust/simulate/with_terms.rs`` the simulation with physical terms (design.md 9.4)
``on_x``           ``rust/simulate/on_x.rs``       the simulation's mechanical terms on x (design.md 9.4)
``average``        ``rust/average.rs``             ``periodic_average``
``estimate``       ``rust/estimate.rs``            ``phase_from_max``, ``gain_estimate``, ...
``solve``          ``rust/solve.rs``               ``sls_regressor``, ``solve_normal``, ``sls_theta``, ...
``steady``         ``rust/steady.rs``              ``steady_loop``
``path_loop``      ``rust/path_loop.rs``           ``path_loop``, ``path_loop_distorted``
``profile``        ``rust/profile.rs``             ``profile_phase_sls``, ``profile_phase_gain``
``refine``         ``rust/refine.rs``              ``levenberg_marquardt``, ``refine``
``terms``          ``rust/terms.rs``               ``augmented_output``, ``augmented_refine``
``compensate``     ``rust/compensate.rs``          ``invert_path``, ``rate_limit`` (feedforward, issue 21)
``timedomain``     ``rust/timedomain.rs``          ``timedomain_sensitivities`` (issue #20; via ``_backend``)
=================  ==============================  =====================================================

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

from .augmented import augmented_output, augmented_refine
from .average import periodic_average
from .estimate import gain_estimate, max_harmonics, phase_from_max, spectral_derivative
from .linear import realize, routh_hurwitz_stable
from .path_loop import path_loop, path_loop_distorted
from .profile import profile_phase_gain, profile_phase_sls
from .refine import levenberg_marquardt, refine
from .simulate import simulate_sampled, simulate_sine
from .solve import golden_section, sls_regressor, sls_search, sls_theta, solve_normal
from .steady import steady_loop

__all__ = [
    "realize",
    "routh_hurwitz_stable",
    "simulate_sine",
    "simulate_sampled",
    "periodic_average",
    "phase_from_max",
    "max_harmonics",
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
    "levenberg_marquardt",
    "refine",
    "augmented_output",
    "augmented_refine",
]

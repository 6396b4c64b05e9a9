"""Every argument of every binding of ``bouc_wen_id._core`` goes through the one converter of
``rust/bindings/convert.rs``: a wrong type, a wrong dtype or an integer beyond 64 bits is the library's
``InvalidParameterError`` (a ``ValueError``), never pyo3's ``TypeError`` or ``OverflowError``."""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.errors import InvalidParameterError

_A = np.linspace(0.1, 1.0, 16)  # any 1-D float64 array
_M = np.eye(3)
_PLANT = ([1.0], [1.0, 1.0], 0.0, 1.0, 1.0, 0.2, 1.5, 0.0)  # num, den, delay, alpha, beta, gamma, mu, w0

#: Well-typed arguments (not necessarily admissible values: the converter runs before any check) of each
#: binding, positional then keyword-only.
_CALLS: dict[str, tuple[tuple[Any, ...], dict[str, Any]]] = {
    "simulate_sine": ((*_PLANT, 1.0, 2.0, 0.05, 50, 1), {"terms": {}}),
    "simulate_sampled": ((*_PLANT, _A, 0.05, 1), {"terms": {}}),
    "periodic_average": ((_A, 4, 1, 2), {}),
    "phase_from_max": ((_A,), {}),
    "spectral_derivative": ((_A, 2.0, 3), {}),
    "sls_regressor": ((_A, _A, 1.0, 2.0, 0.3, 1.5), {}),
    "solve_normal": ((_M, _A[:3]), {}),
    "sls_theta": ((_A, _A, 1.0, 2.0, 0.3, 1.5), {}),
    "golden_section": ((abs, 0.0, 1.0, 1e-6, 10), {}),
    "sls_search": ((_A, _A, 1.0, 2.0, 0.3, 1.0, 3.0, 1e-6, 10), {}),
    "gain_estimate": ((_A, _A, 1.0, 2.0, 0.3, 1.0, 0.5, 1.5), {}),
    "steady_loop": ((1.0, 1.0, 0.5, 1.5, 0.3, 16, 2), {}),
    "path_loop": ((1.0, 1.0, 0.5, 1.5, 0.1, 0.1, 0.3, 16, 2), {}),
    "path_loop_distorted": ((1.0, 1.0, 0.5, 1.5, 0.1, 0.1, 0.3, 0.0, _A[:2], 16, 2), {}),
    "profile_phase_sls": ((_A, _A, 1.0, 2.0, 1.0, 3.0, 1e-6, 8), {}),
    "profile_phase_gain": ((_A, _A, 1.0, 2.0, 1.0, 0.5, 1.5, 8), {}),
    "refine": (([_A], [1.0], [1.0], 1.0, 0.5, 1.5, [1.0], [0.0], 10, 2, 1e-12, 1e-10, 1.0, 10.0), {}),
    "augmented_output": ((16, 1.0, 2.0, 0.0, ["offset"], _A[:4], 1.0, 0.0, 2, _A[:2]), {}),
    "augmented_refine": (
        ([_A], [1.0], [2.0], [0.0], [1.0], ["offset"], [1.0, 0.5, 1.5, 0.0], [1.0], [0.0]),
        {"max_iter": 10, "substeps": 2, "mu_lo": 1.0, "mu_hi": 10.0, "waveforms": [_A[:2]]},
    ),
    "set_budget": (_core.get_budget(), {}),  # the limits in force: nothing changes should one pass
    "refine_many": (
        ([_A], [1.0], [1.0], [[1.0, 0.5, 1.5, 1.0, 0.0]], 10, 2, 1e-12, 1e-10, 1.0, 10.0, 0, 10.0, 1),
        {},
    ),
    "harmonic_rss": ((_A, _A, _A[:3], 2.0), {}),
    "harmonic_fit": ((_A, _A, 1, 2.0), {}),
    "harmonic_nls": ((_A, _A, 2.0, 0.01, 1), {}),
    "gram_well_conditioned": ((_A[:9], 3), {}),
    "unscaled_variances": ((_A[:9], 3), {}),
    "window_fits": ((_A, _A, _A, [0], [16], 1, 2.0), {}),
    "spectral_peak": ((_A, 32, 1, 10, -1, -1, 0.1), {}),
    # issue 21: feedforward compensation (rust/bindings/compensate.rs)
    "invert_path": ((_A, 1.0, 1.0, 0.5, 1.5, 0.0, 0.0, 0.0), {}),
    "rate_limit": ((_A, 0.1, 0.0), {}),
    # issue 20: Bouc-Wen in feedback (bindings/feedback.rs) and the Wiener cascade in time (timedomain.rs)
    "feedback_simulate": (
        ([2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0], [0.0, 0.0, 0.0], _A, 1e-3, 1, 1, False),
        {},
    ),
    "feedback_periodic": (([2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0], 1.0, 2.0, 16, 1, 1, 2, 1e-8), {}),
    "timedomain_sensitivities": ((0, 1, [1.0, 1.0, 0.0, 1.0, 0.5, 1.5, 0.0], _A, 0.05, 1), {}),
    # test-only (rust/bindings/testing.rs)
    "harmonic_moments": ((_A, _A, 2), {}),
    "harmonic_series": ((_A, _A[:3]), {}),
    "harmonic_gauss_newton": ((_A, _A, _A, _A[:3]), {}),
    "cholesky_upper": ((_A[:9], 3), {}),
    "padded_spectrum": ((_A, 32), {}),
}


def _bindings() -> list[str]:
    return sorted(n for n, f in vars(_core).items() if not n.startswith("_") and callable(f))


def test_every_binding_is_listed() -> None:
    # get_budget takes no argument; everything else must be exercised below.
    assert set(_bindings()) == set(_CALLS) | {"get_budget"}


def _cases() -> list[tuple[str, str, Any]]:
    cases: list[tuple[str, str, Any]] = []
    for name, (args, kwargs) in _CALLS.items():
        params = list(inspect.signature(getattr(_core, name)).parameters)
        for i in range(len(args)):
            cases.append((name, params[i], "not a value"))
            if isinstance(args[i], int) and not isinstance(args[i], bool):
                cases.append((name, params[i], 2**70))
        for key in kwargs:
            cases.append((name, key, "not a value"))
        # The arrays: a float32 array where a float64 one is taken.
        for i, a in enumerate(args):
            if isinstance(a, np.ndarray) and a.ndim == 1:
                cases.append((name, params[i], a.astype(np.float32)))
    return cases


@pytest.mark.parametrize(("name", "param", "bad"), _cases(), ids=lambda v: v if isinstance(v, str) else None)
def test_a_wrong_argument_is_invalid_parameter_error(name: str, param: str, bad: Any) -> None:
    args, kwargs = _CALLS[name]
    params = list(inspect.signature(getattr(_core, name)).parameters)
    call_args = list(args)
    call_kwargs = dict(kwargs)
    if param in call_kwargs:
        call_kwargs[param] = bad
    else:
        call_args[params.index(param)] = bad
    with pytest.raises(InvalidParameterError):
        getattr(_core, name)(*call_args, **call_kwargs)


def test_a_non_callable_objective_is_named() -> None:
    with pytest.raises(InvalidParameterError, match="callable"):
        _core.golden_section(3.0, 0.0, 1.0, 1e-6)  # type: ignore[arg-type]


def test_a_simulation_with_two_unknown_terms_names_the_same_one_every_time() -> None:
    """The terms reach the core as a map; its order is the names' (sorted), not a hash's, so the error for
    two unknown names is the same on every call (it named either one, call by call)."""
    messages = set()
    for _ in range(40):
        with pytest.raises(InvalidParameterError, match="unknown term") as err:
            _core.simulate_sine(*_PLANT, 1.0, 2.0, 0.05, 50, 1, terms={"zz_nope": 1.0, "aa_nope": 1.0})
        messages.add(str(err.value))
    assert len(messages) == 1
    assert "aa_nope" in messages.pop()

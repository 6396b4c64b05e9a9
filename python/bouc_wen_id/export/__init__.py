"""Export of the whole model (issue #21 item 2), plain or with terms, in physical units.

* :func:`to_nlsys`: a python-control nonlinear I/O system (``control.nlsys``); :func:`rk4_response` runs
  it with the simulator's own RK4 step and input interpolation (:class:`SampledInput`), and reproduces
  :func:`bouc_wen_id.simulate_input` to rounding (but for play and sensor lag, whose simulator schemes are
  not RK4 steps of an ODE: there to the integration error).
* :func:`to_c`: a self-contained C99 source, one function, fixed-step RK4, no allocation; it reproduces the
  simulator for every term it simulates.
* :func:`model_to_json` / :func:`save_model` and :func:`load_model` / :func:`model_from_json`: the model as
  a versioned JSON document, read back exactly.

One module per job: ``_model`` (the plant as the simulator integrates it), ``_input``, ``_nlsys``, ``_c``,
``_json``.
"""

from __future__ import annotations

from ._c import to_c
from ._input import SampledInput
from ._json import MODEL_FORMAT, MODEL_VERSION, load_model, model_from_json, model_to_json, save_model
from ._nlsys import initial_state, input_signals, rk4_response, to_nlsys

__all__ = [
    "MODEL_FORMAT",
    "MODEL_VERSION",
    "model_to_json",
    "model_from_json",
    "save_model",
    "load_model",
    "to_c",
    "SampledInput",
    "to_nlsys",
    "input_signals",
    "initial_state",
    "rk4_response",
]

"""Export of the whole model (issue #21 item 2), plain or with terms, in physical units.

* :func:`to_nlsys`: a python-control nonlinear I/O system (``control.nlsys``), every term at every place.
  Continuous (default): :func:`rk4_response` runs it with the simulator's own RK4 step and input
  interpolation (:class:`SampledInput`) and reproduces :func:`bouc_wen_id.simulate_input` to rounding (but
  for play and sensor lag, whose simulator schemes are not RK4 steps of an ODE: there to the integration
  error). Discrete (``dt=`` the sample step): one update is one step of the simulator's own scheme, so
  :func:`discrete_response` (python-control's ``input_output_response`` on :func:`stage_inputs`) reproduces
  it to rounding for every term, play and lag included.
* :func:`to_c`: a self-contained C99 source, one function, fixed-step RK4, no allocation; it reproduces the
  simulator for every term at every place.
* :func:`model_to_json` / :func:`save_model` and :func:`load_model` / :func:`model_from_json`: the model as
  a versioned JSON document, read back exactly.

The measured-input distortion is written to JSON but refused by the simulators' exporters
(:class:`UnsupportedTermError`), as ``simulate_input`` refuses it: it stands for one sine experiment's own
harmonics, not a map of an arbitrary input. A registry term with no exporter is refused the same way.

One module per job: ``_model`` (the plant as the simulator integrates it), ``_input``, ``_rhs`` (the
simulator's right-hand side in Python), ``_nlsys``, ``_discrete``, ``_c``, ``_json``.
"""

from __future__ import annotations

from ._c import to_c
from ._discrete import discrete_response, stage_inputs
from ._input import SampledInput
from ._json import MODEL_FORMAT, MODEL_VERSION, load_model, model_from_json, model_to_json, save_model
from ._model import EXPORTED, UnsupportedTermError
from ._nlsys import input_signals, rk4_response, to_nlsys
from ._rhs import initial_state, peak_speeds

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
    "peak_speeds",
    "stage_inputs",
    "discrete_response",
    "EXPORTED",
    "UnsupportedTermError",
]

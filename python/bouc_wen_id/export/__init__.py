"""Export of the whole identified model (issue #21 item 2): python-control, C, JSON."""

from __future__ import annotations

from ._c import to_c
from ._input import SampledInput
from ._nlsys import initial_state, input_signals, rk4_response, to_nlsys

__all__ = ["to_c", "SampledInput", "to_nlsys", "input_signals", "initial_state", "rk4_response"]

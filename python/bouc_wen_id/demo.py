"""The built-in demonstration plant and plan used by ``bouc-wen-id demo``."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .model import BoucWen, SinePlan, TransferFunction, WienerPlant
from .terms import Viscous

__all__ = ["demo_plant", "demo_plan", "design_amplitudes", "demo_hidden_plant", "DEMO_HIDDEN"]

#: Demo frequencies (rad/s): below, at and above the resonance at 5 rad/s.
DEMO_FREQUENCIES = (1.0, 2.0, 3.0, 4.0, 5.0, 6.5, 8.0)
#: Target amplitude of the alpha-normalised x, in units of the Bouc-Wen bound w_0 = 1: the loops saturate
#: but are not flat.  Deep saturation (U|G| >> w_0) makes the paper's sgn(d ybar/dt) regressor unreliable:
#: the averaged output is nearly constant there and the sign of its derivative is decided by ringing.
DEMO_X_AMPLITUDE = 1.2


def design_amplitudes(
    plant: WienerPlant, frequencies: Sequence[float], x_amplitude: float = DEMO_X_AMPLITUDE
) -> NDArray[np.float64]:
    """Input amplitudes U_i giving ``|alpha G(j omega_i)| U_i = x_amplitude * w_0`` (rounded to 4 digits).

    ``w_0 = (1/(beta + gamma))^(1/mu)`` is the bound of the normalised Bouc-Wen output (Proposition 1).
    """
    norm = plant.normalized()
    gain, _ = norm.linear.gain_phase(np.asarray(frequencies, dtype=np.float64))
    out: NDArray[np.float64] = np.round(x_amplitude * norm.hysteresis.w_bound / gain, 4)
    return out


def demo_plant() -> WienerPlant:
    """A lightly damped resonance (omega_n = 5 rad/s, zeta = 0.2) behind a 0.05 s pure delay.

    ``G(s) = e^{-0.05 s} 25 / (s^2 + 2 s + 25)`` followed by a Bouc-Wen element with alpha = 2, so that the
    alpha-normalised model the method identifies is ``2 G``, beta = 0.8, gamma = 0.2, mu = 1.6.
    """
    return WienerPlant(
        TransferFunction([25.0], [1.0, 2.0, 25.0], delay=0.05),
        BoucWen(beta=1.6, gamma=0.4, mu=1.6, alpha=2.0),
    )


#: What the demo's second plant hides: a dashpot beside the hysteresis, ``c udot`` with c = 0.004 (output
#: units s per input unit); the plain model's held-out NRMSE is 1.4-6x the final model's.
DEMO_HIDDEN = Viscous(0.004)


def demo_hidden_plant() -> WienerPlant:
    """:func:`demo_plant` with :data:`DEMO_HIDDEN` beside it: what the plain model leaves out, for the
    diagnosis to find."""
    plant = demo_plant()
    return WienerPlant(plant.linear, plant.hysteresis, terms=(DEMO_HIDDEN,))


def demo_plan(
    plant: WienerPlant | None = None,
    *,
    samples_per_period: int = 1024,
    periods: int = 40,
    settle_periods: int = 30,
    noise_sd: float = 0.005,
    seed: int = 2024,
) -> SinePlan:
    """Seven sine experiments around the resonance, each amplitude set so that ``|alpha G| U = 1.2``.

    The amplitudes are designed from ``plant`` (default :func:`demo_plant`), as an experimenter would
    from a rough prior model.
    """
    plant = demo_plant() if plant is None else plant
    return SinePlan(
        frequencies=DEMO_FREQUENCIES,
        amplitudes=design_amplitudes(plant, DEMO_FREQUENCIES),
        settle_periods=settle_periods,
        periods=periods,
        samples_per_period=samples_per_period,
        substeps=2,
        noise_sd=noise_sd,
        seed=seed,
    )

"""The Cramer-Rao bound of a sine-experiment design.

For white Gaussian output noise of standard deviation sigma, the N-period average of experiment i
carries noise of variance sigma^2/N on each of its P samples, and the averaged period is a sufficient
statistic for the loop.  The Fisher information of ``[beta, gamma, mu, |G_0|, phi_0, |G_1|, ...]`` is
then ``sum_i (N/sigma^2) J_i^T J_i`` with ``J_i`` the exact sensitivities of the steady loop (the same
ones the refined fit uses), and its inverse bounds the covariance of any unbiased estimator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._backend import Backend, get_backend
from .errors import InvalidParameterError
from .model import SinePlan, WienerPlant

__all__ = ["CramerRao", "cramer_rao"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class CramerRao:
    """Lower bounds on the standard deviations of unbiased estimates (alpha-normalised model)."""

    beta: float
    gamma: float
    mu: float
    gain: FloatArray
    phase: FloatArray
    fisher: FloatArray = field(repr=False)
    covariance: FloatArray = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {
            "beta": self.beta,
            "gamma": self.gamma,
            "mu": self.mu,
            "gain": self.gain.tolist(),
            "phase": self.phase.tolist(),
        }


def cramer_rao(
    plant: WienerPlant, plan: SinePlan, *, substeps: int = 8, backend: Backend = "rust"
) -> CramerRao:
    """Cramer-Rao bound of ``plan`` on ``plant`` for white Gaussian noise of ``plan.noise_sd``.

    Parameters
    ----------
    plant : WienerPlant
        The true system (normalised internally to alpha = 1).
    plan : SinePlan
        The design: frequencies, amplitudes, periods N averaged, samples per period P, noise level.
    substeps : int
        RK4 steps per sample of the steady-loop solver that gives the sensitivities.

    Returns
    -------
    CramerRao
        Standard-deviation bounds for beta, gamma, mu and, per experiment, |G(j omega_i)| and phi_i.

    Raises
    ------
    InvalidParameterError
        When the plan is noise-free (the bound is zero), the Fisher matrix is singular, or the plant has
        physical terms (the bound is the plain model's).
    """
    if plan.noise_sd <= 0:
        raise InvalidParameterError(
            "the Cramer-Rao bound of a noise-free design is zero; set plan.noise_sd > 0"
        )
    if plant.terms:
        # The sensitivities below are the plain model's: a bound for it would silently ignore the terms.
        raise InvalidParameterError(
            "cramer_rao covers the plain Wiener-Bouc-Wen model, and this plant has terms "
            f"({', '.join(t.kind for t in plant.terms)}); pass the plant without them"
        )
    core = get_backend(backend)
    norm = plant.normalized()
    h = norm.hysteresis
    gains, phases = norm.linear.gain_phase(plan.frequencies)
    m = len(plan)
    n = 3 + 2 * m
    fisher = np.zeros((n, n))
    weight = plan.periods / plan.noise_sd**2
    for i in range(m):
        amp = float(plan.amplitudes[i])
        _, jac, _, _ = core.steady_loop(
            amp * gains[i], h.beta, h.gamma, h.mu, float(phases[i]), plan.samples_per_period, substeps
        )
        jac = np.asarray(jac)
        full = np.zeros((jac.shape[0], n))
        full[:, :3] = jac[:, :3]
        full[:, 3 + 2 * i] = jac[:, 3] * amp
        full[:, 4 + 2 * i] = jac[:, 4]
        fisher += weight * full.T @ full
    try:
        cov = np.asarray(np.linalg.inv(fisher), dtype=np.float64)
    except np.linalg.LinAlgError as exc:
        raise InvalidParameterError(
            "the Fisher information of this design is singular: it cannot identify every parameter"
        ) from exc
    sd = np.sqrt(np.abs(np.diag(cov)))
    return CramerRao(
        beta=float(sd[0]),
        gamma=float(sd[1]),
        mu=float(sd[2]),
        gain=sd[3::2].copy(),
        phase=sd[4::2].copy(),
        fisher=fisher,
        covariance=cov,
    )

"""The Cramer-Rao bound of a sine-experiment design.

For white Gaussian output noise of standard deviation sigma, the N-period average of experiment i
carries noise of variance sigma^2/N on each of its P samples, and the averaged period is a sufficient
statistic for the loop.  The Fisher information of ``[beta, gamma, mu, |G_0|, phi_0, |G_1|, ...]`` is
then ``sum_i (N/sigma^2) J_i^T J_i`` with ``J_i`` the exact sensitivities of the steady loop (the same
ones the refined fit uses), and its inverse bounds the covariance of any unbiased estimator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._backend import Backend, get_backend
from .errors import InvalidParameterError
from .model import SinePlan, WienerPlant

__all__ = ["CramerRao", "cramer_rao", "experiment_fisher"]

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


def experiment_fisher(
    plant: WienerPlant,
    frequency: float,
    amplitude: float,
    samples_per_period: int,
    *,
    substeps: int = 8,
    backend: Backend = "rust",
) -> FloatArray:
    """Fisher information of one averaged period of one sine experiment, for unit noise variance.

    The information of an experiment averaged over N periods with noise sd sigma is this block times
    ``N / sigma^2``.  Parameters ``[beta, gamma, mu, |G(j omega)|, phi]`` of the alpha-normalised model.

    Parameters
    ----------
    plant : WienerPlant
        The system (normalised internally to alpha = 1).
    frequency : float
        omega, rad/s.
    amplitude : float
        Input amplitude U.
    samples_per_period : int
        Samples P of the averaged period (the information grows about linearly in P for white noise).

    Returns
    -------
    ndarray, shape (5, 5)
        ``J^T J`` with ``J`` (P x 5) the steady loop's exact sensitivities.
    """
    core = get_backend(backend).paper
    norm = plant.normalized()
    h = norm.hysteresis
    gains, phases = norm.linear.gain_phase(np.array([frequency], dtype=np.float64))
    _, jac, _, _ = core.steady_loop(
        amplitude * float(gains[0]), h.beta, h.gamma, h.mu, float(phases[0]), samples_per_period, substeps
    )
    jac = np.array(jac, dtype=np.float64)
    # The core differentiates with respect to the x amplitude X = U |G|: d/d|G| = U d/dX.
    jac[:, 3] *= amplitude
    block: FloatArray = jac.T @ jac
    return block


def cramer_rao(
    plant: WienerPlant, plan: SinePlan | Sequence[SinePlan], *, substeps: int = 8, backend: Backend = "rust"
) -> CramerRao:
    """Cramer-Rao bound of ``plan`` on ``plant`` for white Gaussian noise of ``plan.noise_sd``.

    Parameters
    ----------
    plant : WienerPlant
        The true system (normalised internally to alpha = 1).
    plan : SinePlan or sequence of SinePlan
        The design: frequencies, amplitudes, periods N averaged, samples per period P, noise level.  A
        sequence of plans is one design whose experiments are those of every plan in order (each with
        its own N, P and noise level: the Fisher information is additive over experiments), as
        :func:`bouc_wen_id.plan_experiment` returns it.
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
    plans = [plan] if isinstance(plan, SinePlan) else list(plan)
    if not plans or not all(isinstance(p, SinePlan) for p in plans):
        raise InvalidParameterError("cramer_rao needs a SinePlan or a non-empty sequence of SinePlans")
    if any(p.noise_sd <= 0 for p in plans):
        raise InvalidParameterError(
            "the Cramer-Rao bound of a noise-free design is zero; set plan.noise_sd > 0"
        )
    if plant.terms:
        # The sensitivities below are the plain model's: a bound for it would silently ignore the terms.
        raise InvalidParameterError(
            "cramer_rao covers the plain Wiener-Bouc-Wen model, and this plant has terms "
            f"({', '.join(t.kind for t in plant.terms)}); pass the plant without them"
        )
    norm = plant.normalized()
    runs = [(p, i) for p in plans for i in range(len(p))]
    m = len(runs)
    n = 3 + 2 * m
    fisher = np.zeros((n, n))
    for k, (p, i) in enumerate(runs):
        block = experiment_fisher(
            norm,
            float(p.frequencies[i]),
            float(p.amplitudes[i]),
            p.samples_per_period,
            substeps=substeps,
            backend=backend,
        )
        # Additive over experiments: this one's (|G_k|, phi_k) columns sit at 3 + 2k, 4 + 2k.
        idx = [0, 1, 2, 3 + 2 * k, 4 + 2 * k]
        fisher[np.ix_(idx, idx)] += (p.periods / p.noise_sd**2) * block
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

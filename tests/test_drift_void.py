"""A drift-correction step the library cannot simulate is void with its reason, not raised out of ``diagnose``
(diagnosis/drift_void.py), and an age the record does not determine is bounded (diagnosis/age.py).

The failing situations are review 44's, saved here as numbers: the degenerate fit of ``feedback-30-D-2``
(mu = 22.8, beta = -gamma, d = 38.8: the loop overflows) and the strength steps of ``nu-10-C-3`` (a loop at
half its saturation read as 796551 periods of age: 2e8 samples to simulate).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import age, drift, drift_void
from bouc_wen_id.errors import BudgetExceededError, NonFiniteError

#: feedback-30-D-2 after one correction pass: (beta, gamma, mu), the latent amplitude and phase, the
#: experiment's omega (rad/s), the record's 10 settling and 4 recorded periods of 256 samples, and d.
DEGENERATE = (0.025731602701261402, -0.025731598524499924, 22.772520548454324)
AMP, PHI, OMEGA, LEAD, PERIODS, GRID = 0.9953784250304816, 0.7080778903846612, 4.0, 10.0, 4, 256
D_RUNAWAY = 38.78364365573723


@dataclass(frozen=True)
class _Record:
    """The fields of an experiment ``drift.corrected`` reads (a DiagExperiment's and an AugExperiment's)."""

    age_periods: float
    blocks: int = PERIODS
    lead_periods: float = LEAD
    periods: float = float(PERIODS)
    h1: Any = field(default_factory=lambda: np.zeros(PERIODS, dtype=np.complex128))
    ybar: Any = field(default_factory=lambda: np.zeros(GRID))
    frequency: float = OMEGA
    amplitude: float = AMP


def _one(beta_gamma_mu: tuple[float, float, float], age_periods: float = 0.0) -> tuple[Any, Any, Any]:
    """One experiment (as both records) and a fit, as ``drift.corrected`` reads them."""
    beta, gamma, mu = beta_gamma_mu
    e = a = _Record(age_periods)
    par = SimpleNamespace(beta=beta, gamma=gamma, mu=mu, terms=(), values=(), phases=(PHI,), gains=(1.0,))
    return e, a, SimpleNamespace(params=par)


def _correct(e: Any, a: Any, fit: Any, d: float) -> Any:
    return drift.corrected([e], [a], fit, d, 1.0, 4)


def test_the_degenerate_fit_of_the_review_blows_up_and_its_step_is_void() -> None:
    e, a, fit = _one(DEGENERATE)
    with pytest.raises(NonFiniteError, match="blew up"):  # the situation: what raised out of diagnose
        _correct(e, a, fit, D_RUNAWAY)
    notes: list[str] = []
    got = drift_void.attempt(
        lambda: _correct(e, a, fit, D_RUNAWAY),
        lambda exc: drift_void.correction_void(exc, "degradation"),
        notes,
    )
    assert got is None
    (note,) = notes
    assert "used as recorded" in note and "could not be simulated" in note and "blew up" in note
    assert "substeps" not in note  # the error's advice to a caller's own simulation is left out
    # A sane fit at the same d is corrected as before: the step is void only when it cannot run.
    sane = _one((1.2, 0.3, 1.5))
    assert drift_void.attempt(lambda: _correct(*sane, 1e-3), drift_void.ages_void, notes) is not None
    assert len(notes) == 1


def test_an_absurd_simulation_is_void_at_the_default_budget_and_raised_under_the_users() -> None:
    """796551 periods of age (nu-10-C-3 on main) ask for 2e8 samples: void at the default budget; a budget
    the user tightened stops the work with its own error (issue 19)."""
    e, a, fit = _one((1.2, 0.3, 1.5), age_periods=796551.4)
    notes: list[str] = []
    assert drift_void.attempt(lambda: _correct(e, a, fit, 1e-3), drift_void.ages_void, notes) is None
    assert len(notes) == 1 and "unrecorded ages: not fitted" in notes[0] and "max_samples" in notes[0]
    short = _one((1.2, 0.3, 1.5))
    drift._mean_period.cache_clear()  # a cached simulation runs no check
    with bw.budget.budget(max_samples=1000), pytest.raises(BudgetExceededError):
        drift_void.attempt(lambda: _correct(*short, 1e-3), drift_void.ages_void, notes)


#: nu-10-C-3's first age pass: the strength steps (Delta ln nu), the energy per period and the steps'
#: standard errors of its ten experiments (the first five below saturation), at d = 7.127e-5.
D_AGE = 7.127e-05
DLN = np.array([0.00343, 0.00645, -0.01742, -0.02461, 0.08301, 0.00084, 0.00103, 0.00123, 0.00195, 0.00122])
ENERGY = np.array([0.1992, 0.08187, 0.02557, 0.006234, 0.001447, 26.63, 18.85, 11.84, 6.338, 2.910])
SE = np.array(
    [4.069e-3, 7.528e-3, 1.649e-2, 4.377e-2, 1.140e-1, 1.543e-4, 1.099e-4, 1.163e-4, 1.588e-4, 3.119e-4]
)


def test_an_undetermined_age_is_not_extrapolated_beyond_the_determined_ones() -> None:
    """age.estimate's first pass on the review's numbers: the ages in energy, anchored at the youngest
    determined record; those not determined (sd above AGE_SE_MAX) at most the oldest determined one's."""
    e0 = DLN / D_AGE  # (ages + step) * energy with ages 0, step = dln / (d E)
    sd = SE / D_AGE / float(np.max(ENERGY))
    sure = [i for i in range(DLN.size) if sd[i] <= age.AGE_SE_MAX]
    assert sure == [5, 6, 7, 8, 9]
    anchored = np.maximum(e0 - float(np.min(e0[sure])), 0.0)
    periods_before = anchored / ENERGY
    assert periods_before[4] > 7e5  # main: 796551 periods of its own drive, 2e8 samples at 256 a period
    got = age.bounded(anchored, sure)
    assert np.array_equal(got[sure], anchored[sure])  # the determined ages as they were
    assert float(np.max(got)) == pytest.approx(float(np.max(anchored[sure])))
    periods = got / ENERGY
    assert float(np.max(periods)) < 2e4  # 10784 periods: 2.8 M samples, within the default 16.8 M
    assert (float(np.max(periods)) + LEAD + 20 + 1) * GRID < bw.budget.DEFAULT_MAX_SAMPLES
    assert np.array_equal(age.bounded(anchored, []), np.zeros(DLN.size))  # nothing determined: no age

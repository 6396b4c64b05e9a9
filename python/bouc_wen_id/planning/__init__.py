"""Plan sine experiments: the design that minimises a Cramer-Rao criterion within a test-time budget.

From a prior guess of the plant and the noise level, :func:`plan_experiment` chooses the frequencies
(within a band), the amplitudes (within the actuator's amplitude and rate limits), the samples per period
(within a sampling-rate limit) and the number of averaged periods of each experiment so that the
Cramer-Rao bound (:func:`bouc_wen_id.cramer_rao`) of what the user cares about is smallest, while the
total test time ``sum_i overhead + (settle_periods + N_i) 2 pi / omega_i`` stays within the budget.

Why it is cheap
---------------
The Fisher information of experiment i is ``(N_i / sigma^2) F_i`` with ``F_i`` the 5 x 5 block of one
averaged period (:func:`bouc_wen_id.uncertainty.experiment_fisher`), in the parameters
``[beta, gamma, mu, |G_i|, phi_i]``.  The gain and phase of experiment i are its own, so eliminating
them leaves the Bouc-Wen information ``sum_i (N_i / sigma^2) S_i`` with ``S_i = A_i - B_i D_i^-1 B_i^T``
the Schur complement of the block (``A`` the Bouc-Wen 3 x 3 part, ``D`` the gain-phase 2 x 2 part): the
designs are scored with 3 x 3 inverses of sums of precomputed matrices, and the covariance of
``(|G_i|, phi_i)`` is ``sigma^2 D_i^-1 / N_i + K_i C K_i^T`` with ``K_i = D_i^-1 B_i^T`` and ``C`` the
Bouc-Wen covariance.  The reported standard errors are then recomputed by :func:`cramer_rao` itself.

Criteria (``target``), all on the alpha-normalised model, all to minimise
----------------------------------------------------------------------
``"beta"``, ``"gamma"``, ``"mu"``
    The relative variance ``var(theta) / theta^2`` of that parameter (the variance itself for a zero
    parameter).
``"bouc_wen"``
    The geometric mean of the relative variances, ``det(C_rel)^(1/3)`` with
    ``C_rel = C / (theta theta^T)``: D-optimal on (beta, gamma, mu), invariant to their units.
``"G"``
    G is pinned only where it is tested, so "G over the band" is scored on a fixed grid: the
    ``n_frequencies`` log-spaced frequencies of the band are ALL tested, and the criterion is the mean
    over them of ``var(|G|) / |G|^2 + var(phi)`` (the relative variance of the complex G(j omega)).
    The planner then chooses the amplitude and the periods of each.

Algorithm
---------
Candidates: ``n_frequencies`` frequencies log-spaced over the band times ``n_amplitudes`` amplitudes
``(1/L, 2/L, ..., 1) x U_max(omega)``, with ``U_max(omega) = min(max_amplitude, max_rate / omega)``. Every
experiment is sampled at the lab's rate ``sample_rate``: a frequency is moved to ``omega = 2 pi
sample_rate / (d P)`` with P a whole number of samples per period (at least
:data:`MIN_SAMPLES_PER_PERIOD`, at most ``max_samples_per_period``) and d = 1, or the smallest whole
decimation that brings P under the cap.  Frequencies whose settling and ``min_periods`` alone exceed the
budget are no candidates.  At most one experiment per frequency.  A greedy phase spends the budget in
chunks (about 1/50 of it): at each step it either adds periods to an experiment or opens a new one (paying
its overhead and settling), whichever lowers the log-criterion most per second of test time.  A
Fedorov-style exchange phase then tries budget-neutral moves (another amplitude at the same frequency,
periods moved between experiments, an experiment closed and its time given to another, an experiment moved
to an unused frequency) and keeps the best improving one until none improves; the greedy phase then spends
what is left, down to single periods. The search is local: when the naive design (below) scores better, it
is the plan. Everything is deterministic.  A vague prior (relative standard deviation 10^4) keeps the
criterion finite while the design cannot yet identify every parameter; it is not in the reported bounds.

Assumptions of the bound (as :func:`cramer_rao`): white Gaussian output noise of the same standard
deviation at any sampling rate (so more samples per period carry more information; a noise that is
filtered before sampling does not gain as much), the steady loop after ``settle_periods``, and unbiased
estimators.  The bound is local: it is only as good as the prior plant.

Modules: ``_settings`` (the input checked by name, the candidate grid on the lab's rate), ``_search`` (the
Fisher blocks, the score, the greedy and exchange phases), ``_plan`` (the entry point, the design's bound,
the naive design), ``_result`` (the result types).
"""

from __future__ import annotations

from ._detect import MIN_EXPERIMENTS, DetectionPlan, plan_detection
from ._naming import NamingChance, naming_chance, naming_factor
from ._plan import plan_experiment
from ._power import (
    DETECTABLE,
    DetectionPower,
    OversizedTermError,
    TwoParameterTermError,
    UnphysicalSizeError,
    detection_power,
)
from ._result import TARGETS, Design, ExperimentPlan, PlannedExperiment, Target
from ._search import criterion_value
from ._settings import (
    MAX_AMPLITUDES,
    MAX_BUDGET,
    MAX_FREQUENCIES,
    MAX_FREQUENCIES_G,
    MIN_SAMPLES_PER_PERIOD,
    NOISE_SD_RANGE,
)

__all__ = [
    "NamingChance",
    "naming_chance",
    "naming_factor",
    "OversizedTermError",
    "TwoParameterTermError",
    "Target",
    "PlannedExperiment",
    "Design",
    "ExperimentPlan",
    "plan_experiment",
    "plan_detection",
    "DetectionPlan",
    "DetectionPower",
    "detection_power",
    "DETECTABLE",
    "MIN_EXPERIMENTS",
    "UnphysicalSizeError",
    "TARGETS",
    "criterion_value",
    "MAX_AMPLITUDES",
    "MAX_BUDGET",
    "MAX_FREQUENCIES",
    "MAX_FREQUENCIES_G",
    "MIN_SAMPLES_PER_PERIOD",
    "NOISE_SD_RANGE",
]

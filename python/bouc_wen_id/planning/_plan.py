"""``plan_experiment``: the input checked, the grid, the search, the design's bound and the naive design."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Optional

import numpy as np

from .._backend import Backend
from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..uncertainty import cramer_rao
from ._result import Design, ExperimentPlan, PlannedExperiment, Target
from ._search import _Search, _search_design, criterion_value
from ._settings import _budget, _check_prior, _Grid, _grid, _on_lab_rate, _Settings, _settings


def plan_experiment(
    prior_plant: WienerPlant,
    budget: float,
    *,
    band: tuple[float, float],
    max_amplitude: float,
    noise_sd: float,
    sample_rate: float,
    target: Target = "bouc_wen",
    max_rate: Optional[float] = None,
    n_frequencies: int = 12,
    n_amplitudes: int = 4,
    settle_periods: int = 20,
    overhead: float = 0.0,
    max_samples_per_period: int = 512,
    min_periods: int = 5,
    max_experiments: Optional[int] = None,
    substeps: int = 8,
    backend: Backend = "rust",
) -> ExperimentPlan:
    """Plan sine experiments minimising the Cramer-Rao criterion ``target`` within a time budget.

    Parameters
    ----------
    prior_plant : WienerPlant
        The prior guess of the plant (a plain Wiener-Bouc-Wen plant, no terms).
    budget : float
        Total test time, s: ``sum_i overhead + (settle_periods + N_i) 2 pi / omega_i <= budget``
        (at most :data:`MAX_BUDGET`).
    band : (float, float)
        Lowest and highest angular frequency allowed, rad/s (low < high).  Frequencies whose settling
        and ``min_periods`` periods alone exceed the budget are not candidates.
    max_amplitude : float
        Largest input amplitude U the actuator allows (> 0; the planner uses positive amplitudes).
    noise_sd : float
        Prior standard deviation of the white output noise, per sample (within :data:`NOISE_SD_RANGE`).
    sample_rate : float
        The lab's sampling rate, Hz.  Every experiment is sampled at it: each candidate frequency is moved
        (by less than half a sample per period) so that a period holds a whole number P of samples; where
        P would exceed ``max_samples_per_period``, the experiment is sampled at ``sample_rate / d`` for
        the smallest whole d that fits (decimate the record by d).
    target : {"bouc_wen", "beta", "gamma", "mu", "G"}
        What to make precise (module docstring: the criteria).
    max_rate : float, optional
        Largest input rate ``U omega`` (a velocity limit, units of u per second).
    n_frequencies : int
        Log-spaced candidate frequencies over the band (for ``"G"``: the tested grid, all used), at most
        :data:`MAX_FREQUENCIES` (:data:`MAX_FREQUENCIES_G` for ``"G"``).
    n_amplitudes : int
        Candidate amplitudes per frequency: ``(1/L, ..., 1) x min(max_amplitude, max_rate / omega)``.
    settle_periods : int
        Periods played before the measured ones, in every experiment (charged to the budget).
    overhead : float
        Set-up time charged per experiment, s.
    max_samples_per_period : int
        Cap on P (the planner takes the most the sampling rate allows, up to this).
    min_periods : int
        Fewest periods N of an experiment (the identification estimates the noise from their spread).
    max_experiments : int, optional
        Most experiments in the design (default: ``n_frequencies``).
    substeps : int
        RK4 steps per sample of the sensitivities (as :func:`cramer_rao`).

    Returns
    -------
    ExperimentPlan
        The design (experiments, predicted standard errors, criterion, total time), the naive design of
        the same budget, and the settings; :meth:`ExperimentPlan.simulate` and
        :meth:`ExperimentPlan.plans` run it.

    Raises
    ------
    InvalidParameterError
        A non-finite or out-of-range argument, an empty band, a plant with terms, no frequency of the
        band sampled with at least :data:`MIN_SAMPLES_PER_PERIOD` samples per period, a budget too small
        for even one experiment (or, for ``"G"``, for every grid point), or a budget whose best design
        still cannot identify every parameter.
    """
    _check_prior(prior_plant, target)
    budget = _budget(budget)
    st = _settings(
        target, band, max_amplitude, noise_sd, sample_rate, max_rate, n_frequencies, n_amplitudes,
        settle_periods, overhead, max_samples_per_period, min_periods, max_experiments, substeps, backend,
    )  # fmt: skip
    grid = _grid(st, budget)
    search = _Search(target, prior_plant, grid, st)
    design = _search_design(search, st, grid, budget)
    experiments = _experiments(st, grid, design)
    planned = _design(st, prior_plant, experiments)
    if planned is None:
        raise InvalidParameterError(
            f"within budget = {budget:g} s no design found identifies every parameter (the Fisher "
            "information stays singular); raise the budget or widen the band"
        )
    naive = _naive(st, prior_plant, budget, len(experiments), grid)
    if naive is not None and naive.criterion < planned.criterion:
        planned = naive  # the search is local: never return a design worse than the naive one
    return ExperimentPlan(target, prior_plant, budget, planned, naive, st.to_dict(grid.omegas))


def _experiments(
    st: _Settings, grid: _Grid, design: dict[int, tuple[int, int]]
) -> tuple[PlannedExperiment, ...]:
    """The searched design as experiments, by frequency."""
    return tuple(
        PlannedExperiment(
            float(grid.omegas[k]),
            float(grid.amps[k, a]),
            int(n),
            int(grid.samples[k]),
            st.settle,
            st.overhead,
        )
        for k, (a, n) in sorted(design.items())
    )


def _design(st: _Settings, prior: WienerPlant, experiments: Sequence[PlannedExperiment]) -> Optional[Design]:
    """The design's exact bound by :func:`cramer_rao` (None when its Fisher matrix is singular)."""
    plans = [e.plan(st.noise_sd) for e in experiments]
    try:
        cr = cramer_rao(prior, plans, substeps=st.substeps, backend=st.backend)
    except InvalidParameterError:
        return None
    freqs = np.array([e.frequency for e in experiments])
    value = criterion_value(st.target, prior, freqs, cr)
    if not math.isfinite(value) or value <= 0:
        return None
    total = float(sum(e.duration for e in experiments))
    return Design(tuple(experiments), st.noise_sd, cr, value, total)


def _naive(st: _Settings, prior: WienerPlant, budget: float, count: int, grid: _Grid) -> Optional[Design]:
    """The naive design's bound (:func:`_naive_experiments`; None when the budget cannot hold it)."""
    experiments = _naive_experiments(st, budget, count, grid)
    return None if experiments is None else _design(st, prior, experiments)


def _naive_experiments(
    st: _Settings, budget: float, count: int, grid: _Grid
) -> Optional[list[PlannedExperiment]]:
    """Evenly log-spaced frequencies of the usable band at the largest amplitude, equal N, fewer if the
    budget is short (for "G": the tested grid)."""
    fixed = st.target == "G"
    for m in range(max(count, 2), 1, -1):
        if fixed:
            omegas, samples = grid.omegas, grid.samples
        else:
            spaced = np.geomspace(grid.lo, grid.top, m)
            omegas, samples = _on_lab_rate(spaced, st.sample_rate, st.p_cap, grid.lo, grid.top)
        period = 2.0 * np.pi / omegas
        n = int((budget - float(np.sum(st.overhead + st.settle * period))) // float(np.sum(period)))
        if n < st.min_n:
            if fixed:
                return None
            continue
        amps = np.minimum(st.max_amplitude, st.rate / omegas)
        return [
            PlannedExperiment(float(w), float(u), n, int(p), st.settle, st.overhead)
            for w, u, p in zip(omegas, amps, samples)
        ]
    return None

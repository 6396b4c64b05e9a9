"""Simulate sine experiments on a Wiener-Bouc-Wen plant."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from typing import Literal, Optional, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import budget as _budget
from ._backend import Backend, get_backend
from .errors import InvalidParameterError
from .model import Recording, SinePlan, WienerPlant
from .terms import core_terms
from .validation import EXACT_GRID_RTOL, check_time_axis, count, finite_array

__all__ = ["simulate", "simulate_input"]


def simulate(
    plant: WienerPlant,
    plan: SinePlan,
    *,
    backend: Backend = "rust",
    workers: Optional[int] = None,
) -> list[Recording]:
    """Run every experiment of ``plan`` on ``plant`` and return one :class:`Recording` each.

    Each experiment starts from rest at t = 0 with ``u = U cos(omega t)`` and lasts
    ``settle_periods + periods`` periods of ``samples_per_period`` samples; the output is
    ``y = w + noise`` with white Gaussian noise of standard deviation ``plan.noise_sd``.  A plant with
    ``terms`` is simulated as the augmented model (docs/design.md 9.4): ``y = F + noise`` with
    ``F = y0 + Lag[w + k u + c udot + m uddot + f tanh(udot/(eps U omega))]`` (plus the mechanical terms on
    ``x``, ``k_x x + c_x xdot + m_x xddot + f_x tanh(xdot/(eps |U| |G| omega))``, from G's state)
    and ``w`` the (asymmetric) hysteresis of the played ``x``; a plant without terms takes the plain path,
    unchanged.  A run that blows up (a huge term or parameter) is :class:`NonFiniteError` naming them.

    Parameters
    ----------
    plant : WienerPlant
        The true system.
    plan : SinePlan
        Frequencies, amplitudes, lengths, grid, noise level and seed.
    backend : {"rust", "numpy"}
        The Rust core (default) or the NumPy reference (slow, for checking).
    workers : int, optional
        Threads used to run experiments concurrently (the Rust core releases the GIL while it integrates).
        Default: one per experiment, at most the number of CPUs.

    Returns
    -------
    list of Recording
        With the inner signals ``x``, ``w`` and the plant attached, so that results can be compared with
        the truth.
    """
    core = get_backend(backend).paper
    h = plant.hysteresis
    lin = plant.linear
    p = plan.samples_per_period
    n = (plan.settle_periods + plan.periods) * p
    # Refuse before any work: each experiment's RK4 cost, and the six signals of every recording.
    _budget.check_simulation(n, plan.substeps)
    _budget.check_bytes(f"the {len(plan)} simulated recordings (six signals each)", 48 * n * len(plan))
    # One independent child stream per experiment: the result does not depend on thread scheduling.
    streams = np.random.SeedSequence(plan.seed).spawn(len(plan))
    # Only a plant with terms goes through the augmented integrator (which also returns y).
    extra = {"terms": core_terms(plant.terms)} if plant.terms else {}

    def run(i: int) -> Recording:
        omega = float(plan.frequencies[i])
        amp = float(plan.amplitudes[i])
        dt = 2.0 * math.pi / omega / p
        x, w, *clean = core.simulate_sine(
            lin.num,
            lin.den,
            lin.delay,
            h.alpha,
            h.beta,
            h.gamma,
            h.mu,
            h.w0,
            amp,
            omega,
            dt,
            n,
            plan.substeps,
            **extra,
        )
        t = np.arange(n, dtype=np.float64) * dt
        u = amp * np.cos(omega * t)
        noise = np.random.default_rng(streams[i]).standard_normal(n) * plan.noise_sd
        return Recording(
            t=t,
            u=u,
            y=(clean[0] if clean else w) + noise,
            amplitude=amp,
            frequency=omega,
            settle_periods=plan.settle_periods,
            x=x,
            w=w,
            plant=plant,
            metadata={"source": "bouc_wen_id.simulate", "noise_sd": repr(plan.noise_sd)},
        )

    if workers is None:
        import os

        workers = min(len(plan), os.cpu_count() or 1)
    if backend == "numpy" or workers <= 1:
        return [run(i) for i in range(len(plan))]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(run, range(len(plan))))


@overload
def simulate_input(
    plant: WienerPlant,
    t: ArrayLike,
    u: ArrayLike,
    *,
    substeps: int = 4,
    backend: Backend = "rust",
    output: Literal[False] = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
@overload
def simulate_input(
    plant: WienerPlant,
    t: ArrayLike,
    u: ArrayLike,
    *,
    substeps: int = 4,
    backend: Backend = "rust",
    output: Literal[True],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
def simulate_input(
    plant: WienerPlant,
    t: ArrayLike,
    u: ArrayLike,
    *,
    substeps: int = 4,
    backend: Backend = "rust",
    output: bool = False,
) -> tuple[NDArray[np.float64], ...]:
    """The inner signals ``(x, w)`` of ``plant`` driven by any uniformly sampled input ``u(t)``, from rest.

    For inputs that are not a clean sine: ramps, idle stretches, bursts, recorded commands.  Between
    samples the input is interpolated at the RK4 stage times by cubic Hermite polynomials with
    Catmull-Rom slopes (``substeps`` RK4 steps per sample interval; docs/design.md section 1).  Add noise
    to ``w`` yourself, from a seeded generator.

    With ``output=True`` returns ``(x, w, y)``: ``y`` the noise-free measured output, which differs from
    ``w`` when the plant has terms (docs/design.md 9.4: the mechanical terms use the interpolant's
    ``u, udot, uddot`` at the samples and ``Vmax = max |udot|`` of the interpolant; the terms on x use the
    linear part's state and, for the friction, the largest ``|xdot|`` at the samples).  ``w`` honours the
    asymmetry and play terms either way.

    Raises
    ------
    InvalidParameterError
        ``t`` and ``u`` of unequal lengths or not real numbers, fewer than 2 samples, a ``substeps`` that is
        not an integer >= 1, or a time axis that is not uniform (:class:`TimeAxisError`, to
        ``validation.EXACT_GRID_RTOL``).
    NonFiniteError
        Non-finite samples, or a run that blows up (naming the parameters and terms, not the data).
    """
    core = get_backend(backend).paper
    tt = _samples("t", t)
    uu = _samples("u", u)
    steps = count("substeps", substeps, 1)
    if tt.ndim != 1 or uu.ndim != 1 or tt.size != uu.size or tt.size < 2:
        raise InvalidParameterError(
            f"t and u must be 1-D of equal lengths >= 2, got shapes {tt.shape} and {uu.shape}"
        )
    check_time_axis(finite_array("t", tt), rtol=EXACT_GRID_RTOL)
    dt = float(np.mean(np.diff(tt)))
    h, lin = plant.hysteresis, plant.linear
    args = (lin.num, lin.den, lin.delay, h.alpha, h.beta, h.gamma, h.mu, h.w0, uu, dt, steps)
    if not plant.terms:
        x, w = core.simulate_sampled(*args)
        y = w
    else:
        x, w, y = core.simulate_sampled(*args, terms=core_terms(plant.terms))
    pair = (np.asarray(x, dtype=np.float64), np.asarray(w, dtype=np.float64))
    return (*pair, np.asarray(y, dtype=np.float64)) if output else pair


def _samples(name: str, values: ArrayLike) -> NDArray[np.float64]:
    """User samples as a C-contiguous float64 array; ragged, complex or non-numeric data is
    :class:`InvalidParameterError` (issue 19: a raw ValueError from NumPy before)."""
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be a 1-D array of real numbers: {exc}") from None
    if raw.dtype.kind not in "biuf":
        raise InvalidParameterError(f"{name} must hold real numbers, got dtype {raw.dtype}")
    return np.ascontiguousarray(raw, dtype=np.float64)

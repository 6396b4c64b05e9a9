"""The sine path's starts of ``fit_time_domain``: G of several orders, each stable and simulable, one chosen.

Why this module: identify's points are the plain cascade's, and a term the cascade lacks bends them (a
viscous term on u adds phase lead that grows with the frequency). The order ``fit_transfer_function``
selects on bent points can be a biproper G with a pole far beyond what the records' sampling can simulate
(RK4 diverges on it, and every start then failed "to simulate"), or a G whose pole sits at the origin. So
without an ``order`` the sine path offers the selected G and the low orders :data:`FIXED_ORDERS` (each
with the delay choice the user gave), drops each G that is not asymptotically stable or that the records'
step cannot simulate (saying why in ``fit.starts``), screens the rest for a few iterations with the terms
being fitted, and keeps the one of least BIC (the search's cost and its free-parameter count).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import (
    BoucWenIdError,
    IdentifiabilityWarning,
    InsufficientDataError,
    InvalidParameterError,
    PoorFitWarning,
    UnstableSystemError,
)
from ..model import BoucWen, TransferFunction, WienerPlant
from ._lm import levenberg_marquardt
from ._records import TimeRecord
from ._wiener import Problem, Structure, check_records

FloatArray = NDArray[np.float64]

#: Orders (m, n) of G offered beside the selected one when no ``order`` is given.
FIXED_ORDERS = ((0, 1), (0, 2), (1, 2))
#: Largest ``|p| h`` (pole times RK4 step) a start may have: RK4's real-axis stability limit is 2.785,
#: and on complex poles it is smaller; beyond this the start's simulation diverges.
RK4_LIMIT = 2.0


def sine_starts(
    result: Any, order: Optional[tuple[int, int]], delay: Optional[bool]
) -> list[tuple[WienerPlant, str]]:
    """Start plants from an identification result: the order asked, else the selected one and
    :data:`FIXED_ORDERS` (duplicates of one (m, n, delay) dropped)."""
    hyst = BoucWen(result.beta, result.gamma, result.mu)
    shapes: list[Optional[tuple[int, int]]] = [order] if order is not None else [None, *FIXED_ORDERS]
    out: list[tuple[WienerPlant, str]] = []
    seen: set[tuple[int, int, bool]] = set()
    for shape in shapes:
        options: dict[str, Any] = {}
        if shape is not None:
            options["order"] = shape
        if delay is not None:
            options["delay"] = delay
        with warnings.catch_warnings():
            # a start's misfit to identify's points (which a term the cascade lacks bends) is what the
            # screening and the time-domain fit's own whiteness test judge; no warning about the points
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            warnings.simplefilter("ignore", PoorFitWarning)
            try:
                tf = result.fit_transfer_function(**options).transfer_function
            except UnstableSystemError:
                continue
        key = (_degree(tf.num), tf.den.size - 1, tf.delay > 0.0)
        if key in seen:
            continue
        seen.add(key)
        label = "selected order" if shape is None else "order"
        out.append(
            (WienerPlant(tf, hyst), f"{label} ({key[0]}, {key[1]}){' with a delay' if key[2] else ''}")
        )
    return out


def _degree(num: FloatArray) -> int:
    return max(np.trim_zeros(np.asarray(num, dtype=float), "f").size - 1, 0)


def unusable(tf: TransferFunction, records: Sequence[TimeRecord], substeps: int) -> Optional[str]:
    """Why a start's G cannot be simulated on the records (None when it can): a pole on or right of the
    imaginary axis, or a pole so fast that RK4 at the records' step diverges on it."""
    den = np.asarray(tf.den, dtype=float)
    if den.size < 2:
        return None
    poles = np.roots(den)
    if np.any(poles.real >= 0.0) or np.any(den <= 0.0):
        return "a pole on or right of the imaginary axis"
    h = max(float(r.dt) for r in records) / substeps
    fastest = float(np.max(np.abs(poles)))
    if fastest * h > RK4_LIMIT:
        return (
            f"a pole at {fastest:.4g} rad/s, too fast for the records' RK4 step of {h:.3g} s "
            f"(|p| h = {fastest * h:.3g} > {RK4_LIMIT})"
        )
    return None


def bic(cost: float, samples: int, free: int) -> float:
    """The Bayesian information criterion of a least-squares fit (Gaussian residuals)."""
    return samples * math.log(max(cost, np.finfo(float).tiny) / samples) + free * math.log(samples)


#: Iterations each start G is screened for before the one of least BIC is kept.
ORDER_SCREEN_ITER = 8


def rank_starts(
    candidates: Sequence[tuple[WienerPlant, str]],
    structure_of: Callable[[WienerPlant], Structure],
    problem_of: Callable[[Structure], Problem],
    substeps: int,
    should_stop: Optional[Callable[[], bool]],
) -> tuple[list[tuple[WienerPlant, str]], tuple[tuple[str, float], ...]]:
    """The usable starts, best first (least BIC after :data:`ORDER_SCREEN_ITER` iterations when there are
    several), and a row per start for ``fit.starts`` (a dropped one with its reason and an infinite cost).

    Raises
    ------
    InsufficientDataError
        The records are shorter than every start's memory.
    InvalidParameterError
        No start's G can be simulated on the records (each reason named).
    """
    usable: list[tuple[WienerPlant, str, Problem]] = []
    rows: list[tuple[str, float]] = []
    short: list[InsufficientDataError] = []
    for plant, origin in candidates:
        problem = problem_of(structure_of(plant))
        why = unusable(plant.linear, problem.records, substeps)
        if why is None:
            try:
                check_records(problem.records, problem.lead, plant)
            except InsufficientDataError as exc:
                why = str(exc)
                short.append(exc)
        if why is None:
            usable.append((plant, origin, problem))
        else:
            rows.append((f"{origin} (dropped: {why})", math.inf))
    if not usable and len(short) == len(rows):
        raise short[0]  # the records are shorter than every start's memory: they are to blame
    if not usable:
        raise InvalidParameterError(
            "no start G can be simulated on these records: "
            + "; ".join(r[0] for r in rows)
            + ": give start= a WienerPlant whose G the records' sampling simulates, or another order="
        )
    if len(usable) == 1:
        return [(usable[0][0], usable[0][1])], tuple(rows)
    scored: list[tuple[float, int]] = []
    for i, (plant, origin, problem) in enumerate(usable):
        st = problem.structure
        theta = st.pack(plant)
        max_delay = min(r.duration for r in problem.records) / 2.0
        lo, hi = st.bounds(theta, max_delay)
        free = st.free
        try:
            run = levenberg_marquardt(
                problem.fun(theta),
                theta[free],
                lo[free],
                hi[free],
                max_iter=ORDER_SCREEN_ITER,
                should_stop=should_stop,
            )
        except BoucWenIdError as exc:  # a start the model cannot simulate is dropped, not fatal
            rows.append((f"{origin} (screen failed: {type(exc).__name__})", math.inf))
            scored.append((math.inf, i))
            continue
        cost = 2.0 * run.cost * problem.scale**2
        samples = sum(len(r) - k for r, k in zip(problem.records, problem.lead))
        rows.append((f"{origin} (order screen, BIC {bic(cost, samples, int(free.sum())):.6g})", cost))
        scored.append((bic(cost, samples, int(free.sum())), i))
    scored.sort()
    return [(usable[i][0], usable[i][1]) for _, i in scored], tuple(rows)

"""What the planner returns: the planned experiments, a design with its bound, and the plan."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, Literal, Optional

import numpy as np

from .._backend import Backend
from .._text import Summarised
from ..model import Recording, SinePlan, WienerPlant
from ..uncertainty import CramerRao

Target = Literal["beta", "gamma", "mu", "bouc_wen", "G"]
TARGETS: tuple[str, ...] = ("beta", "gamma", "mu", "bouc_wen", "G")


@dataclass(frozen=True)
class PlannedExperiment:
    """One sine experiment of a design: ``u = amplitude cos(frequency t)``.

    ``frequency`` in rad/s; ``samples_per_period`` P (the sampling rate is ``P frequency / (2 pi)``
    Hz); ``settle_periods`` played and discarded, then ``periods`` N measured and averaged;
    ``overhead`` seconds of set-up counted against the budget.
    """

    frequency: float
    amplitude: float
    periods: int
    samples_per_period: int
    settle_periods: int
    overhead: float = 0.0

    @property
    def period(self) -> float:
        """One period, s."""
        return 2.0 * math.pi / self.frequency

    @property
    def duration(self) -> float:
        """Test time charged to the budget, s: overhead + (settle + N) periods."""
        return self.overhead + (self.settle_periods + self.periods) * self.period

    @property
    def sample_rate(self) -> float:
        """Sampling rate, Hz."""
        return self.samples_per_period / self.period

    def plan(self, noise_sd: float, seed: Optional[int] = 0, substeps: int = 4) -> SinePlan:
        """This experiment as a one-frequency :class:`SinePlan` (for :func:`bouc_wen_id.simulate`)."""
        return SinePlan(
            frequencies=[self.frequency],
            amplitudes=[self.amplitude],
            settle_periods=self.settle_periods,
            periods=self.periods,
            samples_per_period=self.samples_per_period,
            substeps=substeps,
            noise_sd=noise_sd,
            seed=seed,
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "frequency": self.frequency,
            "amplitude": self.amplitude,
            "periods": self.periods,
            "samples_per_period": self.samples_per_period,
            "settle_periods": self.settle_periods,
            "overhead": self.overhead,
            "duration": self.duration,
            "sample_rate": self.sample_rate,
        }


@dataclass(frozen=True, eq=False)
class Design:
    """A set of experiments with its predicted standard errors (Cramer-Rao) and its criterion value."""

    experiments: tuple[PlannedExperiment, ...]
    noise_sd: float
    predicted: CramerRao
    criterion: float
    total_time: float

    def plans(self, seed: Optional[int] = 0, substeps: int = 4) -> list[SinePlan]:
        """One :class:`SinePlan` per experiment (each its own N and P); the noise seeds are derived from
        ``seed`` by ``numpy.random.SeedSequence(seed).spawn`` (``None``: fresh entropy)."""
        if seed is None:
            return [e.plan(self.noise_sd, None, substeps) for e in self.experiments]
        children = np.random.SeedSequence(seed).spawn(len(self.experiments))
        return [
            e.plan(self.noise_sd, int(c.generate_state(1)[0]), substeps)
            for e, c in zip(self.experiments, children)
        ]

    def simulate(
        self, plant: WienerPlant, seed: Optional[int] = 0, substeps: int = 4, backend: Backend = "rust"
    ) -> list[Recording]:
        """Simulate every experiment on ``plant`` (e.g. the prior, or a truth for a Monte Carlo)."""
        from ..simulation import simulate

        recs: list[Recording] = []
        for plan in self.plans(seed, substeps):
            recs.extend(simulate(plant, plan, backend=backend, workers=1))
        return recs

    def to_dict(self) -> dict[str, Any]:
        return {
            "experiments": [e.to_dict() for e in self.experiments],
            "noise_sd": self.noise_sd,
            "predicted_sd": self.predicted.to_dict(),
            "criterion": self.criterion,
            "total_time": self.total_time,
        }


@dataclass(frozen=True, eq=False)
class ExperimentPlan(Summarised):
    """The planned design, the naive design of the same budget, and the constraints they obey.

    ``design`` is what to run; ``naive`` (None when the budget cannot hold it) is the comparison:
    evenly log-spaced frequencies over the band (for ``target="G"``: the same tested grid) at the
    largest allowed amplitude, the same number of experiments, the same periods N each, the same
    sampling-rate rule.  ``improvement`` is ``naive.criterion / design.criterion`` (>= 1 is a gain).
    """

    target: str
    prior: WienerPlant
    budget: float
    design: Design
    naive: Optional[Design]
    settings: dict[str, Any] = field(repr=False)

    @property
    def experiments(self) -> tuple[PlannedExperiment, ...]:
        return self.design.experiments

    @property
    def predicted(self) -> CramerRao:
        return self.design.predicted

    @property
    def total_time(self) -> float:
        return self.design.total_time

    @property
    def improvement(self) -> Optional[float]:
        if self.naive is None:
            return None
        return self.naive.criterion / self.design.criterion

    def plans(self, seed: Optional[int] = 0, substeps: int = 4) -> list[SinePlan]:
        """The planned experiments as :class:`SinePlan` s (see :meth:`Design.plans`)."""
        return self.design.plans(seed, substeps)

    def simulate(
        self,
        plant: Optional[WienerPlant] = None,
        seed: Optional[int] = 0,
        substeps: int = 4,
        backend: Backend = "rust",
    ) -> list[Recording]:
        """Simulate the planned experiments on ``plant`` (default: the prior)."""
        return self.design.simulate(self.prior if plant is None else plant, seed, substeps, backend)

    def summary(self) -> str:
        lines = [
            f"Experiment plan: target {self.target!r}, budget {self.budget:g} s "
            f"(used {self.design.total_time:.1f} s), noise sd {self.design.noise_sd:g}",
            f"  {'#':>2} {'omega rad/s':>11} {'f Hz':>8} {'U':>9} {'P':>5} {'fs Hz':>9} "
            f"{'settle':>6} {'N':>6} {'time s':>8} {'sd|G|/|G|':>10} {'sd phi':>9}",
        ]
        gains, _ = self.prior.normalized().linear.gain_phase([e.frequency for e in self.experiments])
        cr = self.design.predicted
        for i, e in enumerate(self.experiments):
            lines.append(
                f"  {i:>2} {e.frequency:>11.4g} {e.frequency / (2 * math.pi):>8.4g} {e.amplitude:>9.4g} "
                f"{e.samples_per_period:>5d} {e.sample_rate:>9.4g} {e.settle_periods:>6d} {e.periods:>6d} "
                f"{e.duration:>8.2f} {cr.gain[i] / gains[i]:>10.3g} {cr.phase[i]:>9.3g}"
            )
        h = self.prior.normalized().hysteresis
        lines.append("Predicted standard deviations (Cramer-Rao bound, alpha-normalised model):")
        lines.append(f"  {'':<9} {'prior':>10} {'planned':>12} {'naive':>12}")
        for name in ("beta", "gamma", "mu"):
            value = getattr(h, name)
            naive = "-" if self.naive is None else f"{getattr(self.naive.predicted, name):.3g}"
            lines.append(
                f"  {name:<9} {value:>10.4g} {getattr(cr, name):>12.3g} {naive:>12}"
                + (f"   ({getattr(cr, name) / abs(value):.2%} of the value)" if value else "")
            )
        naive_c = "-" if self.naive is None else f"{self.naive.criterion:.3g}"
        lines.append(
            f"  {'criterion':<9} {'':>10} {self.design.criterion:>12.3g} {naive_c:>12}   "
            f"({_CRITERION_TEXT[self.target]})"
        )
        if self.improvement is not None:
            lines.append(
                f"Naive design ({len(self.naive.experiments) if self.naive else 0} experiments at the "
                "largest "
                f"amplitude, equal periods): the planned one's criterion is {self.improvement:.3g}x smaller."
            )
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (format ``bouc_wen_id.plan``, version 1)."""
        return {
            "format": "bouc_wen_id.plan",
            "version": 1,
            "target": self.target,
            "criterion": _CRITERION_TEXT[self.target],
            "budget": self.budget,
            "prior": self.prior.to_dict(),
            "settings": self.settings,
            "design": self.design.to_dict(),
            "naive": None if self.naive is None else self.naive.to_dict(),
            "improvement": self.improvement,
        }

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)


_CRITERION_TEXT = {
    "beta": "relative variance of beta",
    "gamma": "relative variance of gamma",
    "mu": "relative variance of mu",
    "bouc_wen": "geometric mean of the relative variances of beta, gamma, mu",
    "G": "mean over the tested grid of var|G|/|G|^2 + var(phi)",
}

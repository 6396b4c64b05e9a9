"""A simulated study: does the identification reach the Cramer-Rao bound on this design?

Run from the repository root (the package installed)::

    python examples/simulated_study.py            # 20 noise seeds, ~10 s
    python examples/simulated_study.py --seeds 5

Each seed draws new measurement noise on the demo plant and design; the spread of the refined estimates
over the seeds is compared with the Cramer-Rao bound of the design, and each seed's 95 % interval of mu
with the truth.  Replace ``demo_plant``/``SinePlan`` by your own plant and design to plan an experiment.
"""

from __future__ import annotations

import argparse
import warnings

import bouc_wen_id as bw
import numpy as np


def main(seeds: int) -> None:
    plant = bw.demo_plant()
    plan = bw.demo_plan(samples_per_period=256, periods=20, noise_sd=0.02)
    bound = bw.cramer_rao(plant, plan)
    estimates, covered = [], 0
    for seed in range(seeds):
        plan_s = bw.SinePlan(
            plan.frequencies,
            plan.amplitudes,
            settle_periods=plan.settle_periods,
            periods=plan.periods,
            samples_per_period=plan.samples_per_period,
            noise_sd=plan.noise_sd,
            seed=seed,
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
            result = bw.identify(bw.simulate(plant, plan_s))
        estimates.append([result.beta, result.gamma, result.mu])
        lo, hi = result.interval("mu")
        assert result.truth is not None  # simulated recordings carry their plant
        covered += lo <= result.truth.mu <= hi
    spread = np.std(estimates, axis=0, ddof=1)
    truth = plant.normalized().hysteresis
    print(f"{'':8}{'truth':>10}{'mean':>12}{'sd':>12}{'CRB':>12}")
    for i, name in enumerate(("beta", "gamma", "mu")):
        mean = float(np.mean([e[i] for e in estimates]))
        true, crb = getattr(truth, name), getattr(bound, name)
        print(f"{name:8}{true:>10.4g}{mean:>12.5g}{spread[i]:>12.3g}{crb:>12.3g}")
    print(f"95 % interval of mu covers the truth in {covered} of {seeds} seeds")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    main(parser.parse_args().seeds)

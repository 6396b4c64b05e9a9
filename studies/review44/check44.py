"""Review 44's checks of its own simulator and of the quantiser's locked error (numbers in FINDINGS.md).

PYTHONPATH=python python studies/review44/check44.py
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).parent))
import drive44 as dr  # noqa: E402
import sim44 as s  # noqa: E402


def linear_closed_form() -> None:
    for g in (s.resonant(6, 0.1, 0.005), s.first_order(0.3, 0.008), s.two_pole(0.5, 0.1)):
        t = np.linspace(0, 60, 20001)
        x, _, _ = s.linear_drive(g, 1.5, 3.0, t)
        xs = np.real(g.response(3.0) * 1.5 * np.exp(1j * 3.0 * t))
        print(f"{g.label}: steady x against G(jw): {np.max(np.abs(x - xs)[t > 50]):.1e}")


def rk4_accuracy() -> None:
    d = s.Design((2.0, 4.0, 8.0), (1.0, 1.0, 1.0))
    p = s.Plant(s.resonant(6, 0.2, 0.004), s.Hyst())
    for kw in ({}, {"play": 0.2}, {"nu": 0.05}, {"eta": 0.05}, {"pinch": 0.6}, {"rate": 0.5}, {"slack": 0.2}):
        q = replace(p, hy=replace(p.hy, **kw))
        r2 = s.run(q, d)
        s.SUB = 8
        r8 = s.run(q, d)
        s.SUB = 2
        print(
            f"{kw or 'plain'}: SUB 2 against 8: "
            f"{max(np.max(np.abs(a[2] - b[2])) for a, b in zip(r2, r8)):.1e}"
        )
    g, om, amp = p.g, 2.0, 1.0
    period = 2 * np.pi / om

    def f(t: float, z: np.ndarray) -> list[float]:
        _, xd, _ = s.linear_drive(g, amp, om, np.array([t]))
        w, v = z[0], xd[0]
        return [v - 1.2 * abs(v) * abs(w) ** 0.5 * w - 0.3 * v * abs(w) ** 1.5]

    tt = np.arange(30 * 256) * period / 256
    sol = solve_ivp(f, (0, tt[-1]), [0.0], t_eval=tt, rtol=1e-10, atol=1e-12, max_step=period / 512)
    print(f"plain against solve_ivp: {np.max(np.abs(sol.y[0] - s.run_one(p, d, 0)[2])):.1e}")


def against_library() -> None:
    import bouc_wen_id as bw
    from bouc_wen_id.terms import StiffnessDegradation

    p, d, truth, _ = dr.build("eta", 10, "Ds")
    g, i = p.g, 7
    plant = bw.WienerPlant(
        bw.TransferFunction(list(g.num), list(g.den), delay=g.delay),
        bw.BoucWen(beta=p.hy.beta, gamma=p.hy.gamma, mu=p.hy.mu, alpha=1.0),
        terms=(StiffnessDegradation(truth["stiffness_degradation"]),),
    )
    plan = bw.SinePlan(
        frequencies=[d.omegas[i]],
        amplitudes=d.amps[i],
        settle_periods=d.settle,
        periods=d.periods,
        samples_per_period=d.samples,
        noise_sd=0.0,
        seed=1,
    )
    (rec,) = bw.simulate(plant, plan)
    y = s.run_one(p, d, i)[2]
    print(
        "eta-10-Ds experiment 7 against bw.simulate (last 4 periods): "
        f"{np.max(np.abs(rec.y[-1024:] - y[-1024:])):.1e}"
    )


def quantiser() -> None:
    from bouc_wen_id.diagnosis.data import quantisation_step

    p, d, _, _ = dr.build("null", 0, "C")
    recs = s.recordings(p, d, dr.NOISES["quant"], 12)
    for r, (_, _, yc) in zip(recs, s.run(p, d)):
        y = r.y[d.settle * d.samples :].reshape(d.periods, d.samples)
        clean = yc[d.settle * d.samples :].reshape(d.periods, d.samples)[0]
        q = quantisation_step(r.y)
        var = np.var(y - y.mean(0), ddof=1) * d.periods / (d.periods - 1)
        err = np.sqrt(np.mean((y.mean(0) - clean) ** 2))
        print(
            f"{r.metadata['name']}: q {q:.3g}, var/(q^2/12) {var / (q * q / 12):.2f}, "
            f"averaged error rms {err:.5f} against noise alone {np.sqrt(var / d.periods):.5f}"
        )


if __name__ == "__main__":
    linear_closed_form()
    rk4_accuracy()
    against_library()
    quantiser()

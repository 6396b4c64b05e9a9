//! Dahl friction's time-domain form (`rust/dahl.rs` has its steady loop): the friction force `F`
//! is one more state, `F' = sigma v' (1 - sgn(v') F / Fc)`, `F(0) = 0`, along the measured input
//! (`v = u`) or across the hysteretic element (`v = x`). `F` adds to the output and does not feed
//! back, so it rides along the RK4 step with the rates `v'` of its four stages. `Fc = 0` or
//! `sigma = 0` is no friction (`F = 0`, as the steady loop's limit).

/// Dahl friction at one place: level `fc` ([y]) and pre-sliding stiffness `sigma`.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Dahl {
    pub(super) fc: f64,
    pub(super) sigma: f64,
}

impl Dahl {
    /// Whether the friction moves at all (`Fc > 0` and `sigma > 0`).
    pub(super) fn is_active(&self) -> bool {
        self.fc > 0.0 && self.sigma > 0.0
    }

    /// `F' = sigma vdot (1 - sgn(vdot) F / Fc)`; 0 when inactive.
    #[inline]
    pub(super) fn rate(&self, vdot: f64, f: f64) -> f64 {
        if !self.is_active() {
            return 0.0;
        }
        let s = if vdot > 0.0 {
            1.0
        } else if vdot < 0.0 {
            -1.0
        } else {
            0.0
        };
        self.sigma * vdot * (1.0 - s * f / self.fc)
    }

    /// One RK4 step of `F` over `h` with the stage rates `vdot = (v1, vm2, vm3, v4)`: the new `F`
    /// and its third-order continuous extension at the step's middle.
    #[inline]
    pub(super) fn step(&self, f: f64, h: f64, vdot: [f64; 4]) -> (f64, f64) {
        let half_h = 0.5 * h;
        let k1 = self.rate(vdot[0], f);
        let k2 = self.rate(vdot[1], f + half_h * k1);
        let k3 = self.rate(vdot[2], f + half_h * k2);
        let k4 = self.rate(vdot[3], f + h * k3);
        (
            f + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4),
            f + h * (5.0 * k1 + 4.0 * (k2 + k3) - k4) / 24.0,
        )
    }
}

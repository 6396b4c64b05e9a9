//! The augmented right-hand side: the play's mode of a step, Foliente's pinching factor, the
//! generalised Bouc-Wen rate with degradation, the linear part and the play's path map.

use super::super::on_x::OnX;
use super::delayed_with_second;
use super::derivatives::{Derivatives, Mechanical};
use crate::bouc_wen::sgn;
use crate::linear::Companion;

/// Play mode of one RK4 step (frozen from the step's start).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    Up,
    Down,
    Dwell,
}

impl Mode {
    #[inline]
    pub(super) fn rate(self, xdot: f64) -> f64 {
        match self {
            Mode::Up => xdot.max(0.0),
            Mode::Down => xdot.min(0.0),
            Mode::Dwell => 0.0,
        }
    }
}

/// Foliente's pinching factor with its fixed shape in units of w (module header).
#[derive(Clone, Copy)]
pub(super) struct Pinch {
    pub(super) zeta1: f64,
    pub(super) centre: f64,
    pub(super) width: f64,
}

impl Pinch {
    /// `h = 1 - zeta1 exp(-((w sgn(xpdot) - centre) / width)^2)`; the rate is 0 where `xpdot = 0`
    /// whatever h, so the sign of 0 does not matter.
    #[inline]
    fn factor(&self, w: f64, xpdot: f64) -> f64 {
        let z = (w * sgn(xpdot) - self.centre) / self.width;
        1.0 - self.zeta1 * (-z * z).exp()
    }
}

/// The augmented right-hand side: linear part, generalised Bouc-Wen with `delta`, the input.
pub(super) struct Augmented<'a, S> {
    pub(super) comp: &'a Companion,
    pub(super) alpha: f64,
    pub(super) beta: f64,
    pub(super) gamma: f64,
    pub(super) mu: f64,
    pub(super) delta: f64,
    /// `delta_nu` of `nu = 1 + delta_nu e` (0: no energy state is needed, `nu = 1`).
    pub(super) degradation: f64,
    /// `delta_eta` of `eta = 1 + delta_eta e` dividing the whole rate (0: `eta = 1`, not applied).
    pub(super) stiffness_degradation: f64,
    pub(super) pinch: Pinch,
    pub(super) delay: f64,
    pub(super) src: &'a S,
    pub(super) mech: Mechanical<'a, S>,
}

impl<S: Derivatives> Augmented<'_, S> {
    /// Delayed input `(v, vdot)` at time `t` (0 before the delay has elapsed).
    #[inline]
    pub(super) fn delayed(&self, t: f64) -> (f64, f64) {
        let tau = t - self.delay;
        if tau < 0.0 {
            (0.0, 0.0)
        } else {
            self.src.at(tau)
        }
    }

    /// `wdot = alpha xpdot - nu (beta |xpdot| |w|^(mu-1) w + gamma xpdot |w|^mu
    /// + delta xpdot |w|^(mu-1) w)`, `nu = 1 + delta_nu e` (positively homogeneous of degree 1 in
    /// `xpdot`, so it is also `dw` for a path increment `dxp`).
    #[inline]
    pub(super) fn rate(&self, xpdot: f64, w: f64, e: f64) -> f64 {
        let wmu = w.abs().powf(self.mu);
        let sw = sgn(w);
        let nu = 1.0 + self.degradation * e;
        // nu multiplies each term (not their sum) so that nu = 1 rounds exactly as before.
        let mut r = self.alpha * xpdot
            - nu * (self.beta * xpdot.abs() * sw * wmu)
            - nu * (self.gamma * xpdot * wmu)
            - nu * (self.delta * xpdot * sw * wmu);
        // Applied only when present, so that the other terms' runs round exactly as before.
        if self.stiffness_degradation != 0.0 {
            r /= 1.0 + self.stiffness_degradation * e;
        }
        if self.pinch.zeta1 != 0.0 {
            r *= self.pinch.factor(w, xpdot);
        }
        r
    }

    /// `xsdot` into `dxs` and `xdot`, at state `xs` and delayed input `(v, vdot)`.
    #[inline]
    pub(super) fn linear(&self, xs: &[f64], (v, vdot): (f64, f64), dxs: &mut [f64]) -> f64 {
        self.comp.state_derivative(xs, v, dxs);
        self.comp.output_row(dxs) + self.comp.d * vdot
    }

    /// `(w, e)` moved along the hysteresis path by the play's clamped travel `dxp` (one RK4 step
    /// of `dw/dsigma = rate(dxp, w, e)`, `de/dsigma = w dxp`, `sigma in [0, 1]`).
    pub(super) fn path(&self, w: f64, e: f64, dxp: f64) -> (f64, f64) {
        let k1 = self.rate(dxp, w, e);
        let (w2, e2) = (w + 0.5 * k1, e + 0.5 * w * dxp);
        let k2 = self.rate(dxp, w2, e2);
        let (w3, e3) = (w + 0.5 * k2, e + 0.5 * w2 * dxp);
        let k3 = self.rate(dxp, w3, e3);
        let (w4, e4) = (w + k3, e + w3 * dxp);
        let k4 = self.rate(dxp, w4, e4);
        (
            w + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0,
            e + (w + 2.0 * w2 + 2.0 * w3 + w4) * dxp / 6.0,
        )
    }

    /// `w + mech(t)`, plus the terms on x at state `xs` when present: the lag's input `F` and,
    /// without a lag, the output before the offset.
    #[inline]
    pub(super) fn forcing(&self, w: f64, t: f64, xs: &[f64], on_x: &mut Option<OnX<'_>>) -> f64 {
        let f = w + self.mech.at(t);
        match on_x {
            Some(o) => f + o.at(xs, delayed_with_second(self.src, self.delay, t)),
            None => f,
        }
    }
}

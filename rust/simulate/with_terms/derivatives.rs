//! The input's second derivative and peak rate (a sine, or the Catmull-Rom interpolant of samples),
//! and the output terms on the measured input.

use super::super::{Sine, Source};
use super::TermValues;
use crate::hermite::Hermite;
use crate::linear::TransferFunction;

/// The input's second derivative and peak rate, beyond the `(u, udot)` of [`Source`].
pub(super) trait Derivatives: Source {
    /// `uddot(tau)` (units of u per s^2), `tau >= 0`.
    fn second(&self, tau: f64) -> f64;
    /// `Vmax = max |udot|` over `t >= 0` (units of u per s).
    fn peak_rate(&self) -> f64;
    /// The steady peak of `|xdot|` through `tf` where the input has one (a sine:
    /// `|U| |G(j omega)| omega`); `None` for samples (`rust/simulate/on_x.rs`).
    fn steady_x_peak_rate(&self, tf: &TransferFunction) -> Option<f64>;
}

impl Derivatives for Sine {
    fn second(&self, tau: f64) -> f64 {
        self.neg_amplitude_omega * self.omega * (self.omega * tau).cos()
    }

    fn peak_rate(&self) -> f64 {
        self.amplitude.abs() * self.omega
    }

    fn steady_x_peak_rate(&self, tf: &TransferFunction) -> Option<f64> {
        let (re, im) = tf.freq_response(self.omega);
        Some(self.amplitude.abs() * re.hypot(im) * self.omega)
    }
}

impl Derivatives for Hermite<'_> {
    /// The right-hand second derivative of the cubic on `[t_k, t_{k+1})` (it jumps at the knots);
    /// 0 past the last sample.
    fn second(&self, tau: f64) -> f64 {
        Hermite::second(self, tau)
    }

    fn steady_x_peak_rate(&self, _tf: &TransferFunction) -> Option<f64> {
        None
    }

    /// Exact: on each interval `udot` is the quadratic `A s^2 + B s + m_k` in `s = (t - t_k)/dt`,
    /// so its extremes are the knot slopes and an interior vertex.
    fn peak_rate(&self) -> f64 {
        let mut peak = 0.0f64;
        for k in 0..self.u.len() - 1 {
            let (m0, m1) = (self.m[k], self.m[k + 1]);
            let slope = (self.u[k + 1] - self.u[k]) / self.dt;
            let a = 3.0 * (m0 + m1) - 6.0 * slope;
            let b = 6.0 * slope - 4.0 * m0 - 2.0 * m1;
            peak = peak.max(m0.abs()).max(m1.abs());
            if a != 0.0 {
                let s = -b / (2.0 * a);
                if s > 0.0 && s < 1.0 {
                    peak = peak.max((m0 + s * (b + s * a)).abs());
                }
            }
        }
        peak
    }
}

/// The output terms on the measured input: `k u + c udot + m uddot + f tanh(udot/(eps Vmax))`.
pub(super) struct Mechanical<'a, S> {
    src: &'a S,
    stiffness: f64,
    viscous: f64,
    inertia: f64,
    coulomb: f64,
    /// `eps Vmax`; 0 when the input never moves (then the friction term is 0).
    velocity_scale: f64,
}

impl<'a, S: Derivatives> Mechanical<'a, S> {
    pub(super) fn new(terms: &TermValues, src: &'a S) -> Self {
        Self {
            src,
            stiffness: terms.stiffness,
            viscous: terms.viscous,
            inertia: terms.inertia,
            coulomb: terms.coulomb,
            velocity_scale: terms.coulomb_smoothing * src.peak_rate(),
        }
    }

    /// The terms at time `t >= 0` (units of y).
    pub(super) fn at(&self, t: f64) -> f64 {
        let (u, udot) = self.src.at(t);
        let uddot = self.src.second(t);
        let friction = if self.velocity_scale > 0.0 {
            self.coulomb * (udot / self.velocity_scale).tanh()
        } else {
            0.0
        };
        self.stiffness * u + self.viscous * udot + self.inertia * uddot + friction
    }
}

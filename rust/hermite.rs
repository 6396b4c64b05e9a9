//! The input between samples: the cubic Hermite interpolant of samples on the uniform grid `k dt`,
//! with Catmull-Rom slopes (centred differences inside, one-sided at the two ends), and the last
//! sample held past the end (docs/design.md section 1).
//!
//! One interpolant for every simulator that takes sampled inputs: the Wiener cascade with and
//! without terms (`rust/simulate.rs`, `rust/simulate/with_terms.rs`), its time-domain sensitivities
//! (`rust/timedomain.rs`) and the feedback structure (`rust/feedback.rs`), so that a record means the
//! same continuous input to each of them.

/// Cubic Hermite interpolant of `u` on the grid `k dt`.
pub(crate) struct Hermite<'a> {
    pub(crate) u: &'a [f64],
    /// Slopes `m_k` (units of u per second), same length as `u`.
    pub(crate) m: Vec<f64>,
    pub(crate) dt: f64,
}

impl<'a> Hermite<'a> {
    /// The interpolant of `u` (the callers check `u.len() >= 2`; shorter gives zero slopes).
    pub(crate) fn new(u: &'a [f64], dt: f64) -> Self {
        let n = u.len();
        let mut m = vec![0.0; n];
        if n >= 2 {
            for k in 1..n - 1 {
                m[k] = (u[k + 1] - u[k - 1]) / (2.0 * dt);
            }
            // One-sided at the ends: no sample beyond to centre on.
            m[0] = (u[1] - u[0]) / dt;
            m[n - 1] = (u[n - 1] - u[n - 2]) / dt;
        }
        Self { u, m, dt }
    }

    /// The cell `k` with `t_k <= tau < t_{k+1}` and the position `s` in it, or `None` past the last
    /// sample. Compared as floats so that a huge `tau` cannot overflow the index.
    #[inline(always)]
    fn cell(&self, tau: f64) -> Option<(usize, f64)> {
        let last = self.u.len() - 1;
        let q = tau / self.dt;
        let kf = q.floor();
        if kf >= last as f64 {
            return None;
        }
        Some((kf as usize, q - kf))
    }

    /// `u(tau)`.
    #[inline(always)]
    pub(crate) fn value(&self, tau: f64) -> f64 {
        self.value_slope(tau).0
    }

    /// `(u, udot)` at `tau`; past the last sample `(u_last, 0)`.
    #[inline(always)]
    pub(crate) fn value_slope(&self, tau: f64) -> (f64, f64) {
        let Some((k, s)) = self.cell(tau) else {
            return (self.u[self.u.len() - 1], 0.0);
        };
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        let (u0, u1, m0, m1) = (self.u[k], self.u[k + 1], self.m[k], self.m[k + 1]);
        let dt = self.dt;
        let val = h00 * u0 + h10 * dt * m0 + h01 * u1 + h11 * dt * m1;
        let d00 = 6.0 * s2 - 6.0 * s;
        let d10 = 3.0 * s2 - 4.0 * s + 1.0;
        let d01 = -6.0 * s2 + 6.0 * s;
        let d11 = 3.0 * s2 - 2.0 * s;
        let der = (d00 * u0 + d01 * u1) / dt + d10 * m0 + d11 * m1;
        (val, der)
    }

    /// The right-hand second derivative of the cubic on `[t_k, t_{k+1})` (it jumps at the knots);
    /// 0 past the last sample.
    #[inline(always)]
    pub(crate) fn second(&self, tau: f64) -> f64 {
        let Some((k, s)) = self.cell(tau) else {
            return 0.0;
        };
        let (u0, u1, m0, m1) = (self.u[k], self.u[k + 1], self.m[k], self.m[k + 1]);
        let dt = self.dt;
        ((12.0 * s - 6.0) * u0 + (6.0 - 12.0 * s) * u1) / (dt * dt)
            + ((6.0 * s - 4.0) * m0 + (6.0 * s - 2.0) * m1) / dt
    }

    /// `(u, udot, uddot)` at `tau` (the second derivative as [`Hermite::second`]).
    #[inline(always)]
    pub(crate) fn value_slope_second(&self, tau: f64) -> (f64, f64, f64) {
        let (v, d) = self.value_slope(tau);
        (v, d, self.second(tau))
    }
}

#[cfg(test)]
mod tests {
    use super::Hermite;

    #[test]
    fn reproduces_a_cubic_between_knots_and_holds_the_last_sample() {
        // Catmull-Rom slopes are exact for a quadratic: the interpolant is the quadratic itself.
        let dt = 0.1;
        let u: Vec<f64> = (0..20).map(|k| (k as f64 * dt).powi(2)).collect();
        let h = Hermite::new(&u, dt);
        for tau in [0.55, 0.93, 1.4] {
            let (v, d, dd) = h.value_slope_second(tau);
            assert!((v - tau * tau).abs() < 1e-12, "{v}");
            assert!((d - 2.0 * tau).abs() < 1e-10, "{d}");
            assert!((dd - 2.0).abs() < 1e-8, "{dd}");
        }
        assert_eq!(h.value_slope(1e300), (u[19], 0.0));
        assert_eq!(h.second(5.0), 0.0);
    }
}

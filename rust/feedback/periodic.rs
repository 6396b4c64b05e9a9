//! Periodic steady state of the feedback system under `u = amplitude cos(omega t)` (issue #20 item 2):
//! Newton shooting on one period with the monodromy matrix.
//!
//! The shooting map `P(x0) = x(T; x0)` over one period `T = 2 pi / omega` is the discrete RK4 map of
//! [`super::integrate`], whose sensitivity to `x0` is the monodromy matrix `M`; Newton solves
//! `P(x0) - x0 = 0` by `(M - I) dx = -(P(x0) - x0)`. At the periodic state `x0*`, the implicit
//! function theorem gives `dx0*/dtheta = -(M - I)^-1 dP/dtheta`, so the periodic output's Jacobian is
//! `dy/dtheta + dy/dx0 dx0*/dtheta`: exact for the discrete map, as the plain model's steady loop.

use nalgebra::Matrix3;

use super::{integrate, Feedback, Force, N_COLS, N_PARAMS, N_STATES};
use crate::error::{finite, CoreError, Result};

/// `amplitude cos(omega t)`, the library's sine (`rust/simulate.rs`).
struct Sine {
    amplitude: f64,
    omega: f64,
}

impl Force for Sine {
    #[inline(always)]
    fn at(&self, t: f64) -> f64 {
        self.amplitude * (self.omega * t).cos()
    }
}

/// One period of the periodic steady state.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicFeedback {
    /// `y(k T / samples)`, `k = 0..samples`.
    pub y: Vec<f64>,
    /// `d y_k / d theta` of the periodic solution, row-major `samples x N_PARAMS`.
    pub jacobian: Vec<f64>,
    /// The periodic state `x0* = [y, yd, z]` at `t = 0`.
    pub state: [f64; N_STATES],
    /// Newton iterations taken.
    pub iterations: usize,
}

/// The periodic steady state of `model` under `amplitude cos(omega t)` on `samples` points per
/// period (`substeps` RK4 steps each): `settle_periods` periods from rest, then Newton shooting until
/// `|P(x0) - x0| <= tol` times the state's scale (`[Y, omega Y, |amplitude| + |alpha| Y]`, `Y` the
/// period's largest `|y|`), at most `max_iter` iterations.
///
/// Errors: [`CoreError::InvalidParameter`] (`omega <= 0`, `samples < 4`, `substeps < 1`,
/// `tol <= 0`), [`CoreError::NonFinite`], [`CoreError::NotConverged`] (no periodic state found, or a
/// singular `M - I`), [`CoreError::BudgetExceeded`], [`CoreError::Interrupted`].
#[allow(clippy::too_many_arguments)]
pub fn periodic_feedback(
    model: &Feedback,
    amplitude: f64,
    omega: f64,
    samples: usize,
    substeps: usize,
    settle_periods: usize,
    max_iter: usize,
    tol: f64,
) -> Result<PeriodicFeedback> {
    finite("amplitude", amplitude)?;
    finite("omega", omega)?;
    finite("tol", tol)?;
    if omega <= 0.0 || samples < 4 || substeps < 1 || tol <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "omega = {omega} rad/s and tol = {tol} must be > 0, samples = {samples} >= 4, substeps = \
             {substeps} >= 1"
        )));
    }
    let periods = (settle_periods as u128) + (max_iter as u128) + 1;
    crate::budget::check_steps(
        "the feedback periodic state (periods x samples x substeps)",
        periods * (samples as u128) * (substeps as u128) * (N_COLS as u128),
    )?;
    let src = Sine { amplitude, omega };
    let dt = 2.0 * std::f64::consts::PI / omega / samples as f64;
    let mut x0 = [0.0; N_STATES];
    if settle_periods > 0 {
        let n = samples * settle_periods + 1;
        x0 = integrate(model, x0, &src, dt, n, substeps, false)?.state;
    }
    let alpha = model.theta()[3].abs();
    for iteration in 1..=max_iter {
        let sim = integrate(model, x0, &src, dt, samples + 1, substeps, true)?;
        let big_y = sim.y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let scale = [big_y, omega * big_y, amplitude.abs() + alpha * big_y];
        let f: [f64; N_STATES] = std::array::from_fn(|i| sim.state[i] - x0[i]);
        let monodromy = Matrix3::from_fn(|i, j| sim.state_jacobian[i][N_PARAMS + j]);
        let Some(inv) = (monodromy - Matrix3::identity()).try_inverse() else {
            return Err(CoreError::NotConverged(format!(
                "the monodromy matrix minus the identity is singular at iteration {iteration}: the \
                 feedback system has no isolated periodic state under this sine"
            )));
        };
        let converged = (0..N_STATES).all(|i| f[i].abs() <= tol * scale[i].max(f64::MIN_POSITIVE));
        if converged {
            return Ok(finish(&sim, &inv, x0, samples, iteration));
        }
        let step = inv * nalgebra::Vector3::new(f[0], f[1], f[2]);
        for (i, v) in x0.iter_mut().enumerate() {
            *v -= step[i];
        }
    }
    Err(CoreError::NotConverged(format!(
        "the Newton shooting did not find the periodic state in {max_iter} iterations (amplitude = \
         {amplitude}, omega = {omega} rad/s); settle more periods first or raise max_iter"
    )))
}

/// The periodic output and its total Jacobian at the converged `x0`.
fn finish(
    sim: &super::FeedbackSimulation,
    inv: &Matrix3<f64>,
    x0: [f64; N_STATES],
    samples: usize,
    iterations: usize,
) -> PeriodicFeedback {
    // dx0*/dtheta = -(M - I)^-1 dP/dtheta
    let mut dx0 = [[0.0; N_PARAMS]; N_STATES];
    for (i, row) in dx0.iter_mut().enumerate() {
        for (p, v) in row.iter_mut().enumerate() {
            *v = -(0..N_STATES)
                .map(|l| inv[(i, l)] * sim.state_jacobian[l][p])
                .sum::<f64>();
        }
    }
    let mut jac = Vec::with_capacity(samples * N_PARAMS);
    for k in 0..samples {
        let row = &sim.jacobian[k * N_COLS..(k + 1) * N_COLS];
        for p in 0..N_PARAMS {
            let via_x0: f64 = (0..N_STATES).map(|i| row[N_PARAMS + i] * dx0[i][p]).sum();
            jac.push(row[p] + via_x0);
        }
    }
    PeriodicFeedback {
        y: sim.y[..samples].to_vec(),
        jacobian: jac,
        state: x0,
        iterations,
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::super::{simulate_feedback, Sampling};
    use super::*;

    const BENCH: [f64; 7] = [2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0];

    #[test]
    fn the_periodic_state_repeats_and_matches_a_long_run() {
        let model = Feedback::new(&BENCH).unwrap();
        let omega = 2.0 * std::f64::consts::PI * 30.0;
        let per = periodic_feedback(&model, 40.0, omega, 64, 8, 2, 30, 1e-12).unwrap();
        // A long plain run from rest (damping ~1 %: ~60 periods to settle to 1e-6) ends on it.
        let periods = 400;
        let n = 64 * periods + 1;
        let dt = 2.0 * std::f64::consts::PI / omega / 64.0;
        let u: Vec<f64> = (0..n)
            .map(|k| 40.0 * (omega * k as f64 * dt).cos())
            .collect();
        let mut s = Sampling {
            dt,
            upsample: 1,
            substeps: 8,
        };
        s.upsample = 1;
        let long = simulate_feedback(&model, [0.0; 3], &u, s, false).unwrap();
        let tail = &long.y[n - 65..n - 1];
        let scale = per.y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        // Hermite-sampled vs analytic cosine: agreement to the interpolation error.
        for (a, b) in tail.iter().zip(&per.y) {
            assert!((a - b).abs() < 2e-3 * scale, "{a} {b}");
        }
    }

    #[test]
    fn periodic_jacobian_matches_finite_differences() {
        let omega = 2.0 * std::f64::consts::PI * 25.0;
        let model = Feedback::new(&BENCH).unwrap();
        let per = periodic_feedback(&model, 40.0, omega, 32, 8, 2, 40, 1e-13).unwrap();
        for p in 0..N_PARAMS {
            let step = 1e-6 * BENCH[p].abs();
            let run = |d: f64| {
                let mut th = BENCH;
                th[p] += d;
                periodic_feedback(
                    &Feedback::new(&th).unwrap(),
                    40.0,
                    omega,
                    32,
                    8,
                    2,
                    40,
                    1e-13,
                )
                .unwrap()
                .y
            };
            let (hi, lo) = (run(step), run(-step));
            let col: Vec<f64> = (0..32).map(|k| per.jacobian[k * N_PARAMS + p]).collect();
            let scale = col.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for k in 0..32 {
                let fd = (hi[k] - lo[k]) / (2.0 * step);
                assert!(
                    (fd - col[k]).abs() < 1e-4 * scale,
                    "param {p} k {k}: {fd} {}",
                    col[k]
                );
            }
        }
    }
}

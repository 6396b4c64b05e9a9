//! Bouc-Wen in feedback, the structure of the Noel-Schoukens benchmark (issue #20):
//!
//! `m ydd + c yd + k y + z = u`, `zdot = alpha yd - bg |yd| |z|^(nu-1) z - bd yd |z|^nu`,
//!
//! with state `x = [y, yd, z]`, integrated by classical RK4 with `substeps` steps per output sample,
//! and the **forward sensitivities**: the exact Jacobian of the discrete RK4 map with respect to the
//! seven physical parameters `theta = [m, c, k, alpha, bg, bd, nu]` and the initial state
//! `x0 = [y0, yd0, z0]` (ten columns, in that order), propagated stage by stage alongside the state.
//!
//! The benchmark writes the hysteresis as `alpha yd - beta (gamma |yd||z|^(nu-1) z + delta yd |z|^nu)`:
//! `beta` only ever multiplies `gamma` and `delta`, so `(beta, gamma, delta)` and
//! `(s beta, gamma / s, delta / s)` give the same output for every `s`; the identifiable
//! combinations are `bg = beta gamma` and `bd = beta delta`, which this module takes as its
//! parameters (the Python side reports `gamma`, `delta` at a fixed `beta`).
//!
//! The input is given as samples on a grid `dt / upsample` (`upsample >= 1`; 1 is the output grid)
//! and interpolated between them by cubic Hermite with Catmull-Rom slopes, as `rust/simulate.rs`
//! does; past its last sample it holds its last value. An oversampled input (band-limited
//! reconstruction done by the caller) removes the interpolation error at high frequency.
//!
//! ## Reference
//! J.-P. Noel and M. Schoukens, *Hysteretic benchmark with a dynamic nonlinearity*, Workshop on
//! nonlinear system identification benchmarks, 2016; M. Schoukens and J.-P. Noel, *Three benchmarks
//! addressing open challenges in nonlinear system identification*, IFAC-PapersOnLine 50(1), 2017.

use crate::error::{all_finite, finite, CoreError, Result};
use crate::hermite::Hermite;

mod periodic;
pub use periodic::{periodic_feedback, PeriodicFeedback};

/// Physical parameters `[m, c, k, alpha, bg, bd, nu]`.
pub const N_PARAMS: usize = 7;
/// States `[y, yd, z]`.
pub const N_STATES: usize = 3;
/// Jacobian columns: the parameters, then the initial state.
pub const N_COLS: usize = N_PARAMS + N_STATES;

/// Output samples between two cancellation checks.
const CHECK_EVERY_SAMPLES: usize = 512;

/// Validated physical parameters of the feedback system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feedback {
    m: f64,
    c: f64,
    k: f64,
    alpha: f64,
    bg: f64,
    bd: f64,
    nu: f64,
}

/// `sgn` with `sgn(0) = 0` (as `numpy.sign`).
#[inline(always)]
fn sgn(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// `f(x)`, and with `jac` its Jacobians in `x` (rows of `zdot` only: the others are constant) and
/// in the parameters.
struct Eval {
    f: [f64; N_STATES],
    /// `d zdot / d yd`, `d zdot / d z`.
    dz_v: f64,
    dz_z: f64,
    /// `d ydd / d (m, c, k)`.
    dv_p: [f64; 3],
    /// `d zdot / d (alpha, bg, bd, nu)`.
    dz_p: [f64; 4],
}

impl Feedback {
    /// Validates `theta = [m, c, k, alpha, bg, bd, nu]`: all finite, `m > 0`, `nu > 0`.
    ///
    /// Errors: [`CoreError::InvalidParameter`] (wrong length, `m <= 0`, `nu <= 0`),
    /// [`CoreError::NonFinite`].
    pub fn new(theta: &[f64]) -> Result<Self> {
        if theta.len() != N_PARAMS {
            return Err(CoreError::InvalidParameter(format!(
                "theta must hold the {N_PARAMS} parameters [m, c, k, alpha, beta*gamma, \
                 beta*delta, nu], got {}",
                theta.len()
            )));
        }
        let names = ["m", "c", "k", "alpha", "beta*gamma", "beta*delta", "nu"];
        for (name, v) in names.iter().zip(theta) {
            finite(name, *v)?;
        }
        let [m, c, k, alpha, bg, bd, nu] = [
            theta[0], theta[1], theta[2], theta[3], theta[4], theta[5], theta[6],
        ];
        if m <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "m = {m} must be > 0 (the mass divides the force balance)"
            )));
        }
        if nu <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "nu = {nu} must be > 0 (the exponent of |z|)"
            )));
        }
        Ok(Self {
            m,
            c,
            k,
            alpha,
            bg,
            bd,
            nu,
        })
    }

    /// The parameters as `[m, c, k, alpha, bg, bd, nu]`.
    pub fn theta(&self) -> [f64; N_PARAMS] {
        [
            self.m, self.c, self.k, self.alpha, self.bg, self.bd, self.nu,
        ]
    }

    /// The right-hand side at state `x` and force `u`; with `jac` also its derivatives.
    #[inline(always)]
    fn eval(&self, x: &[f64; N_STATES], u: f64, jac: bool) -> Eval {
        let [y, v, z] = *x;
        let az = z.abs();
        let sz = sgn(z);
        let wmu = az.powf(self.nu);
        let av = v.abs();
        let vdot = (u - self.c * v - self.k * y - z) / self.m;
        let zdot = self.alpha * v - self.bg * av * sz * wmu - self.bd * v * wmu;
        let mut e = Eval {
            f: [v, vdot, zdot],
            dz_v: 0.0,
            dz_z: 0.0,
            dv_p: [0.0; 3],
            dz_p: [0.0; 4],
        };
        if jac {
            // |z|^(nu-1): at z = 0 the limit for nu = 1 (1) and nu > 1 (0); for nu < 1 the
            // derivative is infinite there and the measure-zero point is given 0.
            let pz = if az > 0.0 {
                wmu / az
            } else if self.nu == 1.0 {
                1.0
            } else {
                0.0
            };
            let lz = if az > 0.0 { az.ln() } else { 0.0 };
            e.dz_v = self.alpha - self.bg * sgn(v) * sz * wmu - self.bd * wmu;
            e.dz_z = -self.nu * pz * (self.bg * av + self.bd * v * sz);
            e.dv_p = [-vdot / self.m, -v / self.m, -y / self.m];
            e.dz_p = [
                v,
                -av * sz * wmu,
                -v * wmu,
                -(self.bg * av * sz + self.bd * v) * wmu * lz,
            ];
        }
        e
    }

    /// The sensitivity derivative `K = f_x S + [f_p | 0]` (3 x N_COLS) at one stage.
    // The three rows are written from the same column of S: one index reads clearer than three zips.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sens_rate(&self, e: &Eval, s: &[[f64; N_COLS]; N_STATES], out: &mut [[f64; N_COLS]; 3]) {
        let inv_m = 1.0 / self.m;
        for j in 0..N_COLS {
            out[0][j] = s[1][j];
            out[1][j] = -(self.k * s[0][j] + self.c * s[1][j] + s[2][j]) * inv_m;
            out[2][j] = e.dz_v * s[1][j] + e.dz_z * s[2][j];
        }
        for (i, d) in e.dv_p.iter().enumerate() {
            out[1][i] += d;
        }
        for (i, d) in e.dz_p.iter().enumerate() {
            out[2][3 + i] += d;
        }
    }
}

/// A simulated record: `y` on the output grid, and with sensitivities `d y_k / d [theta, x0]`
/// (row-major, `n_samples x N_COLS`), and the state after the last sample.
#[derive(Debug, Clone, PartialEq)]
pub struct FeedbackSimulation {
    /// Displacement `y_k = y(k dt)`.
    pub y: Vec<f64>,
    /// Row `k` holds `d y_k / d [m, c, k, alpha, bg, bd, nu, y0, yd0, z0]`; empty without
    /// sensitivities.
    pub jacobian: Vec<f64>,
    /// The state `[y, yd, z]` at the last output sample.
    pub state: [f64; N_STATES],
    /// Its sensitivity (3 x N_COLS; zeros without sensitivities).
    pub state_jacobian: [[f64; N_COLS]; N_STATES],
}

/// The sampling of one record: output step `dt`, input oversampling `upsample` (the input grid is
/// `dt / upsample`), RK4 `substeps` per output sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Output step (s), `> 0`.
    pub dt: f64,
    /// Input samples per output sample, `>= 1`.
    pub upsample: usize,
    /// RK4 steps per output sample, `>= 1`.
    pub substeps: usize,
}

impl Sampling {
    /// Checks the sampling and returns the number of output samples of an input of `n_input`
    /// samples: `(n_input - 1) / upsample + 1`.
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`],
    /// [`CoreError::InsufficientData`] (fewer than 2 input samples), [`CoreError::BudgetExceeded`].
    pub fn output_len(&self, n_input: usize) -> Result<usize> {
        let dt = finite("dt", self.dt)?;
        if dt <= 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "dt = {dt} s must be > 0"
            )));
        }
        if self.upsample < 1 || self.substeps < 1 {
            return Err(CoreError::InvalidParameter(format!(
                "upsample = {} and substeps = {} must be >= 1",
                self.upsample, self.substeps
            )));
        }
        if n_input < 2 {
            return Err(CoreError::InsufficientData(format!(
                "a sampled input needs at least 2 samples, got {n_input}"
            )));
        }
        let n = (n_input - 1) / self.upsample + 1;
        crate::budget::check_simulation(n, self.substeps)?;
        Ok(n)
    }
}

/// Simulates the feedback system from the state `x0 = [y0, yd0, z0]` at `t = 0` under the input
/// samples `u` (grid `dt / upsample`); with `sensitivities`, also the exact Jacobian of the
/// discrete RK4 map with respect to `[theta, x0]`.
///
/// Errors: those of [`Sampling::output_len`] and [`Feedback::new`] (through the caller),
/// [`CoreError::NonFinite`] for non-finite `u` or `x0` and for a blow-up of the model,
/// [`CoreError::BudgetExceeded`], [`CoreError::Interrupted`].
pub fn simulate_feedback(
    model: &Feedback,
    x0: [f64; N_STATES],
    u: &[f64],
    sampling: Sampling,
    sensitivities: bool,
) -> Result<FeedbackSimulation> {
    all_finite("u", u)?;
    all_finite("x0", &x0)?;
    let n = sampling.output_len(u.len())?;
    if sensitivities {
        crate::budget::check_bytes("the feedback Jacobian", (n as u128) * (N_COLS as u128) * 8)?;
    }
    let src = Hermite::new(u, sampling.dt / sampling.upsample as f64);
    integrate(
        model,
        x0,
        &src,
        sampling.dt,
        n,
        sampling.substeps,
        sensitivities,
    )
}

/// The applied force `u(t)` at any time `t >= 0`.
pub(crate) trait Force {
    fn at(&self, t: f64) -> f64;
}

impl Force for Hermite<'_> {
    #[inline(always)]
    fn at(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return self.u[0];
        }
        self.value(t)
    }
}

/// RK4 over `n` output samples of step `dt` (`substeps` steps each) from `x0`, with sensitivities.
///
/// Errors: [`CoreError::NonFinite`] for a blow-up, [`CoreError::Interrupted`].
pub(crate) fn integrate<F: Force>(
    model: &Feedback,
    x0: [f64; N_STATES],
    src: &F,
    dt: f64,
    n: usize,
    substeps: usize,
    sensitivities: bool,
) -> Result<FeedbackSimulation> {
    let h = dt / substeps as f64;
    let mut x = x0;
    let mut s = [[0.0; N_COLS]; N_STATES];
    for (i, row) in s.iter_mut().enumerate() {
        row[N_PARAMS + i] = 1.0;
    }
    let mut y = Vec::with_capacity(n);
    let mut jac = Vec::with_capacity(if sensitivities { n * N_COLS } else { 0 });
    for k in 0..n {
        y.push(x[0]);
        if sensitivities {
            jac.extend_from_slice(&s[0]);
        }
        if k + 1 == n {
            break;
        }
        if k % CHECK_EVERY_SAMPLES == 0 {
            crate::cancel::checkpoint()?;
        }
        let t = k as f64 * dt;
        for step in 0..substeps {
            let ts = t + step as f64 * h;
            let inputs = [src.at(ts), src.at(ts + 0.5 * h), src.at(ts + h)];
            rk4_step(model, &mut x, &mut s, inputs, h, sensitivities);
        }
    }
    if let Some(k) = y.iter().position(|v| !v.is_finite()) {
        return Err(blow_up(model, k, dt));
    }
    if !x.iter().all(|v| v.is_finite()) {
        return Err(blow_up(model, n - 1, dt));
    }
    Ok(FeedbackSimulation {
        y,
        jacobian: jac,
        state: x,
        state_jacobian: s,
    })
}

fn blow_up(model: &Feedback, k: usize, dt: f64) -> CoreError {
    CoreError::NonFinite(format!(
        "the feedback simulation blew up at sample {k} (t = {:.6e} s); the parameters [m, c, k, \
         alpha, beta*gamma, beta*delta, nu] = {:?} make the state overflow at this input level; use \
         parameters of moderate size or more substeps",
        k as f64 * dt,
        model.theta()
    ))
}

/// One RK4 step of length `h` of the state and (with `sens`) its sensitivity, with the input at
/// the step's start, middle and end.
#[inline(always)]
fn rk4_step(
    model: &Feedback,
    x: &mut [f64; N_STATES],
    s: &mut [[f64; N_COLS]; N_STATES],
    [u0, um, u1]: [f64; 3],
    h: f64,
    sens: bool,
) {
    let half = 0.5 * h;
    let add = |a: &[f64; N_STATES], c: f64, d: &[f64; N_STATES]| {
        [a[0] + c * d[0], a[1] + c * d[1], a[2] + c * d[2]]
    };
    let e1 = model.eval(x, u0, sens);
    let x2 = add(x, half, &e1.f);
    let e2 = model.eval(&x2, um, sens);
    let x3 = add(x, half, &e2.f);
    let e3 = model.eval(&x3, um, sens);
    let x4 = add(x, h, &e3.f);
    let e4 = model.eval(&x4, u1, sens);
    let h6 = h / 6.0;
    for (i, xi) in x.iter_mut().enumerate() {
        *xi += h6 * (e1.f[i] + 2.0 * e2.f[i] + 2.0 * e3.f[i] + e4.f[i]);
    }
    if !sens {
        return;
    }
    let stage = |base: &[[f64; N_COLS]; N_STATES], c: f64, d: &[[f64; N_COLS]; N_STATES]| {
        let mut out = *base;
        for (o, dr) in out.iter_mut().zip(d) {
            for (oj, dj) in o.iter_mut().zip(dr) {
                *oj += c * dj;
            }
        }
        out
    };
    let mut k1 = [[0.0; N_COLS]; N_STATES];
    let mut k2 = k1;
    let mut k3 = k1;
    let mut k4 = k1;
    model.sens_rate(&e1, s, &mut k1);
    model.sens_rate(&e2, &stage(s, half, &k1), &mut k2);
    model.sens_rate(&e3, &stage(s, half, &k2), &mut k3);
    model.sens_rate(&e4, &stage(s, h, &k3), &mut k4);
    for (i, row) in s.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v += h6 * (k1[i][j] + 2.0 * k2[i][j] + 2.0 * k3[i][j] + k4[i][j]);
        }
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    const BENCH: [f64; 7] = [2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0];

    fn input(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 / 750.0;
                40.0 * (2.0 * std::f64::consts::PI * 23.0 * t).sin()
                    + 15.0 * (2.0 * std::f64::consts::PI * 61.0 * t + 0.4).cos()
            })
            .collect()
    }

    fn sampling() -> Sampling {
        Sampling {
            dt: 1.0 / 750.0,
            upsample: 1,
            substeps: 20,
        }
    }

    #[test]
    fn linear_limit_is_a_damped_oscillator_at_rest() {
        // With bg = bd = 0 and nu = 1 the system is linear: zero input from rest stays at rest,
        // and a scaled input scales the output exactly (to rounding).
        let lin = Feedback::new(&[2.0, 10.0, 5e4, 5e4, 0.0, 0.0, 1.0]).unwrap();
        let u = input(400);
        let a = simulate_feedback(&lin, [0.0; 3], &u, sampling(), false).unwrap();
        let u3: Vec<f64> = u.iter().map(|v| 3.0 * v).collect();
        let b = simulate_feedback(&lin, [0.0; 3], &u3, sampling(), false).unwrap();
        let scale = a.y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (ya, yb) in a.y.iter().zip(&b.y) {
            assert!((3.0 * ya - yb).abs() <= 1e-12 * scale, "{ya} {yb}");
        }
        let zero = simulate_feedback(&lin, [0.0; 3], &[0.0; 50], sampling(), false).unwrap();
        assert!(zero.y.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let model = Feedback::new(&BENCH).unwrap();
        let u = input(300);
        let x0 = [1e-4, -2e-3, 3.0];
        let sim = simulate_feedback(&model, x0, &u, sampling(), true).unwrap();
        let mut p: Vec<f64> = BENCH.iter().chain(x0.iter()).copied().collect();
        for j in 0..N_COLS {
            let step = 1e-6 * p[j].abs().max(1e-3);
            let run = |p: &[f64]| {
                let m = Feedback::new(&p[..N_PARAMS]).unwrap();
                simulate_feedback(&m, [p[7], p[8], p[9]], &u, sampling(), false)
                    .unwrap()
                    .y
            };
            let keep = p[j];
            p[j] = keep + step;
            let hi = run(&p);
            p[j] = keep - step;
            let lo = run(&p);
            p[j] = keep;
            let col: Vec<f64> = (0..sim.y.len())
                .map(|k| sim.jacobian[k * N_COLS + j])
                .collect();
            let scale = col.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            assert!(scale > 0.0, "column {j} is zero");
            for k in 0..sim.y.len() {
                let fd = (hi[k] - lo[k]) / (2.0 * step);
                assert!(
                    (fd - col[k]).abs() <= 1e-5 * scale,
                    "column {j} sample {k}: {fd} vs {}",
                    col[k]
                );
            }
        }
    }

    #[test]
    fn bad_input_is_named() {
        let model = Feedback::new(&BENCH).unwrap();
        let e = Feedback::new(&[0.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("m = 0"), "{e}");
        let e = Feedback::new(&BENCH[..6]).unwrap_err();
        assert!(matches!(e, CoreError::InvalidParameter(_)));
        let e = simulate_feedback(&model, [0.0; 3], &[1.0, f64::NAN], sampling(), false);
        assert!(matches!(e, Err(CoreError::NonFinite(_))));
        let e = simulate_feedback(&model, [0.0; 3], &[1.0], sampling(), false);
        assert!(matches!(e, Err(CoreError::InsufficientData(_))));
        let mut bad = sampling();
        bad.dt = -1.0;
        let e = simulate_feedback(&model, [0.0; 3], &[1.0, 2.0], bad, false);
        assert!(matches!(e, Err(CoreError::InvalidParameter(_))));
    }

    #[test]
    fn upsampled_input_on_the_same_waveform_agrees() {
        // The same smooth input given at 1x and 8x: the outputs agree to the interpolation error.
        let model = Feedback::new(&BENCH).unwrap();
        let f = |t: f64| 30.0 * (2.0 * std::f64::consts::PI * 9.0 * t).sin();
        let coarse: Vec<f64> = (0..301).map(|i| f(i as f64 / 750.0)).collect();
        let fine: Vec<f64> = (0..2401).map(|i| f(i as f64 / 6000.0)).collect();
        let a = simulate_feedback(&model, [0.0; 3], &coarse, sampling(), false).unwrap();
        let mut s8 = sampling();
        s8.upsample = 8;
        let b = simulate_feedback(&model, [0.0; 3], &fine, s8, false).unwrap();
        assert_eq!(a.y.len(), b.y.len());
        let scale = b.y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let err =
            a.y.iter()
                .zip(&b.y)
                .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(err < 1e-3 * scale, "{err} vs {scale}");
    }
}

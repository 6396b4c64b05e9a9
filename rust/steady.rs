//! Steady-state Bouc-Wen loop under a sine, computed directly, with its parameter sensitivities.
//!
//! With alpha = 1 (2b) and `x = A cos(theta)`, `theta = omega t - phi` (3a), Bouc-Wen is rate
//! independent, so the loop obeys
//! `dw/dtheta = x'(theta) (1 - beta sgn(x') sgn(w) |w|^mu - gamma |w|^mu)`, `x' = -A sin(theta)`.
//! Its steady state is odd-symmetric, `w(theta + pi) = -w(theta)` (Proposition 2 and the
//! symmetry of the sine), so one half cycle suffices: RK4 from `theta = 0` to `pi`, and a
//! safeguarded Newton iteration on `w(0)` until `w(pi) = -w(0)`. No settling is simulated.
//!
//! The forward sensitivity equations ride along: `Phi = dw/dw(0)` and `S_p = dw/dp` for
//! `p = beta, gamma, mu, A`. Periodicity fixes the sensitivity of the start value,
//! `dw(0)/dp = -S_p(pi) / (1 + Phi(pi))`, and `dw/dphi = -dw/dtheta`.
//!
//! The half cycle is integrated on the lattice that the sample grid `theta_j = 2 pi j/P - phi`
//! folds onto modulo pi, so every sample is hit exactly, without interpolation.
//!
//! ## Reference
//! *Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose
//! equation numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2):
//! F. Ikhouane and J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control
//! using the Bouc-Wen Model*, Wiley, 2007.

use crate::bouc_wen::sgn;
use crate::error::{finite, CoreError, Result};
use std::f64::consts::PI;

/// Newton iterations allowed for the shooting on `w(0)`.
const SHOOT_MAX_ITER: usize = 60;
/// Relative tolerance of the periodicity condition `|w(pi) + w(0)| <= tol * w_bound`.
const SHOOT_RTOL: f64 = 1e-13;

/// Number of state components integrated: `w`, `Phi`, `S_beta`, `S_gamma`, `S_mu`, `S_A`.
const NS: usize = 6;
/// The shootings' first bracket is `|w(0)| < BRACKET_SLACK w_bound`, not `< w_bound`: a saturated
/// loop (`|A|` many times the loop's width, `Phi(pi)` ~ 1e-160) has its `w(0)` at the bound itself,
/// and its first Newton step lands exactly there; with the open bracket `(-w_bound, w_bound)` every
/// such step was refused and the shooting bisected, halving the residual per pass (20 coarse and
/// 45 fine passes instead of 2 and 1: most of the MR damper's fit time at 0 A). The slack only
/// admits the Newton step; the converged loop meets the same tolerance.
const BRACKET_SLACK: f64 = 1.0 + 1e-9;
/// Components of a reduced shooting pass: `w` and `Phi` (the residual and its slope).
const NR: usize = 2;
/// A fine shooting pass integrates the sensitivities and records the loop only when the previous
/// pass's residual is within this many `w_bound`s (Newton then converges on the next pass); the
/// other passes carry `w` and `Phi` alone. A reduced pass that converges is followed by one full
/// pass from the same `w(0)`, so the loop returned is the same bit for bit either way.
const FULL_PASS_RESIDUAL: f64 = 1e-6;
/// The first fine pass integrates the sensitivities too when the coarse shooting's last `|Phi(pi)|`
/// is below this: the loop has saturated before `theta = pi`, its end forgets `w(0)`, and the fine
/// pass from the coarse `w(0)` meets the tolerance at once (MR damper, 1 A: 7294 of 8035 such
/// loops converged on that pass, which was then run again with the sensitivities; 349 of 6523 with
/// `|Phi(pi)|` in 1e-12 .. 1e-6). Either kind of pass gives `w` and `Phi` bit for bit, so the loop
/// returned is the same; only the wasted reduced pass goes.
const SATURATED_PHI: f64 = 1e-12;

/// Index of each sensitivity in [`SteadyLoop::jac`] rows.
pub const D_BETA: usize = 0;
/// d w / d gamma.
pub const D_GAMMA: usize = 1;
/// d w / d mu.
pub const D_MU: usize = 2;
/// d w / d A (A = U |G| signed: the amplitude of x).
pub const D_AMPLITUDE: usize = 3;
/// d w / d phi.
pub const D_PHI: usize = 4;

/// The steady loop on the sample grid and its Jacobian.
#[derive(Debug, Clone)]
pub struct SteadyLoop {
    /// `w(t_j)`, `t_j = j T / P`, j = 0..P.
    pub w: Vec<f64>,
    /// `d w(t_j) / d(beta, gamma, mu, A, phi)`, one row per sample.
    pub jac: Vec<[f64; 5]>,
    /// `w` at `theta = 0` (the top of `x`).
    pub w_top: f64,
    /// Newton iterations of the shooting.
    pub iterations: usize,
}

#[derive(Clone, Copy)]
struct Params {
    a: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
}

/// Rate of the augmented state at `theta`.
#[inline(always)]
fn rhs(p: &Params, theta: f64, y: &[f64; NS]) -> [f64; NS] {
    rhs_sin::<NS>(p, theta.sin(), y)
}

/// [`rhs`] with `sin(theta)` given (the half cycle takes it from tables, see [`SinTable`]).
///
/// `N` is the number of state components integrated: [`NS`] (the loop and every sensitivity) or
/// [`NR`] (`w` and `Phi` only, what a shooting pass needs to take its Newton step). Each component
/// is formed by the same operations whatever `N`, so `w` and `Phi` are equal bit for bit.
#[inline(always)]
fn rhs_sin<const N: usize>(p: &Params, sin_t: f64, y: &[f64; N]) -> [f64; N] {
    let xt = -p.a * sin_t;
    let w = y[0];
    let aw = w.abs();
    let sw = sgn(w);
    let sx = sgn(xt);
    let (wmu, wmu1, lnw) = if aw > 0.0 {
        let lnw = aw.ln();
        let wmu = (p.mu * lnw).exp();
        (wmu, wmu / aw, lnw)
    } else {
        (0.0, 0.0, 0.0)
    };
    let bracket = 1.0 - p.beta * sx * sw * wmu - p.gamma * wmu;
    let f = xt * bracket;
    // d/dw of sgn(w)|w|^mu is mu |w|^(mu-1); of |w|^mu it is mu |w|^(mu-1) sgn(w).
    let fw = xt * (-p.beta * sx * p.mu * wmu1 - p.gamma * p.mu * wmu1 * sw);
    let mut out = [0.0; N];
    out[0] = f;
    out[1] = fw * y[1];
    if N == NS {
        let fbeta = -xt * sx * sw * wmu;
        let fgamma = -xt * wmu;
        let fmu = xt * (-p.beta * sx * sw - p.gamma) * wmu * lnw;
        let fa = -sin_t * bracket;
        out[2] = fw * y[2] + fbeta;
        out[3] = fw * y[3] + fgamma;
        out[4] = fw * y[4] + fmu;
        out[5] = fw * y[5] + fa;
    }
    out
}

#[inline(always)]
fn axpy<const N: usize>(y: &[f64; N], h: f64, k: &[f64; N]) -> [f64; N] {
    let mut out = *y;
    for i in 0..N {
        out[i] += h * k[i];
    }
    out
}

/// One classical RK4 step of length `h` from `theta`.
#[inline(always)]
fn rk4<const N: usize>(p: &Params, theta: f64, y: &mut [f64; N], h: f64) {
    let sines = (theta.sin(), (theta + 0.5 * h).sin(), (theta + h).sin());
    rk4_sin(p, sines, y, h);
}

/// One classical RK4 step of length `h` with `sin(theta)` at its start, middle and end given.
#[inline(always)]
fn rk4_sin<const N: usize>(p: &Params, (s1, sm, s4): (f64, f64, f64), y: &mut [f64; N], h: f64) {
    let k1 = rhs_sin(p, s1, y);
    let k2 = rhs_sin(p, sm, &axpy(y, 0.5 * h, &k1));
    let k3 = rhs_sin(p, sm, &axpy(y, 0.5 * h, &k2));
    let k4 = rhs_sin(p, s4, &axpy(y, h, &k3));
    for i in 0..N {
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// `sin` at every RK4 stage of the lattice intervals, for all the shooting passes of one loop.
///
/// Stage `j` (`0..=2 substeps`) of interval `k` sits at `offset + k L + j h/2`; its sine is
/// `sin(theta_k) cos(j h/2) + cos(theta_k) sin(j h/2)` from one `sin`/`cos` pair per lattice point
/// and per stage offset, computed once per [`steady_loop`] instead of one `sin` per stage and pass
/// (a few ulps from the direct evaluation; issue #8). The first (offset) segment and the last
/// interval, whose steps differ, are evaluated directly.
struct SinTable {
    /// `(sin, cos)` of `offset + k L`, per lattice point.
    points: Vec<(f64, f64)>,
    /// `(sin, cos)` of `j h / 2`, `j = 0..=2 substeps`, `h = L / substeps`.
    stages: Vec<(f64, f64)>,
}

impl SinTable {
    fn new(lat: &Lattice, substeps: usize) -> Self {
        let h = lat.spacing / substeps as f64;
        Self {
            points: (0..lat.len)
                .map(|k| (lat.offset + k as f64 * lat.spacing).sin_cos())
                .collect(),
            stages: (0..=2 * substeps)
                .map(|j| (0.5 * j as f64 * h).sin_cos())
                .collect(),
        }
    }

    /// `sin(theta_k + j h/2)`.
    #[inline(always)]
    fn at(&self, k: usize, j: usize) -> f64 {
        let (sk, ck) = self.points[k];
        let (sj, cj) = self.stages[j];
        sk * cj + ck * sj
    }
}

/// The lattice `delta + k L`, k = 0..n, that the sample phases fold onto modulo pi.
struct Lattice {
    spacing: f64,
    offset: f64,
    len: usize,
    /// Per sample: (lattice index, sign of the half cycle).
    map: Vec<(usize, f64)>,
}

impl Lattice {
    fn new(p: usize, phi: f64) -> Self {
        // theta_j = 2 pi j / P - phi = (c j - phi/L) L with L = 2 pi/P (P even) or pi/P (P odd).
        let (c, len) = if p % 2 == 0 {
            (1_i64, p / 2)
        } else {
            (2_i64, p)
        };
        let spacing = PI / len as f64;
        let q = phi / spacing;
        let qf = q.floor();
        let r = q - qf;
        let (offset, shift) = if r > 0.0 {
            ((1.0 - r) * spacing, qf as i64 + 1)
        } else {
            (0.0, qf as i64)
        };
        let n = len as i64;
        let map = (0..p as i64)
            .map(|j| {
                let i = c * j - shift;
                let half = i.div_euclid(n);
                let m = i.rem_euclid(n) as usize;
                (m, if half % 2 == 0 { 1.0 } else { -1.0 })
            })
            .collect();
        Self {
            spacing,
            offset,
            len,
            map,
        }
    }
}

/// Integrates the half cycle from `w(0) = w_top`, recording the state at every lattice point when
/// `rec` is given. Returns the state at `theta = pi`.
fn half_cycle<const N: usize>(
    p: &Params,
    lat: &Lattice,
    table: &SinTable,
    w_top: f64,
    substeps: usize,
    mut rec: Option<&mut [[f64; N]]>,
) -> [f64; N] {
    let mut y = [0.0; N];
    y[0] = w_top;
    y[1] = 1.0;
    let mut theta = 0.0;
    let sub = substeps as f64;
    if lat.offset > 0.0 {
        let h = lat.offset / sub;
        for s in 0..substeps {
            rk4(p, s as f64 * h, &mut y, h);
        }
        theta = lat.offset;
    }
    let h = lat.spacing / sub;
    let check_mask = (crate::cancel::CHECK_EVERY_STEPS / substeps)
        .max(1)
        .next_power_of_two()
        - 1;
    for k in 0..lat.len {
        // A cancelled half cycle stops early; the caller's checkpoint turns it into the error.
        if k & check_mask == 0 && crate::cancel::requested() {
            return y;
        }
        if let Some(rec) = rec.as_deref_mut() {
            rec[k] = y;
        }
        let start = lat.offset + k as f64 * lat.spacing;
        // The last lattice interval ends at pi, not at the next lattice point.
        let (len, base) = if k + 1 == lat.len {
            (PI - start, start)
        } else {
            (lat.spacing, start)
        };
        if k + 1 == lat.len {
            let hh = len / sub;
            for s in 0..substeps {
                rk4(p, base + s as f64 * hh, &mut y, hh);
            }
        } else {
            for s in 0..substeps {
                let sines = (
                    table.at(k, 2 * s),
                    table.at(k, 2 * s + 1),
                    table.at(k, 2 * s + 2),
                );
                rk4_sin(p, sines, &mut y, h);
            }
        }
        theta = base + len;
    }
    debug_assert!((theta - PI).abs() < 1e-9);
    y
}

/// Largest lattice [`steady_loop`] accepts (memory: about 50 bytes per sample).
pub const MAX_SAMPLES_PER_PERIOD: usize = 1 << 24;
/// Largest number of RK4 steps per period [`steady_loop`] accepts (time: about 0.1 us per step).
pub const MAX_STEPS_PER_PERIOD: usize = 1 << 27;

/// Relative tolerance of the coarse shooting (one RK4 step per lattice interval) that gives the
/// fine shooting its start.
const COARSE_RTOL: f64 = 1e-9;
/// Newton iterations allowed for the coarse shooting (it only proposes a start).
const COARSE_MAX_ITER: usize = 20;

/// `w(0)` of the periodic half cycle with one RK4 step per lattice interval and the last pass's
/// `Phi(pi)`, or `None` when that shooting does not converge (the fine one then starts from 0, as it
/// always did).
fn coarse_top<const N: usize>(
    p: &Params,
    lat: &Lattice,
    table: &SinTable,
    bound: f64,
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (-bound * BRACKET_SLACK, bound * BRACKET_SLACK);
    let mut w_top = 0.0;
    for _ in 0..COARSE_MAX_ITER {
        // Only the residual and its slope are used: `w` and `Phi` alone (equal bit for bit).
        let end = half_cycle::<N>(p, lat, table, w_top, 1, None);
        let h = end[0] + w_top;
        if !h.is_finite() {
            return None;
        }
        if h.abs() <= COARSE_RTOL * bound {
            return Some((w_top, end[1]));
        }
        if h > 0.0 {
            hi = w_top;
        } else {
            lo = w_top;
        }
        let newton = w_top - h / (end[1] + 1.0);
        w_top = if newton > lo && newton < hi && newton.is_finite() {
            newton
        } else {
            0.5 * (lo + hi)
        };
    }
    None
}

/// The sample grid and RK4 steps of a steady-loop solver (this one and the path loop): at least 4
/// samples and 1 substep, within [`MAX_SAMPLES_PER_PERIOD`] and [`MAX_STEPS_PER_PERIOD`].
pub(crate) fn check_grid(samples_per_period: usize, substeps: usize) -> Result<()> {
    if samples_per_period < 4 {
        return Err(CoreError::InsufficientData(format!(
            "samples_per_period = {samples_per_period}: at least 4 are needed"
        )));
    }
    if substeps < 1 {
        return Err(CoreError::InvalidParameter(format!(
            "substeps = {substeps} must be >= 1"
        )));
    }
    if samples_per_period > MAX_SAMPLES_PER_PERIOD
        || samples_per_period.saturating_mul(substeps) > MAX_STEPS_PER_PERIOD
    {
        return Err(CoreError::InvalidParameter(format!(
            "samples_per_period = {samples_per_period} with substeps = {substeps} exceeds the \
             limits ({MAX_SAMPLES_PER_PERIOD} samples, {MAX_STEPS_PER_PERIOD} RK4 steps per \
             period); a loop this fine gains nothing over a few thousand samples"
        )));
    }
    Ok(())
}

/// Steady loop of (2b) driven by `x = amplitude cos(omega t - phi)`, sampled at `P` points per
/// period (`t_j = j T / P`), with `substeps` RK4 steps per lattice interval.
///
/// `amplitude` is `A = U |G|` (units of x, may be negative); `beta`, `gamma` in `1/[w]^mu`;
/// `phi` in rad. Returns `w` (length P) and its Jacobian rows `d/d(beta, gamma, mu, A, phi)`.
///
/// Errors: non-finite inputs, `mu <= 1`, `beta + gamma <= 0` (unbounded loop), `P < 4`,
/// `substeps < 1`, `amplitude == 0`, a lattice above [`MAX_SAMPLES_PER_PERIOD`] or
/// [`MAX_STEPS_PER_PERIOD`], and a loop that overflows; [`CoreError::NotConverged`] when the
/// shooting does not converge in `SHOOT_MAX_ITER` iterations.
pub fn steady_loop(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    phi: f64,
    samples_per_period: usize,
    substeps: usize,
) -> Result<SteadyLoop> {
    let args = (amplitude, beta, gamma, mu, phi);
    steady_loop_passes(args, samples_per_period, substeps, true)
}

/// [`steady_loop`] with every shooting pass reduced to `w` and `Phi` but the converged one
/// (`reduced`), or with every pass full (the solver as it was before; the tests hold the two equal
/// bit for bit).
fn steady_loop_passes(
    (amplitude, beta, gamma, mu, phi): (f64, f64, f64, f64, f64),
    samples_per_period: usize,
    substeps: usize,
    reduced: bool,
) -> Result<SteadyLoop> {
    for (name, v) in [
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("phi", phi),
    ] {
        finite(name, v)?;
    }
    if mu <= 1.0 {
        return Err(CoreError::InvalidParameter(format!(
            "mu = {mu} must be > 1 in the identification model"
        )));
    }
    if beta + gamma <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma = {} must be > 0: otherwise the loop is unbounded and has no steady state",
            beta + gamma
        )));
    }
    if amplitude == 0.0 {
        return Err(CoreError::ZeroAmplitude(
            "the amplitude of x is 0: the loop is a point".into(),
        ));
    }
    check_grid(samples_per_period, substeps)?;
    let p = Params {
        a: amplitude,
        beta,
        gamma,
        mu,
    };
    let lat = Lattice::new(samples_per_period, phi.rem_euclid(2.0 * PI));
    let mut rec = vec![[0.0; NS]; lat.len];
    // |w| never exceeds the bound of Proposition 1 in steady state.
    let bound = (1.0 / (beta + gamma)).powf(1.0 / mu);
    let (mut lo, mut hi) = (-bound * BRACKET_SLACK, bound * BRACKET_SLACK);
    let table = SinTable::new(&lat, substeps);
    // Coarse to fine: the shooting first converges with one RK4 step per lattice interval (a
    // quarter or less of a pass's work), whose w(0) differs from the fine one by the small
    // discretisation error; the fine passes then start there and need one Newton step or two
    // instead of three to five (issue #8). The fine iteration below decides, as before.
    let (mut w_top, coarse_phi) = if substeps > 1 {
        let coarse = SinTable::new(&lat, 1);
        if reduced {
            coarse_top::<NR>(&p, &lat, &coarse, bound)
        } else {
            coarse_top::<NS>(&p, &lat, &coarse, bound)
        }
        .unwrap_or((0.0, f64::NAN))
    } else {
        (0.0, f64::NAN)
    };
    let mut iterations = 0;
    // The fine passes: reduced (`w`, `Phi`) while the shooting is still far, full (sensitivities,
    // the loop recorded) once the last residual says Newton converges on this pass, or from the
    // first pass when the coarse loop saturated (`SATURATED_PHI`).
    let mut full = !reduced || coarse_phi.abs() < SATURATED_PHI;
    let end = loop {
        let (w_end, phi_end, end) = if full {
            let end = half_cycle::<NS>(&p, &lat, &table, w_top, substeps, Some(&mut rec));
            (end[0], end[1], Some(end))
        } else {
            let end = half_cycle::<NR>(&p, &lat, &table, w_top, substeps, None);
            (end[0], end[1], None)
        };
        crate::cancel::checkpoint()?;
        let h = w_end + w_top;
        if h.abs() <= SHOOT_RTOL * bound {
            match end {
                Some(end) => break end,
                // Converged on a reduced pass: the same pass again with the sensitivities.
                None => {
                    let end = half_cycle::<NS>(&p, &lat, &table, w_top, substeps, Some(&mut rec));
                    crate::cancel::checkpoint()?;
                    break end;
                }
            }
        }
        iterations += 1;
        if iterations > SHOOT_MAX_ITER {
            return Err(CoreError::NotConverged(format!(
                "the steady-loop shooting did not converge in {SHOOT_MAX_ITER} iterations \
                 (residual {h:.3e}); the parameters (A = {amplitude}, beta = {beta}, \
                 gamma = {gamma}, mu = {mu}) are far from a physical loop"
            )));
        }
        // h is increasing in w_top (dh/dw_top = Phi(pi) + 1 > 0): keep a bracket.
        if h > 0.0 {
            hi = w_top;
        } else {
            lo = w_top;
        }
        let newton = w_top - h / (phi_end + 1.0);
        w_top = if newton > lo && newton < hi && newton.is_finite() {
            newton
        } else {
            0.5 * (lo + hi)
        };
        full = !reduced || h.abs() <= FULL_PASS_RESIDUAL * bound;
    };
    let denom = 1.0 + end[1];
    let dtop = [
        -end[2] / denom,
        -end[3] / denom,
        -end[4] / denom,
        -end[5] / denom,
    ];
    let mut w = Vec::with_capacity(samples_per_period);
    let mut jac = Vec::with_capacity(samples_per_period);
    for &(m, sign) in &lat.map {
        let y = &rec[m];
        let theta = lat.offset + m as f64 * lat.spacing;
        let slope = rhs(&p, theta, y)[0];
        w.push(sign * y[0]);
        jac.push([
            sign * (y[2] + y[1] * dtop[0]),
            sign * (y[3] + y[1] * dtop[1]),
            sign * (y[4] + y[1] * dtop[2]),
            sign * (y[5] + y[1] * dtop[3]),
            -sign * slope,
        ]);
    }
    if !(w.iter().all(|v| v.is_finite()) && jac.iter().flatten().all(|v| v.is_finite())) {
        return Err(CoreError::NonFinite(format!(
            "the steady loop or its sensitivities overflowed for A = {amplitude:e}, beta = {beta:e}, \
             gamma = {gamma:e}, mu = {mu}; rescale the data so that the parameters are of moderate size"
        )));
    }
    Ok(SteadyLoop {
        w,
        jac,
        w_top,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn loop_at(a: f64, beta: f64, gamma: f64, mu: f64, phi: f64, p: usize) -> SteadyLoop {
        steady_loop(a, beta, gamma, mu, phi, p, 8).unwrap()
    }

    /// Uniform draws in [0, 1) from a seeded SplitMix64 (no crate needed).
    struct Draws(u64);

    impl Draws {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn reduced_passes_give_the_full_solver_bit_for_bit() {
        // The shooting's passes with `w` and `Phi` alone must leave every output as the solver
        // with every pass full gave it: loop, Jacobian, w(0) and the Newton count, on random
        // loops (thin to fat, gamma of either sign, odd and even grids, 1-4 substeps).
        let mut r = Draws(20261127);
        let mut fine_passes = 0;
        for case in 0..300 {
            // Every third loop saturated (|A| up to 50 loop widths, as the MR damper's): the
            // first fine pass is then full (`SATURATED_PHI`).
            let reach = if case % 3 == 0 { 50.0 } else { 3.0 };
            let a = (0.2 + reach * r.next()) * if r.next() < 0.2 { -1.0 } else { 1.0 };
            let beta = 0.05 + 2.0 * r.next();
            let gamma = beta * (2.0 * r.next() - 0.9);
            let mu = 1.0 + 1e-3 + 3.0 * r.next();
            let phi = 8.0 * r.next() - 1.0;
            let p = [4, 5, 37, 64, 243, 325, 401][case % 7];
            let substeps = 1 + case % 4;
            let args = (a, beta, gamma, mu, phi);
            let full = steady_loop_passes(args, p, substeps, false);
            let fast = steady_loop(a, beta, gamma, mu, phi, p, substeps);
            match (full, fast) {
                (Ok(x), Ok(y)) => {
                    let bits = |v: &[f64]| v.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&x.w), bits(&y.w), "case {case}: {args:?} P {p}");
                    assert_eq!(
                        bits(x.jac.as_flattened()),
                        bits(y.jac.as_flattened()),
                        "case {case}"
                    );
                    assert_eq!(x.w_top.to_bits(), y.w_top.to_bits(), "case {case}");
                    assert_eq!(x.iterations, y.iterations, "case {case}");
                    fine_passes += x.iterations + 1;
                }
                (Err(x), Err(y)) => assert_eq!(x.to_string(), y.to_string(), "case {case}"),
                (x, y) => panic!("case {case}: {:?} vs {:?}", x.is_ok(), y.is_ok()),
            }
        }
        // Enough Newton steps that both kinds of pass (and the repeated converged one) ran.
        assert!(fine_passes > 600, "{fine_passes}");
    }

    #[test]
    fn a_saturated_loop_converges_by_newton() {
        // |A| = 48 against a loop of width 1 (a fit of the MR damper at 0 A): w(0) sits at the
        // bound and Phi(pi) underflows; the first Newton step lands on the bound and must be taken.
        let (beta, gamma, mu) = (1.9, 1.9, 1.94);
        let bound = (1.0_f64 / (beta + gamma)).powf(1.0 / mu);
        for (a, p, substeps) in [
            (48.4, 401, 2),
            (-37.9, 391, 2),
            (10.0, 37, 4),
            (30.0, 243, 1),
        ] {
            let l = steady_loop(a, beta, gamma, mu, 0.7, p, substeps).unwrap();
            assert!(
                l.iterations <= 2,
                "{a} {p}: {} Newton iterations",
                l.iterations
            );
            assert_relative_eq!(l.w_top.abs(), bound, max_relative = 1e-9);
            let half = if p % 2 == 0 { p / 2 } else { 0 };
            if half > 0 {
                assert_relative_eq!(l.w[0], -l.w[half], epsilon = 1e-12);
            }
        }
    }

    #[test]
    fn loop_is_odd_symmetric_and_periodic() {
        let l = loop_at(1.5, 0.8, 0.2, 1.6, 0.7, 256);
        for j in 0..128 {
            assert_relative_eq!(l.w[j], -l.w[j + 128], epsilon = 1e-12);
        }
        let bound = 1.0_f64;
        assert!(l.w.iter().all(|w| w.abs() <= bound + 1e-12));
    }

    #[test]
    fn odd_and_even_sample_counts_agree() {
        // The same loop sampled at P = 200 and P = 201 must agree where the grids meet (t = 0).
        let a = loop_at(1.2, 0.6, 0.3, 2.0, 0.3, 200);
        let b = loop_at(1.2, 0.6, 0.3, 2.0, 0.3, 201);
        assert_relative_eq!(a.w[0], b.w[0], epsilon = 1e-9);
        assert_relative_eq!(a.w_top, b.w_top, epsilon = 1e-9);
    }

    #[test]
    fn matches_a_long_time_domain_simulation() {
        use crate::bouc_wen::BoucWen;
        use crate::linear::TransferFunction;
        use crate::simulate::{simulate, Input};
        let (a, beta, gamma, mu, phi, omega) = (1.7, 0.8, 0.2, 1.6, 1.1, 3.0);
        let p = 256;
        // x = A cos(omega t - phi) from a static gain behind a delay phi/omega.
        let tf = TransferFunction::new(&[a], &[1.0], phi / omega).unwrap();
        let bw = BoucWen::new(1.0, beta, gamma, mu, 0.0).unwrap();
        let dt = 2.0 * PI / omega / p as f64;
        let periods = 40;
        let sim = simulate(
            &tf,
            &bw,
            Input::Sine {
                amplitude: 1.0,
                omega,
            },
            dt,
            periods * p,
            32,
        )
        .unwrap();
        let l = loop_at(a, beta, gamma, mu, phi, p);
        let last = &sim.w[(periods - 1) * p..];
        for (a, b) in l.w.iter().zip(last) {
            assert_relative_eq!(a, b, epsilon = 5e-7);
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let (a, beta, gamma, mu, phi) = (1.4, 0.7, 0.25, 1.8, 0.9);
        let p = 128;
        let base = loop_at(a, beta, gamma, mu, phi, p);
        let h = 1e-6;
        let params = [beta, gamma, mu, a, phi];
        for k in 0..5 {
            let mut up = params;
            let mut dn = params;
            up[k] += h;
            dn[k] -= h;
            let lu = loop_at(up[3], up[0], up[1], up[2], up[4], p);
            let ld = loop_at(dn[3], dn[0], dn[1], dn[2], dn[4], p);
            for j in 0..p {
                let fd = (lu.w[j] - ld.w[j]) / (2.0 * h);
                assert!(
                    (fd - base.jac[j][k]).abs() < 2e-5 * (1.0 + fd.abs()),
                    "param {k}, sample {j}: fd {fd} vs {}",
                    base.jac[j][k]
                );
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(matches!(
            steady_loop(1.0, 0.5, 0.5, 1.0, 0.0, 64, 4),
            Err(CoreError::InvalidParameter(_))
        ));
        assert!(matches!(
            steady_loop(1.0, -0.5, 0.2, 1.5, 0.0, 64, 4),
            Err(CoreError::InvalidParameter(_))
        ));
        assert!(matches!(
            steady_loop(0.0, 0.5, 0.2, 1.5, 0.0, 64, 4),
            Err(CoreError::ZeroAmplitude(_))
        ));
        assert!(matches!(
            steady_loop(f64::NAN, 0.5, 0.2, 1.5, 0.0, 64, 4),
            Err(CoreError::NonFinite(_))
        ));
        // Sizes that would panic on allocation (or run for hours) are refused up front.
        for (p, sub) in [(1usize << 62, 1usize), (1 << 40, 1), (1 << 20, 1 << 20)] {
            assert!(matches!(
                steady_loop(1.0, 1.0, 0.5, 2.0, 0.0, p, sub),
                Err(CoreError::InvalidParameter(_))
            ));
        }
        // Parameters at the edge of the float range: an error, never NaN sensitivities.
        assert!(matches!(
            steady_loop(
                6.1457403761690284e-96,
                4.49423283715579e307,
                0.0,
                4.0,
                0.0,
                4,
                1
            ),
            Err(CoreError::NonFinite(_))
        ));
    }
}

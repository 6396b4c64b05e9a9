//! Steady hysteresis loop along the input path, with asymmetry and play (`docs/design.md` 9.2).
//!
//! Generalised Bouc-Wen with alpha = 1 (the `sgn(w)` asymmetry term of Song & Der Kiureghian,
//! "Generalized Bouc-Wen model for highly asymmetric hysteresis", J. Eng. Mech. 132(6), 2006):
//! `wdot = xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))]`, driven by
//! `xp = Play_b[x]`, the play (backlash) operator of half-width b, with `x = A cos(theta - phi)`.
//! The model is rate independent, so along a monotone stretch of the path
//! `dw/dxp = h(w, s) = 1 - |w|^mu (gamma + (beta s + delta) sgn(w))`, `s = sgn(xpdot)`, whatever
//! the speed: the loop is integrated in `xp`, from node to node (the P samples and the two
//! reversals of x, ordered from the top), never in time.
//!
//! Each segment map `w_b = Psi(w_a, dx)` is RK4 on `dw/dsigma = dx h(w, s)`, `sigma in [0, 1]`,
//! with the forward sensitivities `d/d(w_a, dx, beta, gamma, mu, delta)` riding along: RK4
//! commutes with forward differentiation, so these are the exact derivatives of the discrete map
//! (as in `steady.rs`, 7.2). The steady state is the fixed point of one full cycle of maps,
//! found by Newton shooting on the top value `w_0`, safeguarded by bisection on
//! `[-w_b, w_b]`, `w_b = (beta + gamma - |delta|)^(-1/mu)`; the chain rule carries every sensitivity
//! (also those of `xp` to `A`, `phi`, `b`) to every sample.
//!
//! The play output of a sine is exact at every node: after the top it dwells at `a - b` until x
//! has come down by `2b`, then follows `x + b`; after the bottom it dwells at `-a + b`, then
//! follows `x - b` (`a = |A|`).

use crate::bouc_wen::sgn;
use crate::error::{finite, CoreError, Result};
use crate::steady::{MAX_SAMPLES_PER_PERIOD, MAX_STEPS_PER_PERIOD};
use std::f64::consts::PI;

/// Column of d w / d beta in [`PathLoop::jac`] rows.
pub const PD_BETA: usize = 0;
/// d w / d gamma.
pub const PD_GAMMA: usize = 1;
/// d w / d mu.
pub const PD_MU: usize = 2;
/// d w / d A (A signed: the amplitude of x).
pub const PD_AMPLITUDE: usize = 3;
/// d w / d phi.
pub const PD_PHI: usize = 4;
/// d w / d delta (asymmetry).
pub const PD_DELTA: usize = 5;
/// d w / d b (play half-width).
pub const PD_PLAY: usize = 6;

/// Newton (or bisection) updates of `w_0` allowed on the full-resolution cycle map. Bisection
/// alone halves `[-w_b, w_b]` to the tolerance in about 45 steps.
const SHOOT_MAX_ITER: usize = 60;
/// Relative tolerance of the periodicity condition `|W(w_0) - w_0| <= tol * w_b` (a few ulps of
/// `w_b` above rounding of the cycle's sum of about `P substeps` increments).
const SHOOT_RTOL: f64 = 1e-13;
/// A Newton step below this fraction of `w_b` predicts (quadratic convergence) that the next pass
/// meets [`SHOOT_RTOL`], so that pass carries the sensitivities and is not repeated.
const FULL_PASS_STEP: f64 = 1e-5;
/// RK4 steps per half cycle of the coarse cycle map (two segments, no samples) whose fixed point
/// starts the shooting: `w_0` within about `1e-7 w_b` of the fine one for moderate `mu`, so that
/// the fine map needs one Newton step before the converged pass.
const COARSE_STEPS: usize = 24;

/// The steady loop along the path on the sample grid and its Jacobian.
#[derive(Debug, Clone)]
pub struct PathLoop {
    /// `w(t_j)`, `t_j = j T / P`, j = 0..P (units of w).
    pub w: Vec<f64>,
    /// `d w(t_j) / d(beta, gamma, mu, A, phi, delta, b)`, one row per sample (columns `PD_*`).
    pub jac: Vec<[f64; 7]>,
    /// Newton (or bisection) updates of the top value on the full-resolution map.
    pub iterations: usize,
}

/// Shape parameters of `h(w, s)`.
#[derive(Clone, Copy)]
struct Shape {
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
}

/// One segment of the path: from one node to the next.
#[derive(Clone, Copy)]
struct Segment {
    /// `xp_end - xp_start`.
    dx: f64,
    /// `d dx / d(A, phi, b)`.
    ddx: [f64; 3],
    /// Direction of xp on the segment (`-1` descending half, `+1` ascending).
    s: f64,
    /// The sample the segment ends on, or [`REVERSAL`].
    end: usize,
}

/// Marks a segment that ends on a reversal of x rather than on a sample.
const REVERSAL: usize = usize::MAX;

/// `h(w, s)` and the pieces of its derivatives at one RK4 stage: one `ln` and one `exp`.
#[derive(Clone, Copy)]
struct Rate {
    /// `h = 1 - |w|^mu c`.
    h: f64,
    /// `dh/dw = -mu |w|^(mu-1) (gamma sgn w + beta s + delta)`.
    hw: f64,
    /// `|w|^mu`.
    wmu: f64,
    /// `ln |w|` (0 at w = 0, where it is multiplied by `|w|^mu = 0`).
    lnw: f64,
    /// `sgn(w)`.
    sw: f64,
    /// `c = gamma + (beta s + delta) sgn(w)`.
    c: f64,
}

#[inline(always)]
fn rate(p: &Shape, s: f64, w: f64) -> Rate {
    let aw = w.abs();
    let sw = sgn(w);
    let (wmu, wmu1, lnw) = if aw > 0.0 {
        let lnw = aw.ln();
        let wmu = (p.mu * lnw).exp();
        (wmu, wmu / aw, lnw)
    } else {
        (0.0, 0.0, 0.0)
    };
    let c = p.gamma + (p.beta * s + p.delta) * sw;
    Rate {
        h: 1.0 - wmu * c,
        // d/dw |w|^mu = mu |w|^(mu-1) sgn(w); d/dw sgn(w)|w|^mu = mu |w|^(mu-1).
        hw: -p.mu * wmu1 * (p.gamma * sw + p.beta * s + p.delta),
        wmu,
        lnw,
        sw,
        c,
    }
}

/// Segment map for the shooting: `(w_end, dw_end/dw_start)` after `substeps` RK4 steps of
/// `dw/dsigma = dx h(w, s)`.
#[inline(always)]
fn segment_shoot(p: &Shape, s: f64, dx: f64, w: f64, substeps: usize) -> (f64, f64) {
    let hs = 1.0 / substeps as f64;
    let (mut w, mut phi) = (w, 1.0);
    for _ in 0..substeps {
        let r1 = rate(p, s, w);
        let (k1, q1) = (dx * r1.h, dx * r1.hw * phi);
        let r2 = rate(p, s, w + 0.5 * hs * k1);
        let (k2, q2) = (dx * r2.h, dx * r2.hw * (phi + 0.5 * hs * q1));
        let r3 = rate(p, s, w + 0.5 * hs * k2);
        let (k3, q3) = (dx * r3.h, dx * r3.hw * (phi + 0.5 * hs * q2));
        let r4 = rate(p, s, w + hs * k3);
        let (k4, q4) = (dx * r4.h, dx * r4.hw * (phi + hs * q3));
        w += hs / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        phi += hs / 6.0 * (q1 + 2.0 * q2 + 2.0 * q3 + q4);
    }
    (w, phi)
}

/// Number of components of the full segment state.
const NF: usize = 7;

/// Rate of the full segment state `[w, dw/dw_a, dw/d dx, dw/d beta, dw/d gamma, dw/d mu,
/// dw/d delta]` in sigma.
#[inline(always)]
fn rhs_full(p: &Shape, s: f64, dx: f64, y: &[f64; NF]) -> [f64; NF] {
    let r = rate(p, s, y[0]);
    let fw = dx * r.hw;
    let dwmu = dx * r.wmu;
    [
        dx * r.h,
        fw * y[1],
        fw * y[2] + r.h,
        fw * y[3] - dwmu * s * r.sw,
        fw * y[4] - dwmu,
        fw * y[5] - dwmu * r.lnw * r.c,
        fw * y[6] - dwmu * r.sw,
    ]
}

#[inline(always)]
fn axpy(y: &[f64; NF], h: f64, k: &[f64; NF]) -> [f64; NF] {
    let mut out = *y;
    for i in 0..NF {
        out[i] += h * k[i];
    }
    out
}

/// Segment map with every sensitivity: the full state after `substeps` RK4 steps from
/// `[w, 1, 0, 0, 0, 0, 0]`.
#[inline(always)]
fn segment_full(p: &Shape, s: f64, dx: f64, w: f64, substeps: usize) -> [f64; NF] {
    let mut y = [w, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    if dx == 0.0 {
        // A dwell: the map is the identity, and its only non-zero sensitivity is
        // d/d dx = h(w) (the RK4 weights sum to 1), needed when dx moves off 0.
        y[2] = rate(p, s, w).h;
        return y;
    }
    let hs = 1.0 / substeps as f64;
    for _ in 0..substeps {
        let k1 = rhs_full(p, s, dx, &y);
        let k2 = rhs_full(p, s, dx, &axpy(&y, 0.5 * hs, &k1));
        let k3 = rhs_full(p, s, dx, &axpy(&y, 0.5 * hs, &k2));
        let k4 = rhs_full(p, s, dx, &axpy(&y, hs, &k3));
        for i in 0..NF {
            y[i] += hs / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    y
}

/// Play output of the sine and its derivatives `d/d(A, phi, b)` at cycle phase `zeta`
/// (`zeta = 0` at the top of x, descending on `[0, pi]`): `x = a cos(zeta)`,
/// `dx/dA = sgn(A) cos(zeta)`, `dx/dphi = a sin(zeta)`.
fn play_node(a: f64, sa: f64, b: f64, zeta: f64, descending: bool) -> (f64, [f64; 3]) {
    let (sz, cz) = zeta.sin_cos();
    let x = a * cz;
    let dx = [sa * cz, a * sz];
    if descending {
        if x < a - 2.0 * b {
            (x + b, [dx[0], dx[1], 1.0])
        } else {
            (a - b, [sa, 0.0, -1.0])
        }
    } else if x > -a + 2.0 * b {
        (x - b, [dx[0], dx[1], -1.0])
    } else {
        (-a + b, [-sa, 0.0, 1.0])
    }
}

/// The P + 2 segments of one cycle, from the top around to the top.
fn segments(amplitude: f64, phi: f64, b: f64, p: usize) -> Vec<Segment> {
    let a = amplitude.abs();
    let sa = sgn(amplitude);
    // Cycle phase of sample j, as a fraction of the period: u_j = frac(j/P - phi'/(2 pi)), with
    // phi' = phi (+ pi when A < 0, whose top is at theta - phi = pi).
    let shift = if amplitude < 0.0 { 0.5 } else { 0.0 };
    let r = (phi / (2.0 * PI) + shift).rem_euclid(1.0);
    let frac = |j: usize| {
        let u = j as f64 / p as f64 - r;
        if u < 0.0 {
            u + 1.0
        } else {
            u
        }
    };
    // The sample closest after the top; the phases then increase cyclically from it.
    let j0 = (0..p)
        .min_by(|&i, &k| frac(i).total_cmp(&frac(k)))
        .unwrap_or(0);
    let mut segs = Vec::with_capacity(p + 2);
    let top = (a - b, [sa, 0.0, -1.0]);
    let bottom = (-a + b, [-sa, 0.0, 1.0]);
    let mut prev = top;
    let mut push = |prev: &mut (f64, [f64; 3]), node: (f64, [f64; 3]), s: f64, end: usize| {
        segs.push(Segment {
            dx: node.0 - prev.0,
            ddx: [
                node.1[0] - prev.1[0],
                node.1[1] - prev.1[1],
                node.1[2] - prev.1[2],
            ],
            s,
            end,
        });
        *prev = node;
    };
    let mut passed_bottom = false;
    for m in 0..p {
        let j = (j0 + m) % p;
        let u = frac(j);
        let descending = u <= 0.5;
        if !descending && !passed_bottom {
            push(&mut prev, bottom, -1.0, REVERSAL);
            passed_bottom = true;
        }
        let node = play_node(a, sa, b, 2.0 * PI * u, descending);
        push(&mut prev, node, if descending { -1.0 } else { 1.0 }, j);
    }
    if !passed_bottom {
        push(&mut prev, bottom, -1.0, REVERSAL);
    }
    push(&mut prev, top, 1.0, REVERSAL);
    segs
}

/// One cycle of segment maps from `w0`: `(W(w0), dW/dw0)`.
fn cycle(shape: &Shape, segs: &[Segment], w0: f64, substeps: usize) -> (f64, f64) {
    let (mut w, mut phi) = (w0, 1.0);
    for seg in segs {
        if seg.dx == 0.0 {
            continue;
        }
        let (wn, d) = segment_shoot(shape, seg.s, seg.dx, w, substeps);
        w = wn;
        phi *= d;
    }
    (w, phi)
}

/// Newton on `g(w0) = W(w0) - w0`, safeguarded by bisection on `[lo, hi]`. `g` is positive at
/// `lo` and negative at `hi` (W maps the bracket into itself), so a positive residual raises `lo`.
/// Returns `(w0, W'(w0))` on convergence, `Err((w0, residual))` after `max_iter` updates.
struct Shooting {
    lo: f64,
    hi: f64,
    w0: f64,
}

impl Shooting {
    /// Next iterate from the residual `g` and the slope `W'` at the current one.
    fn update(&mut self, g: f64, dw: f64) -> f64 {
        if g > 0.0 {
            self.lo = self.w0;
        } else {
            self.hi = self.w0;
        }
        let newton = self.w0 + g / (1.0 - dw);
        let next = if newton > self.lo && newton < self.hi && newton.is_finite() {
            newton
        } else {
            0.5 * (self.lo + self.hi)
        };
        let step = next - self.w0;
        self.w0 = next;
        step
    }
}

/// Steady loop of the generalised Bouc-Wen (alpha = 1, asymmetry `delta`) behind a play of
/// half-width `play`, driven by `x = amplitude cos(omega t - phi)` and sampled at `P` points per
/// period (`t_j = j T / P`), with `substeps` RK4 steps per segment between nodes.
///
/// `amplitude` is `A` (units of x, may be negative: its top is then at `theta - phi = pi`);
/// `beta`, `gamma`, `delta` in `1/[w]^mu`; `mu` dimensionless; `play` (b) in units of x; `phi`
/// in rad. Returns `w` (length P, units of w) and its Jacobian rows `d/d(beta, gamma, mu, A, phi,
/// delta, b)` (columns `PD_*`).
///
/// Errors: [`CoreError::NonFinite`] for a non-finite input or an overflowing loop;
/// [`CoreError::InvalidParameter`] for `mu <= 1`, `beta + gamma - |delta| <= 0`, `play < 0`,
/// `substeps < 1`, a grid above [`MAX_SAMPLES_PER_PERIOD`] / [`MAX_STEPS_PER_PERIOD`];
/// [`CoreError::ZeroAmplitude`] for `amplitude == 0` or `play >= |amplitude|` (no motion reaches
/// the hysteresis); [`CoreError::InsufficientData`] for `P < 4`; [`CoreError::NotConverged`]
/// when the shooting finds no periodic loop.
#[allow(clippy::too_many_arguments)]
pub fn path_loop(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    for (name, v) in [
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("delta", delta),
        ("play", play),
        ("phi", phi),
    ] {
        finite(name, v)?;
    }
    if mu <= 1.0 {
        return Err(CoreError::InvalidParameter(format!(
            "mu = {mu} must be > 1 in the identification model"
        )));
    }
    let margin = beta + gamma - delta.abs();
    if margin <= 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma - |delta| = {margin} must be > 0 (beta = {beta}, gamma = {gamma}, \
             delta = {delta}): otherwise one side of the loop is unbounded; shrink |delta| below \
             beta + gamma"
        )));
    }
    if amplitude == 0.0 {
        return Err(CoreError::ZeroAmplitude(
            "the amplitude of x is 0: the loop is a point".into(),
        ));
    }
    if play < 0.0 {
        return Err(CoreError::InvalidParameter(format!(
            "play = {play} must be >= 0 (it is the half-width of the backlash, in units of x)"
        )));
    }
    if play >= amplitude.abs() {
        return Err(CoreError::ZeroAmplitude(format!(
            "play = {play} >= |amplitude| = {}: x never travels past the play, so no motion \
             reaches the hysteresis and its loop is undetermined; the play must be below |A|",
            amplitude.abs()
        )));
    }
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
    let shape = Shape {
        beta,
        gamma,
        mu,
        delta,
    };
    let p = samples_per_period;
    let segs = segments(amplitude, phi, play, p);
    // |w| stays below the larger of the two saturation levels (beta + gamma -+ delta)^(-1/mu).
    let bound = (1.0 / margin).powf(1.0 / mu);
    let tol = SHOOT_RTOL * bound;
    let travel = 2.0 * (amplitude.abs() - play);

    // Start: the fixed point of the coarse map (two segments of COARSE_STEPS steps), an
    // approximation of the exact loop's top value that is independent of the samples.
    let coarse = [
        Segment {
            dx: -travel,
            ddx: [0.0; 3],
            s: -1.0,
            end: REVERSAL,
        },
        Segment {
            dx: travel,
            ddx: [0.0; 3],
            s: 1.0,
            end: REVERSAL,
        },
    ];
    let mut sh = Shooting {
        lo: -bound,
        hi: bound,
        w0: 0.0,
    };
    for _ in 0..SHOOT_MAX_ITER {
        let (wn, d) = cycle(&shape, &coarse, sh.w0, COARSE_STEPS);
        let g = wn - sh.w0;
        if g.abs() <= tol || sh.update(g, d).abs() <= tol {
            break;
        }
    }
    // The coarse fixed point is a start, not a bracket: the fine root may lie on either side.
    let start = sh.w0;
    sh = Shooting {
        lo: -bound,
        hi: bound,
        w0: start,
    };

    let mut w = vec![0.0; p];
    let mut jac = vec![[0.0; 7]; p];
    // dw_j / dw_0 of each sample.
    let mut phis = vec![0.0; p];
    let mut iterations = 0;
    let mut full = false;
    loop {
        let (wn, d, t) = if full {
            full_cycle(&shape, &segs, sh.w0, substeps, &mut w, &mut jac, &mut phis)
        } else {
            let (wn, d) = cycle(&shape, &segs, sh.w0, substeps);
            (wn, d, [0.0; 7])
        };
        let g = wn - sh.w0;
        if g.abs() <= tol {
            if full {
                // dw_0/dq = (dW/dq) / (1 - dW/dw_0); every sample: T_j + Phi_j dw_0/dq.
                let dtop = t.map(|v| v / (1.0 - d));
                for (row, &ph) in jac.iter_mut().zip(&phis) {
                    for (v, dt) in row.iter_mut().zip(dtop) {
                        *v += ph * dt;
                    }
                }
                break;
            }
            // Converged on a cheap pass: repeat it with the sensitivities (same w trajectory).
            full = true;
            continue;
        }
        iterations += 1;
        if iterations > SHOOT_MAX_ITER || !g.is_finite() {
            let why = if g.is_finite() {
                format!("found no periodic loop in {SHOOT_MAX_ITER} iterations (residual {g:.3e})")
            } else {
                format!(
                    "diverged (w reached {wn:e} within one cycle from w_0 = {:e})",
                    sh.w0
                )
            };
            return Err(CoreError::NotConverged(format!(
                "the path-loop shooting {why}, bound {bound:.3e}, for A = {amplitude}, \
                 beta = {beta}, gamma = {gamma}, mu = {mu}, delta = {delta}, play = {play}; with \
                 beta < 0 the unloading branch runs away at large amplitudes: check the \
                 parameters' signs and scale"
            )));
        }
        let step = sh.update(g, d);
        full = step.abs() <= FULL_PASS_STEP * bound;
    }
    if !(w.iter().all(|v| v.is_finite()) && jac.iter().flatten().all(|v| v.is_finite())) {
        return Err(CoreError::NonFinite(format!(
            "the path loop or its sensitivities overflowed for A = {amplitude:e}, beta = {beta:e}, \
             gamma = {gamma:e}, mu = {mu}, delta = {delta:e}, play = {play:e}; rescale the data so \
             that the parameters are of moderate size"
        )));
    }
    Ok(PathLoop { w, jac, iterations })
}

/// One cycle with every sensitivity from `w0`, recording each sample's `w`, its partials `T_j`
/// at fixed `w0` (into `jac`) and `Phi_j = dw_j/dw0`. Returns `(W, dW/dw0, dW/dq)`.
fn full_cycle(
    shape: &Shape,
    segs: &[Segment],
    w0: f64,
    substeps: usize,
    w_out: &mut [f64],
    jac: &mut [[f64; 7]],
    phis: &mut [f64],
) -> (f64, f64, [f64; 7]) {
    let (mut w, mut phi) = (w0, 1.0);
    let mut t = [0.0; 7];
    for seg in segs {
        let y = segment_full(shape, seg.s, seg.dx, w, substeps);
        let pw = y[1];
        for v in t.iter_mut() {
            *v *= pw;
        }
        t[PD_BETA] += y[3];
        t[PD_GAMMA] += y[4];
        t[PD_MU] += y[5];
        t[PD_DELTA] += y[6];
        t[PD_AMPLITUDE] += y[2] * seg.ddx[0];
        t[PD_PHI] += y[2] * seg.ddx[1];
        t[PD_PLAY] += y[2] * seg.ddx[2];
        phi *= pw;
        w = y[0];
        if seg.end != REVERSAL {
            w_out[seg.end] = w;
            jac[seg.end] = t;
            phis[seg.end] = phi;
        }
    }
    (w, phi, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::steady::steady_loop;

    #[allow(clippy::too_many_arguments)]
    fn pl(
        a: f64,
        beta: f64,
        gamma: f64,
        mu: f64,
        delta: f64,
        b: f64,
        phi: f64,
        p: usize,
        sub: usize,
    ) -> PathLoop {
        path_loop(a, beta, gamma, mu, delta, b, phi, p, sub).unwrap()
    }

    /// Largest difference of w, and largest relative one of the 5 common Jacobian columns.
    fn diff_to_steady(l: &PathLoop, w: &[f64], jac: &[[f64; 5]]) -> (f64, f64) {
        let dw =
            l.w.iter()
                .zip(w)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
        let dj = l
            .jac
            .iter()
            .zip(jac)
            .flat_map(|(r, q)| (0..5).map(move |k| (r[k] - q[k]).abs() / (1.0 + q[k].abs())))
            .fold(0.0, f64::max);
        (dw, dj)
    }

    #[test]
    fn plain_case_agrees_with_the_half_cycle_steady_loop() {
        // Two different O(h^4) discretisations (RK4 in theta on the folded lattice vs RK4 in xp
        // between nodes) of the same loop. With mu = 3, |w|^mu is C^3 through w = 0 and both keep
        // their order: the difference must shrink about 16x from 16 to 32 substeps (at least 8x
        // is asserted) and be at the measured RK4 error level (w ~ 1e-11, Jacobian ~ 1e-9 at 32
        // substeps on P = 64), with a 5x margin.
        let (a, beta, gamma, mu, phi, p) = (1.4, 0.7, 0.25, 3.0, 0.9, 64);
        let mut prev = (f64::INFINITY, f64::INFINITY);
        for sub in [16, 32] {
            let l = pl(a, beta, gamma, mu, 0.0, 0.0, phi, p, sub);
            let s = steady_loop(a, beta, gamma, mu, phi, p, sub).unwrap();
            let d = diff_to_steady(&l, &s.w, &s.jac);
            assert!(
                d.0 < prev.0 / 8.0 && d.1 < prev.1 / 8.0,
                "sub {sub}: {d:?} vs {prev:?}"
            );
            prev = d;
        }
        assert!(prev.0 < 5e-11 && prev.1 < 5e-9, "{prev:?}");
        // mu < 2: |w|^(mu-2) is singular where w crosses 0, so RK4 drops to about order mu + 1
        // on those two steps; at 64 substeps both are within ~2e-10 of the limit (w) and
        // ~3e-7 (Jacobian, whose rate carries |w|^(mu-1)): tolerance 5x.
        let l = pl(a, beta, gamma, 1.8, 0.0, 0.0, -2.0, 48, 64);
        let s = steady_loop(a, beta, gamma, 1.8, -2.0, 48, 64).unwrap();
        let d = diff_to_steady(&l, &s.w, &s.jac);
        assert!(d.0 < 1e-9 && d.1 < 2e-6, "{d:?}");
    }

    #[test]
    fn jacobian_matches_central_differences() {
        // Central differences of the same discrete map: truncation (h^2 w''' ~ 1e-10) plus the
        // shooting's tolerance 1e-13 w_b / (1 - Phi) on each call divided by 2h (~1e-8 for
        // h = 1e-5), so 1e-6 (1 + |fd|) is a test that a wrong chain-rule term (O(1)) fails.
        let sets: [[f64; 7]; 5] = [
            // [beta, gamma, mu, A, phi, delta, b]
            [0.7, 0.25, 1.8, 1.4, 0.9, 0.2, 0.15],
            [0.9, -0.3, 2.5, -1.1, 2.0, -0.35, 0.3],
            [0.5, 0.5, 1.3, 3.0, -1.0, 0.45, 0.5],
            [1.0, 0.2, 2.0, 0.3, 4.0, 0.5, 0.05],
            [0.6, 0.1, 3.5, -2.2, 0.3, 0.0, 1.1],
        ];
        let p = 40;
        let sub = 3;
        let run = |q: &[f64; 7]| pl(q[3], q[0], q[1], q[2], q[5], q[6], q[4], p, sub);
        for q in sets {
            let base = run(&q);
            for k in 0..7 {
                let h = 1e-5 * q[k].abs().max(1.0);
                let (mut up, mut dn) = (q, q);
                up[k] += h;
                dn[k] -= h;
                let (lu, ld) = (run(&up), run(&dn));
                for j in 0..p {
                    let fd = (lu.w[j] - ld.w[j]) / (2.0 * h);
                    let an = base.jac[j][k];
                    assert!(
                        (fd - an).abs() < 1e-6 * (1.0 + fd.abs()),
                        "set {q:?}, column {k}, sample {j}: fd {fd} vs {an}"
                    );
                }
            }
        }
    }

    #[test]
    fn asymmetric_saturation_levels() {
        // Far beyond saturation, loading drives w to the root of h = 0 on each side:
        // (beta + gamma + delta)^(-1/mu) ascending with w > 0, -(beta + gamma - delta)^(-1/mu)
        // descending with w < 0; at A = 60 the gap has decayed like exp(-120 mu c w^(mu-1)),
        // so only the RK4 error (< 1e-9 at 16 substeps) remains.
        let (beta, gamma, delta, mu) = (0.6, 0.3, 0.25, 2.0);
        let l = pl(60.0, beta, gamma, mu, delta, 0.0, 0.0, 256, 16);
        let max = l.w.iter().copied().fold(f64::MIN, f64::max);
        let min = l.w.iter().copied().fold(f64::MAX, f64::min);
        let top = (beta + gamma + delta).powf(-1.0 / mu);
        let bottom = -(beta + gamma - delta).powf(-1.0 / mu);
        assert!((max - top).abs() < 1e-9, "{max} vs {top}");
        assert!((min - bottom).abs() < 1e-9, "{min} vs {bottom}");
        // Swapping the sign of delta and of x mirrors the loop: w -> -w.
        let m = pl(-60.0, beta, gamma, mu, -delta, 0.0, 0.0, 256, 16);
        for (a, b) in l.w.iter().zip(&m.w) {
            assert!((a + b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn play_dwells_and_shifts_the_plain_loop() {
        let (a, beta, gamma, mu, delta, b, phi, p, sub) =
            (1.5, 0.8, 0.1, 2.5, 0.15, 0.3, 0.4, 64, 32);
        let l = pl(a, beta, gamma, mu, delta, b, phi, p, sub);
        let (mut dwell_top, mut dwell_bottom, mut active) = (vec![], vec![], 0);
        for j in 0..p {
            let zeta = (2.0 * PI * j as f64 / p as f64 - phi).rem_euclid(2.0 * PI);
            let x = a * zeta.cos();
            let descending = zeta <= PI;
            if descending && x >= a - 2.0 * b {
                dwell_top.push(l.w[j]);
                continue;
            }
            if !descending && x <= -a + 2.0 * b {
                dwell_bottom.push(l.w[j]);
                continue;
            }
            // Active: xp = x -+ b moves; the plain loop of amplitude a - b, sampled where its
            // x equals this xp on the same branch, has the same w (rate independence). Both
            // are RK4 at 32 substeps per segment or finer (error < 1e-10 here): tolerance 1e-9.
            active += 1;
            let xp = if descending { x + b } else { x - b };
            let c = (xp / (a - b)).clamp(-1.0, 1.0).acos();
            let zeta_plain = if descending { c } else { 2.0 * PI - c };
            let plain = pl(a - b, beta, gamma, mu, delta, 0.0, -zeta_plain, 4, 256);
            assert!(
                (plain.w[0] - l.w[j]).abs() < 1e-9,
                "sample {j}: {} vs {}",
                l.w[j],
                plain.w[0]
            );
        }
        assert!(dwell_top.len() >= 2 && dwell_bottom.len() >= 2 && active > 20);
        // Inside a dwell xp does not move, so w does not either (bit for bit: the map is the
        // identity there).
        for d in [&dwell_top, &dwell_bottom] {
            assert!(d.iter().all(|&v| v == d[0]), "{d:?}");
        }
    }

    #[test]
    fn periodic_in_phase_and_sign_of_the_amplitude() {
        let (beta, gamma, mu, delta, b, p) = (0.7, 0.2, 1.7, -0.3, 0.2, 50);
        let l = pl(1.3, beta, gamma, mu, delta, b, 0.77, p, 4);
        // One sample later in phase is the same node set: the loop rotates by one sample.
        let r = pl(
            1.3,
            beta,
            gamma,
            mu,
            delta,
            b,
            0.77 + 2.0 * PI / p as f64,
            p,
            4,
        );
        // A full turn of phi, and -A half a turn later, are the same x.
        let t = pl(1.3, beta, gamma, mu, delta, b, 0.77 - 2.0 * PI, p, 4);
        let n = pl(-1.3, beta, gamma, mu, delta, b, 0.77 + PI, p, 4);
        for j in 0..p {
            assert!((r.w[(j + 1) % p] - l.w[j]).abs() < 1e-12);
            assert!((t.w[j] - l.w[j]).abs() < 1e-12);
            assert!((n.w[j] - l.w[j]).abs() < 1e-12);
            // d/dA flips with the sign of A; the other columns agree.
            for k in 0..7 {
                let s = if k == PD_AMPLITUDE { -1.0 } else { 1.0 };
                assert!(
                    (s * n.jac[j][k] - l.jac[j][k]).abs() < 1e-9 * (1.0 + l.jac[j][k].abs()),
                    "sample {j} column {k}"
                );
            }
        }
        // Odd P works too.
        assert_eq!(pl(1.3, beta, gamma, mu, delta, b, 0.77, 7, 4).w.len(), 7);
    }

    type Args = (f64, f64, f64, f64, f64, f64, f64, usize, usize);

    fn call(f: &dyn Fn(&mut Args)) -> Result<PathLoop> {
        let mut a: Args = (1.0, 0.5, 0.2, 1.5, 0.1, 0.1, 0.0, 64, 4);
        f(&mut a);
        path_loop(a.0, a.1, a.2, a.3, a.4, a.5, a.6, a.7, a.8)
    }

    #[test]
    fn every_bad_input_is_a_named_error() {
        assert!(call(&|_| {}).is_ok());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let setters: [&dyn Fn(&mut Args); 7] = [
                &|a| a.0 = bad,
                &|a| a.1 = bad,
                &|a| a.2 = bad,
                &|a| a.3 = bad,
                &|a| a.4 = bad,
                &|a| a.5 = bad,
                &|a| a.6 = bad,
            ];
            for f in setters {
                let r = call(f);
                assert!(matches!(r, Err(CoreError::NonFinite(_))), "{r:?}");
            }
        }
        let invalid: [&dyn Fn(&mut Args); 8] = [
            &|a| a.3 = 1.0,
            &|a| a.3 = 0.5,
            &|a| a.4 = 0.7,
            &|a| a.4 = -0.7,
            &|a| a.5 = -1e-3,
            &|a| a.8 = 0,
            &|a| a.7 = 1 << 25,
            &|a| {
                a.7 = 1 << 20;
                a.8 = 1 << 20
            },
        ];
        for f in invalid {
            let r = call(f);
            assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
        }
        let zero: [&dyn Fn(&mut Args); 4] =
            [&|a| a.0 = 0.0, &|a| a.5 = 1.0, &|a| a.5 = 2.0, &|a| {
                a.0 = -0.5;
                a.5 = 0.5
            }];
        for f in zero {
            let r = call(f);
            assert!(matches!(r, Err(CoreError::ZeroAmplitude(_))), "{r:?}");
        }
        let r = call(&|a| a.7 = 3);
        assert!(matches!(r, Err(CoreError::InsufficientData(_))), "{r:?}");
        // beta < 0 with beta + gamma > 0: unloading runs away at large amplitude, so there is
        // no periodic loop; the shooting says so instead of returning garbage.
        let r = path_loop(20.0, -0.4, 1.0, 2.0, 0.0, 0.0, 0.0, 64, 4);
        assert!(matches!(r, Err(CoreError::NotConverged(_))), "{r:?}");
        // Parameters at the edge of the float range: an error, never a panic or NaN.
        let r = path_loop(6.1e-96, 4.49e307, 0.0, 4.0, 0.0, 0.0, 0.0, 4, 1);
        assert!(
            matches!(r, Err(CoreError::NonFinite(_) | CoreError::NotConverged(_))),
            "{r:?}"
        );
    }
}

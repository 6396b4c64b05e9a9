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
//! (as in `steady.rs`, 7.2), here summed in reverse within each RK4 step. The steady state is the
//! fixed point of one full cycle of maps. It is found by multiple shooting: the cycle is cut into
//! four pieces whose RK4 chains are independent, so that a core overlaps their `ln`/`exp`
//! latencies, and Newton closes the joins (started from the same on a coarse cycle); bracketed
//! single shooting on the top value, Newton safeguarded by bisection on `[-w_b, w_b]`,
//! `w_b = (beta + gamma - |delta|)^(-1/mu)`, takes over should it stray. The chain rule carries
//! every sensitivity (also those of `xp` to `A`, `phi`, `b`) across the pieces and to every sample.
//!
//! The play output of a sine is exact at every node: after the top it dwells at `a - b` until x
//! has come down by `2b`, then follows `x + b`; after the bottom it dwells at `-a + b`, then
//! follows `x - b` (`a = |A|`).

use crate::bouc_wen::sgn;
use crate::error::{finite, CoreError, Result};
use crate::terms::{PINCHING_CENTRE, PINCHING_WIDTH};
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
/// d w / d lambda (the distortion of a measured input waveform, design.md 9.5).
pub const PD_DISTORT: usize = 7;
/// d w / d zeta1 (pinching, [`path_loop_pinched`]).
pub const PD_PINCH: usize = 8;
/// Columns of a [`PathLoop::jac`] row.
pub const N_PD: usize = 9;

/// Newton (or bisection) updates of `w_0` allowed on the full-resolution cycle map. Bisection
/// alone halves `[-w_b, w_b]` to the tolerance in about 45 steps.
const SHOOT_MAX_ITER: usize = 60;
/// Relative tolerance of the periodicity condition `|W(w_0) - w_0| <= tol * w_b` (multiple
/// shooting: the sum of the joins' mismatches), a few hundred ulps of `w_b`, above the rounding
/// of a cycle's sum of about `P substeps` increments.
const SHOOT_RTOL: f64 = 1e-13;
/// A Newton step below this fraction of `w_b` predicts (quadratic convergence) that the next pass
/// meets [`SHOOT_RTOL`], so that pass carries the sensitivities and is not repeated. Over 200
/// random admissible loops (P = 256) 1e-5 costs the fewest passes: 1.15 cheap and 1.12 full per
/// call, against 1.44 and 1.03 at 1e-6 (a full pass costs about 1.3 cheap ones).
const FULL_PASS_STEP: f64 = 1e-5;
/// Segments (merged runs of the fine ones) of the coarse cycle whose fixed point gives the start
/// values (more where the loop is stiff, see [`COARSE_STIFF`]): close enough to the fine fixed
/// point that the fine map needs one or two Newton steps before the converged pass (measured over
/// 200 random admissible loops at P = 256: 2.3 fine passes on average).
const COARSE_SEGMENTS: usize = 32;
/// RK4 steps per coarse segment.
const COARSE_SUBSTEPS: usize = 2;
/// Classical RK4 is stable on `y' = -L y` for steps up to about 2.785 / L.
const RK4_STABLE: f64 = 2.785;
/// Largest coarse RK4 step in x, times the loop's stiffness bound `max |dh/dw|`.
const COARSE_STIFF: f64 = 0.5;
/// The coarse shooting stops after a Newton step below this fraction of `w_b`.
const COARSE_STEP: f64 = 1e-6;
/// Pieces of the cycle shot at once (their RK4 chains are independent, so a core overlaps them).
const PIECES: usize = 4;
/// Newton steps allowed to the coarse multiple shooting before bracketed single shooting.
const COARSE_MULTI_MAX_ITER: usize = 12;
/// Newton updates allowed to the multiple shooting before bracketed single shooting takes over.
const MULTI_MAX_ITER: usize = 8;

/// The steady loop along the path on the sample grid and its Jacobian.
#[derive(Debug, Clone)]
pub struct PathLoop {
    /// `w(t_j)`, `t_j = j T / P`, j = 0..P (units of w).
    pub w: Vec<f64>,
    /// `d w(t_j) / d(beta, gamma, mu, A, phi, delta, b)`, one row per sample (columns `PD_*`).
    pub jac: Vec<[f64; N_PD]>,
    /// Newton (or bisection) updates of the shooting on the full-resolution map (the coarse start
    /// not counted).
    pub iterations: usize,
}

/// Shape parameters of `h(w, s)`.
#[derive(Clone, Copy)]
struct Shape {
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    /// Pinching `zeta1`, and whether its factor (and `d/dzeta1`) is computed at all.
    pinch: f64,
    pinched: bool,
    /// `w_u = (beta + gamma)^(-1/mu)`, the virgin saturation level the pinching band scales with.
    w_u: f64,
    /// `d w_u / d(beta, gamma, mu)`.
    dwu: [f64; 3],
}

impl Shape {
    fn new(beta: f64, gamma: f64, mu: f64, delta: f64, pinch: Option<f64>) -> Self {
        let bg = beta + gamma;
        let w_u = bg.powf(-1.0 / mu);
        let d_bg = -w_u / (mu * bg);
        Self {
            beta,
            gamma,
            mu,
            delta,
            pinch: pinch.unwrap_or(0.0),
            pinched: pinch.is_some(),
            w_u,
            dwu: [d_bg, d_bg, w_u * bg.ln() / (mu * mu)],
        }
    }
}

/// One segment of the path: from one node to the next.
#[derive(Clone, Copy)]
struct Segment {
    /// `xp_end - xp_start`.
    dx: f64,
    /// `d dx / d(A, phi, b, lambda)`.
    ddx: [f64; 4],
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
    /// The pinching factor `P = 1 - zeta1 G` (1 without pinching; `h` above includes it).
    pf: f64,
    /// `h / P`, the Bouc-Wen part of `h`.
    hb: f64,
    /// `dP/dw_u` and `dP/dzeta1 = -G` (0 without pinching).
    p_wu: f64,
    p_z: f64,
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
    let hb = 1.0 - wmu * c;
    // d/dw |w|^mu = mu |w|^(mu-1) sgn(w); d/dw sgn(w)|w|^mu = mu |w|^(mu-1).
    let hbw = -p.mu * wmu1 * (p.gamma * sw + p.beta * s + p.delta);
    if !p.pinched {
        return Rate {
            h: hb,
            hw: hbw,
            wmu,
            lnw,
            sw,
            c,
            pf: 1.0,
            hb,
            p_wu: 0.0,
            p_z: 0.0,
        };
    }
    // Foliente's P = 1 - zeta1 exp(-z^2), z = (w s / w_u - q) / zeta2.
    let width = PINCHING_WIDTH * p.w_u;
    let z = (w * s - PINCHING_CENTRE * p.w_u) / width;
    let g = (-z * z).exp();
    let pf = 1.0 - p.pinch * g;
    // dP/dz = 2 zeta1 G z; dz/dw = s / width; dz/dw_u = -(w s) / (w_u width).
    let p_dz = 2.0 * p.pinch * g * z;
    Rate {
        h: hb * pf,
        hw: hbw * pf + hb * p_dz * s / width,
        wmu,
        lnw,
        sw,
        c,
        pf,
        hb,
        p_wu: -p_dz * w * s / (p.w_u * width),
        p_z: -g,
    }
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
                0.0,
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

/// Grid points per period (at least, and per highest harmonic) on which the reversals of a
/// distorted waveform are bracketed: the sign changes of `xi'` on the grid; a harmonic k turns at
/// most `2k` times per period, so 8 points per highest harmonic's period separate its roots
/// unless two nearly coincide (a nearly flat inflection, whose loop contribution is nil).
const REVERSAL_GRID_MIN: usize = 64;
/// See [`REVERSAL_GRID_MIN`].
const REVERSAL_GRID_PER_HARMONIC: usize = 8;
/// Safeguarded Newton steps allowed per reversal (bisection alone reaches 1e-15 rad in ~50).
const REVERSAL_MAX_ITER: usize = 100;

/// A measured input's waveform beyond its fundamental (design.md 9.5): the latent input is
/// `x = A xi(theta - phi)`, `xi(zeta) = cos(zeta) + lambda d(zeta)`, with the normalised
/// distortion `d(zeta) = sum_{k >= 2} Re(c_k e^{i k zeta})` measured on the input (`c_k` relative
/// to the fundamental's amplitude and phase) and `lambda` the fitted scale (1: the measured
/// waveform drives the model; 0: the pure sine).
#[derive(Debug, Clone, Copy)]
pub struct Waveform<'a> {
    /// `lambda` (dimensionless).
    pub lambda: f64,
    /// `[Re c_2, Im c_2, Re c_3, Im c_3, ...]` (dimensionless, relative to the fundamental).
    pub harmonics: &'a [f64],
}

impl Waveform<'_> {
    /// `[xi, xi', xi'', d]` at `zeta` (derivatives in zeta).
    fn eval(&self, zeta: f64) -> [f64; 4] {
        let (mut d, mut d1, mut d2) = (0.0, 0.0, 0.0);
        for (i, c) in self.harmonics.chunks_exact(2).enumerate() {
            let k = (i + 2) as f64;
            let (s, co) = (k * zeta).sin_cos();
            let v = c[0] * co - c[1] * s;
            d += v;
            d1 -= k * (c[0] * s + c[1] * co);
            d2 -= k * k * v;
        }
        let (s, co) = zeta.sin_cos();
        let l = self.lambda;
        [co + l * d, -s + l * d1, -co + l * d2, d]
    }

    /// The reversals of `xi` (roots of `xi'`) in `[0, 2 pi)`: sign changes on a grid, each
    /// refined by Newton safeguarded by bisection in its bracket.
    fn reversals(&self) -> Vec<f64> {
        let m = REVERSAL_GRID_MIN.max(REVERSAL_GRID_PER_HARMONIC * (self.harmonics.len() / 2 + 1));
        let h = 2.0 * PI / m as f64;
        let f = |z: f64| self.eval(z)[1];
        let mut roots = Vec::new();
        for i in 0..m {
            let (mut lo, mut hi) = (i as f64 * h, (i + 1) as f64 * h);
            let (flo, fhi) = (f(lo), f(hi));
            if flo == 0.0 {
                roots.push(lo);
                continue;
            }
            if flo * fhi >= 0.0 {
                continue;
            }
            let mut z = 0.5 * (lo + hi);
            for _ in 0..REVERSAL_MAX_ITER {
                let e = self.eval(z);
                if e[1] == 0.0 {
                    break;
                }
                if (e[1] < 0.0) == (flo < 0.0) {
                    lo = z;
                } else {
                    hi = z;
                }
                let newton = z - e[1] / e[2];
                let next = if newton > lo && newton < hi {
                    newton
                } else {
                    0.5 * (lo + hi)
                };
                let done = (next - z).abs() <= 4.0 * f64::EPSILON * (1.0 + z.abs());
                z = next;
                if done || hi - lo <= 4.0 * f64::EPSILON * (1.0 + z.abs()) {
                    break;
                }
            }
            roots.push(z);
        }
        roots
    }
}

/// The P + 2 segments of one cycle of `x = |A| xi(theta - phi')` (`phi' = phi`, `+ pi` for
/// `A < 0`) behind a play of half-width b (design.md 9.5), from the top of x around, and the half
/// travel `(max x - min x) / 2`.
///
/// One maximum and one minimum per period: x is monotone between them, so the play output is the
/// sine's rule with the extremes in place of `±a`: descending `xp = min(x_top - b, x + b)`,
/// ascending `xp = max(x_bot + b, x - b)`. Node derivatives `d/d(A, phi, b, lambda)`: at a sample
/// `x_A = xi`, `x_phi = -A xi'`, `x_lambda = A d`; at a reversal `xi' = 0`, so `x_phi = 0` there
/// (the extreme moves with phi but its value does not).
fn distorted_segments(
    amplitude: f64,
    phi: f64,
    b: f64,
    wf: &Waveform,
    p: usize,
) -> Result<(Vec<Segment>, f64)> {
    // x = |A| xi(theta - phi'), phi' = phi (+ pi for A < 0): for a sine the same x as A cos(theta - phi),
    // and the waveform stays the input's whatever the sign convention of (g, phi); d/dA = sgn(A) d/d|A|.
    let sa = sgn(amplitude);
    let (amplitude, phi) = if amplitude < 0.0 {
        (-amplitude, phi + PI)
    } else {
        (amplitude, phi)
    };
    let roots = wf.reversals();
    if roots.len() != 2 {
        return Err(CoreError::InvalidParameter(format!(
            "the input waveform xi = cos + lambda d (lambda = {}) has {} reversals per period; \
             the path loop with a measured waveform supports one maximum and one minimum (a \
             mildly distorted input): the distortion is too strong for this model",
            wf.lambda,
            roots.len()
        )));
    }
    let e = [wf.eval(roots[0]), wf.eval(roots[1])];
    // The top of x = A xi: the larger xi for A > 0, the smaller for A < 0.
    let first_is_top = (amplitude * (e[0][0] - e[1][0])) > 0.0;
    let (zt, zb, et, eb) = if first_is_top {
        (roots[0], roots[1], e[0], e[1])
    } else {
        (roots[1], roots[0], e[1], e[0])
    };
    let xt = amplitude * et[0];
    let xb = amplitude * eb[0];
    let half = 0.5 * (xt - xb);
    if b >= half {
        return Err(CoreError::ZeroAmplitude(format!(
            "play = {b} >= the half travel {half} of the distorted x: no motion reaches the \
             hysteresis and its loop is undetermined; the play must be below it"
        )));
    }
    // Reversal nodes: d/d(A, phi, b, lambda).
    let top = (xt - b, [sa * et[0], 0.0, -1.0, amplitude * et[3]]);
    let bottom = (xb + b, [sa * eb[0], 0.0, 1.0, amplitude * eb[3]]);
    let r = ((phi + zt) / (2.0 * PI)).rem_euclid(1.0);
    let ub = ((zb - zt) / (2.0 * PI)).rem_euclid(1.0);
    let frac = |j: usize| {
        let u = j as f64 / p as f64 - r;
        if u < 0.0 {
            u + 1.0
        } else {
            u
        }
    };
    let j0 = (0..p)
        .min_by(|&i, &k| frac(i).total_cmp(&frac(k)))
        .unwrap_or(0);
    let mut segs = Vec::with_capacity(p + 2);
    let mut prev = top;
    let mut push = |prev: &mut (f64, [f64; 4]), node: (f64, [f64; 4]), s: f64, end: usize| {
        segs.push(Segment {
            dx: node.0 - prev.0,
            ddx: std::array::from_fn(|q| node.1[q] - prev.1[q]),
            s,
            end,
        });
        *prev = node;
    };
    let mut passed_bottom = false;
    for m in 0..p {
        let j = (j0 + m) % p;
        let descending = frac(j) <= ub;
        if !descending && !passed_bottom {
            push(&mut prev, bottom, -1.0, REVERSAL);
            passed_bottom = true;
        }
        let zeta = 2.0 * PI * j as f64 / p as f64 - phi;
        let ev = wf.eval(zeta);
        let x = amplitude * ev[0];
        let dx = [sa * ev[0], -amplitude * ev[1], amplitude * ev[3]];
        let node = if descending {
            if x < xt - 2.0 * b {
                (x + b, [dx[0], dx[1], 1.0, dx[2]])
            } else {
                top
            }
        } else if x > xb + 2.0 * b {
            (x - b, [dx[0], dx[1], -1.0, dx[2]])
        } else {
            bottom
        };
        push(&mut prev, node, if descending { -1.0 } else { 1.0 }, j);
    }
    if !passed_bottom {
        push(&mut prev, bottom, -1.0, REVERSAL);
    }
    push(&mut prev, top, 1.0, REVERSAL);
    Ok((segs, half))
}

/// Pieces of the cycle integrated side by side: piece i is `segs[start[i]..end[i]]`. With
/// `K > 1` the K chains are independent until the pieces are joined, so their `ln`/`exp`
/// latencies overlap (multiple shooting); `K = 1` is plain single shooting.
#[derive(Clone, Copy)]
struct Pieces<const K: usize> {
    start: [usize; K],
    end: [usize; K],
}

impl<const K: usize> Pieces<K> {
    /// K contiguous pieces of `n` segments, as equal as they come.
    fn split(n: usize) -> Self {
        Self {
            start: std::array::from_fn(|i| i * n / K),
            end: std::array::from_fn(|i| (i + 1) * n / K),
        }
    }

    fn longest(&self) -> usize {
        (0..K)
            .map(|i| self.end[i] - self.start[i])
            .max()
            .unwrap_or(0)
    }

    /// Segment `m` of every piece (a dwell `dx = 0` past a piece's end).
    #[inline(always)]
    fn row(&self, segs: &[Segment], m: usize) -> [Segment; K] {
        std::array::from_fn(|i| {
            let k = self.start[i] + m;
            if k < self.end[i] {
                segs[k]
            } else {
                Segment {
                    dx: 0.0,
                    ddx: [0.0; 4],
                    s: 1.0,
                    end: REVERSAL,
                }
            }
        })
    }
}

/// Sensitivities of one RK4 step to `[dx, beta, gamma, mu, delta]` at a fixed step start.
const NQ: usize = 6;

/// One RK4 step of length `hs` in sigma of `dw/dsigma = dx h(w, s)` for K chains side by side
/// (stage by stage, so that the chains' `ln`/`exp` overlap). Returns the new `w`, the step's
/// derivative `R = dw_new/dw` and (`FULL`) its derivatives at fixed `w` to `[dx, beta, gamma,
/// mu, delta]`.
///
/// The derivatives are those of the augmented RK4 (forward sensitivities riding along), summed
/// in reverse: with `k_i = dx h(w_i)`, `a_i = dx dh/dw(w_i)` and `b_i = d k_i/dq` at fixed
/// `w_i`, the weights `l_4 = hs/6`, `l_3 = hs/3 + l_4 a_4 hs`, `l_2 = hs/3 + l_3 a_3 hs/2`,
/// `l_1 = hs/6 + l_2 a_2 hs/2` give `R = 1 + sum l_i a_i` and `dw_new/dq = sum l_i b_i`: the
/// same numbers with five multiplications per parameter instead of a 7-component RK4 state.
#[inline(always)]
fn rk4_step<const K: usize, const FULL: bool>(
    p: &Shape,
    row: &[Segment; K],
    w: &[f64; K],
    hs: f64,
) -> ([f64; K], [f64; K], [[f64; NQ]; K]) {
    let r1: [Rate; K] = std::array::from_fn(|i| rate(p, row[i].s, w[i]));
    let k1: [f64; K] = std::array::from_fn(|i| row[i].dx * r1[i].h);
    let r2: [Rate; K] = std::array::from_fn(|i| rate(p, row[i].s, w[i] + 0.5 * hs * k1[i]));
    let k2: [f64; K] = std::array::from_fn(|i| row[i].dx * r2[i].h);
    let r3: [Rate; K] = std::array::from_fn(|i| rate(p, row[i].s, w[i] + 0.5 * hs * k2[i]));
    let k3: [f64; K] = std::array::from_fn(|i| row[i].dx * r3[i].h);
    let r4: [Rate; K] = std::array::from_fn(|i| rate(p, row[i].s, w[i] + hs * k3[i]));
    let mut wn = [0.0; K];
    let mut rr = [0.0; K];
    let mut inc = [[0.0; NQ]; K];
    for i in 0..K {
        let dx = row[i].dx;
        let k4 = dx * r4[i].h;
        wn[i] = w[i] + hs / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4);
        let rs = [&r1[i], &r2[i], &r3[i], &r4[i]];
        let a = rs.map(|r| dx * r.hw);
        let l4 = hs / 6.0;
        let l3 = hs / 3.0 + l4 * a[3] * hs;
        let l2 = hs / 3.0 + l3 * a[2] * 0.5 * hs;
        let l1 = hs / 6.0 + l2 * a[1] * 0.5 * hs;
        let l = [l1, l2, l3, l4];
        rr[i] = 1.0 + l1 * a[0] + l2 * a[1] + l3 * a[2] + l4 * a[3];
        if FULL {
            let s = row[i].s;
            let mut q = [0.0; NQ];
            for (li, r) in l.iter().zip(rs) {
                // d k/d dx = h; d k/d(beta, gamma, mu, delta) = -dx |w|^mu (s sgn w, 1,
                // ln|w| c, sgn w) P, plus (pinching) dx h_b dP/dw_u dw_u/d(beta, gamma, mu);
                // d k/d zeta1 = dx h_b dP/dzeta1.
                let e = li * dx * r.wmu * r.pf;
                q[0] += li * r.h;
                q[1] -= e * s * r.sw;
                q[2] -= e;
                q[3] -= e * r.lnw * r.c;
                q[4] -= e * r.sw;
                if p.pinched {
                    let f = li * dx * r.hb;
                    let u = f * r.p_wu;
                    q[1] += u * p.dwu[0];
                    q[2] += u * p.dwu[1];
                    q[3] += u * p.dwu[2];
                    q[5] += f * r.p_z;
                }
            }
            inc[i] = q;
        }
    }
    (wn, rr, inc)
}

/// Every piece's map from its start value `v[i]`: `(w_end, dw_end/dv)` per piece, by
/// `substeps` RK4 steps per segment.
fn shoot_pass<const K: usize>(
    p: &Shape,
    segs: &[Segment],
    pc: &Pieces<K>,
    v: &[f64; K],
    substeps: usize,
) -> ([f64; K], [f64; K]) {
    let hs = 1.0 / substeps as f64;
    let (mut w, mut ph) = (*v, [1.0; K]);
    for m in 0..pc.longest() {
        let row = pc.row(segs, m);
        if row.iter().all(|g| g.dx == 0.0) {
            // A dwell (or the end of every piece): the identity.
            continue;
        }
        for _ in 0..substeps {
            let (wn, rr, _) = rk4_step::<K, false>(p, &row, &w, hs);
            w = wn;
            for i in 0..K {
                ph[i] *= rr[i];
            }
        }
    }
    (w, ph)
}

/// Every piece's map with all sensitivities, recording at each sample its `w`, its partials
/// `T_j` at a fixed piece start (into `jac`) and `Phi_j = dw_j/dv` (into `phis`). Returns per
/// piece `(w_end, dw_end/dv, T_end)`.
#[allow(clippy::type_complexity)]
fn full_pass<const K: usize>(
    p: &Shape,
    segs: &[Segment],
    pc: &Pieces<K>,
    v: &[f64; K],
    substeps: usize,
    out: &mut Record<'_>,
) -> ([f64; K], [f64; K], [[f64; N_PD]; K]) {
    let hs = 1.0 / substeps as f64;
    let mut w = *v;
    let mut ph = [1.0; K];
    let mut t = [[0.0; N_PD]; K];
    for m in 0..pc.longest() {
        let row = pc.row(segs, m);
        for _ in 0..substeps {
            let (wn, rr, inc) = rk4_step::<K, true>(p, &row, &w, hs);
            w = wn;
            for i in 0..K {
                // Chain rule through the step: T <- R T + dw_new/dq (through dx for A, phi, b).
                let (ti, q, g) = (&mut t[i], &inc[i], &row[i]);
                for x in ti.iter_mut() {
                    *x *= rr[i];
                }
                ti[PD_AMPLITUDE] += q[0] * g.ddx[0];
                ti[PD_PHI] += q[0] * g.ddx[1];
                ti[PD_PLAY] += q[0] * g.ddx[2];
                ti[PD_DISTORT] += q[0] * g.ddx[3];
                ti[PD_BETA] += q[1];
                ti[PD_GAMMA] += q[2];
                ti[PD_MU] += q[3];
                ti[PD_DELTA] += q[4];
                ti[PD_PINCH] += q[5];
                ph[i] *= rr[i];
            }
        }
        for i in 0..K {
            let end = row[i].end;
            if end != REVERSAL {
                out.w[end] = w[i];
                out.jac[end] = t[i];
                out.phis[end] = ph[i];
            }
        }
    }
    (w, ph, t)
}

/// The output being filled: `w_j`, the partials `T_j` at a fixed piece start, `dw_j/dv`.
struct Record<'a> {
    w: &'a mut [f64],
    jac: &'a mut [[f64; N_PD]],
    phis: &'a mut [f64],
}

/// Newton correction of the piece starts from the joins' residuals `r_i = M_i(v_i) - v_{i+1}`
/// and slopes `m_i`: `delta_{i+1} = m_i delta_i + r_i` around the cycle, closed by
/// `delta_0 = c / (1 - prod m)`. For `K = 1` this is Newton on `W(w_0) - w_0`.
fn newton_steps<const K: usize>(r: &[f64; K], m: &[f64; K]) -> [f64; K] {
    let (mut c, mut prod) = (0.0, 1.0);
    for i in 0..K {
        c = m[i] * c + r[i];
        prod *= m[i];
    }
    let mut d = [0.0; K];
    d[0] = c / (1.0 - prod);
    for i in 0..K - 1 {
        d[i + 1] = m[i] * d[i] + r[i];
    }
    d
}

/// How a shooting ended without a loop.
enum Failure {
    /// Too many updates; the last residual.
    Iterations(f64),
    /// A non-finite value within a cycle.
    Diverged(f64),
    /// Multiple shooting overflowed or took too many steps: retry with single shooting.
    Unsafe,
}

/// Shooting on the piece starts `v` to `sum |r_i| <= tol`, then one pass with every sensitivity
/// at the converged starts, folded into `out` by the chain rule across pieces and around the
/// cycle. For `K = 1` (single shooting) Newton is safeguarded by bisection on
/// `[-bound, bound]`: `g = W(w_0) - w_0` is positive at `-bound` and negative at `bound`
/// (W maps the bracket into itself), so a positive residual raises the lower end; for `K > 1`
/// the iterates are clamped into `[-bound, bound]`. Returns the number of updates.
#[allow(clippy::too_many_arguments)]
fn shoot<const K: usize>(
    p: &Shape,
    segs: &[Segment],
    pc: &Pieces<K>,
    mut v: [f64; K],
    substeps: usize,
    bound: f64,
    max_iter: usize,
    out: &mut Record<'_>,
) -> std::result::Result<usize, Failure> {
    let tol = SHOOT_RTOL * bound;
    let bracketed = K == 1;
    let (mut lo, mut hi) = (-bound, bound);
    let mut iterations = 0;
    let mut full = false;
    loop {
        let (e, m, t) = if full {
            full_pass(p, segs, pc, &v, substeps, out)
        } else {
            let (e, m) = shoot_pass(p, segs, pc, &v, substeps);
            (e, m, [[0.0; N_PD]; K])
        };
        let r: [f64; K] = std::array::from_fn(|i| e[i] - v[(i + 1) % K]);
        let resid: f64 = r.iter().map(|x| x.abs()).sum();
        if !resid.is_finite() {
            let worst = e.iter().copied().fold(
                0.0,
                |a: f64, b| if b.is_finite() { a.max(b.abs()) } else { b },
            );
            return Err(if bracketed {
                Failure::Diverged(worst)
            } else {
                Failure::Unsafe
            });
        }
        if resid <= tol {
            if !full {
                // Converged on a cheap pass: repeat it with the sensitivities (same w).
                full = true;
                continue;
            }
            // dv/dq around the cycle (the same recurrence as the Newton step, with the
            // partials T_end in place of the residuals); then every sample T_j + Phi_j dv_i/dq.
            let mut dv = [[0.0; N_PD]; K];
            for q in 0..N_PD {
                let tq: [f64; K] = std::array::from_fn(|i| t[i][q]);
                let d = newton_steps(&tq, &m);
                for i in 0..K {
                    dv[i][q] = d[i];
                }
            }
            for i in 0..K {
                for seg in &segs[pc.start[i]..pc.end[i]] {
                    if seg.end != REVERSAL {
                        let ph = out.phis[seg.end];
                        for (x, d) in out.jac[seg.end].iter_mut().zip(dv[i]) {
                            *x += ph * d;
                        }
                    }
                }
            }
            return Ok(iterations);
        }
        iterations += 1;
        if iterations > max_iter {
            return Err(if bracketed {
                Failure::Iterations(resid)
            } else {
                Failure::Unsafe
            });
        }
        let d = newton_steps(&r, &m);
        let step = if bracketed {
            if r[0] > 0.0 {
                lo = v[0];
            } else {
                hi = v[0];
            }
            let newton = v[0] + d[0];
            let next = if newton > lo && newton < hi && newton.is_finite() {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let step = next - v[0];
            v[0] = next;
            step.abs()
        } else {
            if !d.iter().all(|x| x.is_finite()) {
                return Err(Failure::Unsafe);
            }
            // |w| <= w_b holds for the loop (a saturated one touches it to rounding), so a
            // step beyond is clamped back, and the residual test decides.
            for i in 0..K {
                v[i] = (v[i] + d[i]).max(-bound).min(bound);
            }
            d.iter().map(|x| x.abs()).fold(0.0, f64::max)
        };
        full = step <= FULL_PASS_STEP * bound;
    }
}

/// The coarse cycle: the fine segments merged, within each piece and each half cycle, into runs
/// of up to `group` and up to `max_dx` of travel (unless one fine segment is longer), each one
/// RK4 segment; returns the segments and the pieces over them.
fn coarse_segments<const K: usize>(
    segs: &[Segment],
    pc: &Pieces<K>,
    group: usize,
    max_dx: f64,
) -> (Vec<Segment>, Pieces<K>) {
    let mut out = Vec::with_capacity(segs.len() / group + 2 * K + 2);
    let mut cp = Pieces {
        start: [0; K],
        end: [0; K],
    };
    for i in 0..K {
        cp.start[i] = out.len();
        let mut k = pc.start[i];
        while k < pc.end[i] {
            let s = segs[k].s;
            let mut dx = 0.0;
            let mut n = 0;
            while k < pc.end[i]
                && segs[k].s == s
                && n < group
                && (n == 0 || (dx + segs[k].dx).abs() <= max_dx)
            {
                dx += segs[k].dx;
                n += 1;
                k += 1;
            }
            out.push(Segment {
                dx,
                ddx: [0.0; 4],
                s,
                end: REVERSAL,
            });
        }
        cp.end[i] = out.len();
    }
    (out, cp)
}

/// Start values by multiple shooting on the coarse cycle from `w = 0` at every piece start,
/// to a Newton step below [`COARSE_STEP`]` w_b` (each iterate clamped into `[-w_b, w_b]`);
/// `None` if it overflows or takes more than [`COARSE_MULTI_MAX_ITER`] steps.
fn coarse_multiple(
    p: &Shape,
    coarse: &[Segment],
    pc: &Pieces<PIECES>,
    bound: f64,
    xp_top: f64,
) -> Option<[f64; PIECES]> {
    // Guess: w ~ xp (slope 1 through the origin, the small loop's limit) clipped to the two
    // saturation levels (the large loop's).
    let upper = (p.beta + p.gamma + p.delta).powf(-1.0 / p.mu);
    let lower = -(p.beta + p.gamma - p.delta).powf(-1.0 / p.mu);
    let mut v = [0.0; PIECES];
    let mut xp = xp_top;
    for i in 0..PIECES {
        v[i] = xp.max(lower).min(upper);
        xp += coarse[pc.start[i]..pc.end[i]]
            .iter()
            .map(|g| g.dx)
            .sum::<f64>();
    }
    if !v.iter().all(|x| x.is_finite()) {
        v = [0.0; PIECES];
    }
    for _ in 0..COARSE_MULTI_MAX_ITER {
        let (e, m) = shoot_pass(p, coarse, pc, &v, COARSE_SUBSTEPS);
        let r: [f64; PIECES] = std::array::from_fn(|i| e[i] - v[(i + 1) % PIECES]);
        let d = newton_steps(&r, &m);
        if !d.iter().all(|x| x.is_finite()) {
            return None;
        }
        // From w = 0 the first steps overshoot where the loop saturates: |w| <= w_b holds for
        // the loop, so clamping keeps the iterate admissible without losing the step's sense.
        for i in 0..PIECES {
            v[i] = (v[i] + d[i]).max(-bound).min(bound);
        }
        if d.iter().all(|x| x.abs() <= COARSE_STEP * bound) {
            return Some(v);
        }
    }
    None
}

/// Start values by bracketed single shooting on the coarse cycle (Newton safeguarded by
/// bisection on `[-w_b, w_b]`, from `w_0 = 0`), then the coarse loop's values at the piece starts.
fn coarse_single(p: &Shape, coarse: &[Segment], pc: &Pieces<PIECES>, bound: f64) -> [f64; PIECES] {
    let whole = Pieces::<1> {
        start: [0],
        end: [coarse.len()],
    };
    let mut lo_hi = (-bound, bound);
    let mut w0 = 0.0;
    for _ in 0..SHOOT_MAX_ITER {
        let (e, m) = shoot_pass(p, coarse, &whole, &[w0], COARSE_SUBSTEPS);
        let g = e[0] - w0;
        if g.abs() <= SHOOT_RTOL * bound || g.is_nan() {
            break;
        }
        if g > 0.0 {
            lo_hi.0 = w0;
        } else {
            lo_hi.1 = w0;
        }
        let newton = w0 + g / (1.0 - m[0]);
        let next = if newton > lo_hi.0 && newton < lo_hi.1 {
            newton
        } else {
            0.5 * (lo_hi.0 + lo_hi.1)
        };
        let step = next - w0;
        w0 = next;
        // Quadratic convergence: the error after this step is about step^2 / w_b, far below
        // the coarse map's own distance to the fine one (>= 1e-9 w_b).
        if step.abs() <= COARSE_STEP * bound {
            break;
        }
    }
    let mut v = [w0; PIECES];
    for i in 1..PIECES {
        let piece = Pieces::<1> {
            start: [pc.start[i - 1]],
            end: [pc.end[i - 1]],
        };
        v[i] = shoot_pass(p, coarse, &piece, &[v[i - 1]], COARSE_SUBSTEPS).0[0];
    }
    v
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
/// `substeps < 1`, a grid above [`crate::steady::MAX_SAMPLES_PER_PERIOD`] /
/// [`crate::steady::MAX_STEPS_PER_PERIOD`];
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
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(args, None, None, samples_per_period, substeps, true)
}

/// [`path_loop`] (or [`path_loop_distorted`], with a `waveform`) with pinching `zeta1` in
/// `[0, 1)`: `h(w, s)` times Foliente's `1 - zeta1 exp(-((w s - q w_u)/(zeta2 w_u))^2)`, `w_u =
/// (beta + gamma)^(-1/mu)`, the shape fixed (`crate::terms::PINCHING_CENTRE`, `PINCHING_WIDTH`).
/// The Jacobian's column [`PD_PINCH`] is `d w / d zeta1`; `zeta1 = 0` is [`path_loop`] to the bit.
///
/// Errors: those of [`path_loop`] / [`path_loop_distorted`], and
/// [`CoreError::InvalidParameter`] for `zeta1` outside `[0, 1)`.
#[allow(clippy::too_many_arguments)]
pub fn path_loop_pinched(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    pinch: f64,
    waveform: Option<&Waveform>,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    finite("zeta1", pinch)?;
    if !(0.0..1.0).contains(&pinch) {
        return Err(CoreError::InvalidParameter(format!(
            "pinching zeta1 = {pinch} must be in [0, 1)"
        )));
    }
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(
        args,
        Some(pinch),
        waveform,
        samples_per_period,
        substeps,
        true,
    )
}

/// [`path_loop`] along `x = A xi(theta - phi)`, a measured input waveform scaled by `lambda`
/// (design.md 9.5): the same loop, the Jacobian's column [`PD_DISTORT`] is `d w / d lambda`.
///
/// Errors: those of [`path_loop`] (with the half travel of x in place of `|A|` for the play),
/// and [`CoreError::InvalidParameter`] for a non-finite or odd-length `harmonics` or a waveform
/// with more than one maximum per period.
#[allow(clippy::too_many_arguments)]
pub fn path_loop_distorted(
    amplitude: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    play: f64,
    phi: f64,
    waveform: &Waveform,
    samples_per_period: usize,
    substeps: usize,
) -> Result<PathLoop> {
    let args = (amplitude, beta, gamma, mu, delta, play, phi);
    path_loop_with(
        args,
        None,
        Some(waveform),
        samples_per_period,
        substeps,
        true,
    )
}

/// The arguments of [`path_loop`]: `(amplitude, beta, gamma, mu, delta, play, phi)`.
type LoopArgs = (f64, f64, f64, f64, f64, f64, f64);

/// [`path_loop`], with the multiple shooting (`multiple`) or bracketed single shooting alone
/// (the fallback, exercised by the tests).
fn path_loop_with(
    args: LoopArgs,
    pinch: Option<f64>,
    waveform: Option<&Waveform>,
    samples_per_period: usize,
    substeps: usize,
    multiple: bool,
) -> Result<PathLoop> {
    let (amplitude, beta, gamma, mu, delta, play, phi) = args;
    check_arguments(args, waveform)?;
    crate::steady::check_grid(samples_per_period, substeps)?;
    let shape = Shape::new(beta, gamma, mu, delta, pinch);
    let p = samples_per_period;
    let (segs, half_travel) = match waveform {
        None => (segments(amplitude, phi, play, p), amplitude.abs()),
        Some(wf) => distorted_segments(amplitude, phi, play, wf, p)?,
    };
    let bound = loop_bound(beta + gamma - delta.abs(), mu)?;

    let mut w = vec![0.0; p];
    let mut jac = vec![[0.0; N_PD]; p];
    // dw_j / dv of each sample (v the start of its piece).
    let mut phis = vec![0.0; p];
    let mut out = Record {
        w: &mut w,
        jac: &mut jac,
        phis: &mut phis,
    };
    // |dh/dw| <= L on |w| <= w_b: it sizes the coarse RK4 steps and the advice on substeps.
    let mut stiffness = mu * bound.powf(mu - 1.0) * (beta.abs() + gamma.abs() + delta.abs());
    if let Some(pinch) = pinch {
        // |d(h_b P)/dw| <= L + max|h_b| max|dP/dw|, max|dP/dw| = zeta1 sqrt(2/e) / (zeta2 w_u).
        let hb_max = 1.0 + bound.powf(mu) * (beta.abs() + gamma.abs() + delta.abs());
        stiffness +=
            hb_max * pinch * (2.0f64 / std::f64::consts::E).sqrt() / (PINCHING_WIDTH * shape.w_u);
    }
    let pieces = Pieces::<PIECES>::split(segs.len());
    let start = Start {
        shape: &shape,
        segs: &segs,
        pieces: &pieces,
        bound,
        stiffness,
    };
    let v = start.values(half_travel - play, multiple);
    let iterations = start
        .solve(v, substeps, multiple, &mut out)
        .map_err(|f| start.not_converged(f, args, substeps))?;
    if !(w.iter().all(|v| v.is_finite()) && jac.iter().flatten().all(|v| v.is_finite())) {
        return Err(CoreError::NonFinite(format!(
            "the path loop or its sensitivities overflowed for A = {amplitude:e}, beta = {beta:e}, \
             gamma = {gamma:e}, mu = {mu}, delta = {delta:e}, play = {play:e}; rescale the data so \
             that the parameters are of moderate size"
        )));
    }
    Ok(PathLoop { w, jac, iterations })
}

/// The checks of [`path_loop`] and [`path_loop_distorted`] on their arguments, in order.
fn check_arguments(args: LoopArgs, waveform: Option<&Waveform>) -> Result<()> {
    let (amplitude, beta, gamma, mu, delta, play, phi) = args;
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
    if let Some(wf) = waveform {
        finite("lambda", wf.lambda)?;
        if wf.harmonics.len() % 2 != 0 || !wf.harmonics.iter().all(|v| v.is_finite()) {
            return Err(CoreError::InvalidParameter(format!(
                "the waveform's harmonics must be finite (re, im) pairs for k = 2, 3, ...; got {} \
                 numbers",
                wf.harmonics.len()
            )));
        }
    } else if play >= amplitude.abs() {
        return Err(CoreError::ZeroAmplitude(format!(
            "play = {play} >= |amplitude| = {}: x never travels past the play, so no motion \
             reaches the hysteresis and its loop is undetermined; the play must be below |A|",
            amplitude.abs()
        )));
    }
    Ok(())
}

/// The bound `w_b = (beta + gamma - |delta|)^(-1/mu)` of the loop: `|w|` stays below the larger
/// of the two saturation levels `(beta + gamma -+ delta)^(-1/mu)`.
///
/// Errors: [`CoreError::InvalidParameter`] when it is not a usable number.
fn loop_bound(margin: f64, mu: f64) -> Result<f64> {
    let bound = (1.0 / margin).powf(1.0 / mu);
    if !(bound.is_finite() && bound > 0.0) {
        return Err(CoreError::InvalidParameter(format!(
            "beta + gamma - |delta| = {margin:e} with mu = {mu}: the loop's bound \
             (beta + gamma - |delta|)^(-1/mu) = {bound:e} is not a usable number; rescale w so \
             that the shape parameters are of moderate size"
        )));
    }
    Ok(bound)
}

/// The shooting problem of one path loop: the fine segments, their pieces, the bound `w_b` and
/// the stiffness `L >= |dh/dw|` on `|w| <= w_b`.
struct Start<'a> {
    shape: &'a Shape,
    segs: &'a [Segment],
    pieces: &'a Pieces<PIECES>,
    bound: f64,
    stiffness: f64,
}

impl Start<'_> {
    /// Start values at the piece starts: shooting on a coarse cycle, the fine segments merged
    /// into about [`COARSE_SEGMENTS`]; multiple shooting from `w = 0` at every piece start (the K
    /// chains overlap) when `multiple`, and should it stray, bracketed single shooting, which
    /// always has a safe step. `xp_top` is the played input at the top of x.
    fn values(&self, xp_top: f64, multiple: bool) -> [f64; PIECES] {
        let group = self.segs.len().div_ceil(COARSE_SEGMENTS).max(1);
        // Coarse RK4 steps of at most COARSE_STIFF / L in x keep the coarse map stable and
        // accurate (RK4 is unstable beyond 2.8 / L) however stiff the loop.
        let max_dx = COARSE_SUBSTEPS as f64 * COARSE_STIFF / self.stiffness;
        let (coarse, coarse_pieces) = coarse_segments(self.segs, self.pieces, group, max_dx);
        match multiple {
            true => coarse_multiple(self.shape, &coarse, &coarse_pieces, self.bound, xp_top),
            false => None,
        }
        .unwrap_or_else(|| coarse_single(self.shape, &coarse, &coarse_pieces, self.bound))
    }

    /// Multiple shooting from the start values `v`; should it stray (or not be asked for),
    /// bracketed single shooting from the first of them, which always has a safe step. Returns
    /// the number of updates; `out` holds the loop.
    fn solve(
        &self,
        v: [f64; PIECES],
        substeps: usize,
        multiple: bool,
        out: &mut Record<'_>,
    ) -> std::result::Result<usize, Failure> {
        let (shape, segs, bound) = (self.shape, self.segs, self.bound);
        let found = if multiple && v.iter().all(|x| x.is_finite() && x.abs() <= bound) {
            shoot(
                shape,
                segs,
                self.pieces,
                v,
                substeps,
                bound,
                MULTI_MAX_ITER,
                out,
            )
        } else {
            Err(Failure::Unsafe)
        };
        if found.is_ok() {
            return found;
        }
        let start = if v[0].is_finite() { v[0] } else { 0.0 };
        let whole = Pieces::<1> {
            start: [0],
            end: [segs.len()],
        };
        shoot(
            shape,
            segs,
            &whole,
            [start],
            substeps,
            bound,
            SHOOT_MAX_ITER,
            out,
        )
    }

    /// The error of a shooting that found no loop: why, and what to change.
    fn not_converged(&self, f: Failure, args: LoopArgs, substeps: usize) -> CoreError {
        let (amplitude, beta, gamma, mu, delta, play, _) = args;
        let (bound, stiffness) = (self.bound, self.stiffness);
        let longest = self.segs.iter().map(|g| g.dx.abs()).fold(0.0, f64::max);
        let why = match f {
            Failure::Diverged(wn) => format!("diverged (w reached {wn:e} within one cycle)"),
            Failure::Iterations(g) => {
                format!("found no periodic loop in {SHOOT_MAX_ITER} iterations (residual {g:.3e})")
            }
            Failure::Unsafe => "left its bracket".to_string(),
        };
        let hint = if longest / substeps as f64 * stiffness > RK4_STABLE {
            format!(
                "its RK4 steps (up to {:.3e} in x) times the loop's stiffness (|dh/dw| up to \
                 {stiffness:.3e}) exceed RK4's stability limit {RK4_STABLE}: raise substeps to at \
                 least {}",
                longest / substeps as f64,
                (longest * stiffness / RK4_STABLE).ceil()
            )
        } else {
            "with beta < 0 the unloading branch runs away at large amplitudes: check the \
             parameters' signs and scale"
                .to_string()
        };
        CoreError::NotConverged(format!(
            "the path-loop shooting {why}, bound {bound:.3e}, for A = {amplitude}, beta = {beta}, \
             gamma = {gamma}, mu = {mu}, delta = {delta}, play = {play}; {hint}"
        ))
    }
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
    fn pinched_jacobian_matches_central_differences_and_zero_pinch_is_the_plain_loop() {
        let sets: [[f64; 8]; 3] = [
            // [beta, gamma, mu, A, phi, delta, b, zeta1]
            [0.7, 0.25, 1.8, 1.4, 0.9, 0.2, 0.15, 0.5],
            [0.9, -0.3, 2.5, -1.1, 2.0, -0.35, 0.05, 0.3],
            [0.5, 0.5, 1.3, 3.0, -1.0, 0.0, 0.5, 0.8],
        ];
        let (p, sub) = (40, 6);
        let run = |q: &[f64; 8]| {
            path_loop_pinched(q[3], q[0], q[1], q[2], q[5], q[6], q[4], q[7], None, p, sub).unwrap()
        };
        for q in sets {
            let base = run(&q);
            let plain = pl(q[3], q[0], q[1], q[2], q[5], q[6], q[4], p, sub);
            let mut zero = q;
            zero[7] = 0.0;
            let z = run(&zero);
            assert_eq!(z.w, plain.w);
            // At zeta1 = 0 the column is still d w / d zeta1 (the diagnosis starts there).
            assert!(z.jac.iter().any(|r| r[PD_PINCH].abs() > 1e-3));
            assert!(base
                .w
                .iter()
                .zip(&plain.w)
                .any(|(a, b)| (a - b).abs() > 1e-3));
            for k in 0..8 {
                let col = if k == 7 { PD_PINCH } else { k };
                let h = 1e-5 * q[k].abs().max(1.0);
                let (mut up, mut dn) = (q, q);
                up[k] += h;
                dn[k] -= h;
                let (lu, ld) = (run(&up), run(&dn));
                for j in 0..p {
                    let fd = (lu.w[j] - ld.w[j]) / (2.0 * h);
                    let an = base.jac[j][col];
                    assert!(
                        (fd - an).abs() < 1e-6 * (1.0 + fd.abs()),
                        "set {q:?}, column {k}, sample {j}: fd {fd} vs {an}"
                    );
                }
            }
        }
        let e =
            path_loop_pinched(1.0, 0.7, 0.3, 1.8, 0.0, 0.0, 0.0, 1.0, None, p, sub).unwrap_err();
        assert!(e.to_string().contains("zeta1"), "{e}");
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
        // Symmetric (delta = 0): both sides saturate at w_b itself, the edge of the shooting's
        // bracket.
        let sym = pl(60.0, beta, gamma, mu, 0.0, 0.0, 0.0, 256, 16);
        let wb = (beta + gamma).powf(-1.0 / mu);
        let max = sym.w.iter().copied().fold(f64::MIN, f64::max);
        let min = sym.w.iter().copied().fold(f64::MAX, f64::min);
        assert!(
            (max - wb).abs() < 1e-9 && (min + wb).abs() < 1e-9,
            "{max} {min} {wb}"
        );
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

    #[test]
    fn multiple_and_single_shooting_find_the_same_loop() {
        // The same discrete fixed point, reached two ways: the joins of the four pieces meet to
        // 1e-13 w_b, so w agrees to a few 1e-13 and the Jacobian to rounding of the chain rule.
        for (args, p) in [
            ((1.4, 0.7, 0.25, 1.8, 0.2, 0.15, 0.9), 64),
            ((-2.5, 0.9, -0.3, 2.5, -0.35, 0.6, 2.0), 37),
            ((0.2, 1.0, 0.2, 1.2, 0.5, 0.0, -1.0), 16),
        ] {
            let m = path_loop_with(args, None, None, p, 4, true).unwrap();
            let s = path_loop_with(args, None, None, p, 4, false).unwrap();
            for j in 0..p {
                assert!((m.w[j] - s.w[j]).abs() < 1e-12, "{args:?} sample {j}");
                for k in 0..7 {
                    let (a, b) = (m.jac[j][k], s.jac[j][k]);
                    assert!(
                        (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                        "{args:?} {j} {k}: {a} {b}"
                    );
                }
            }
        }
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
        // A bound that overflows (denormal margin) is refused, not iterated on.
        let r = path_loop(1.0, 5e-324, 0.0, 3.0, 0.0, 0.0, 0.0, 16, 2);
        assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
        // Parameters at the edge of the float range: an error, never a panic or NaN.
        let r = path_loop(6.1e-96, 4.49e307, 0.0, 4.0, 0.0, 0.0, 0.0, 4, 1);
        assert!(
            matches!(r, Err(CoreError::NonFinite(_) | CoreError::NotConverged(_))),
            "{r:?}"
        );
    }

    #[test]
    fn distorted_waveform_nests_the_sine_and_has_an_exact_lambda_column() {
        // lambda = 0: the reversals land on 0 and pi to rounding, so the loop is the sine's.
        let h = [0.03, -0.02, 0.04, 0.01];
        let wf = |lambda| Waveform {
            lambda,
            harmonics: &h,
        };
        let (p, sub) = (36, 3);
        for a in [1.3, -0.9] {
            let d =
                path_loop_distorted(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, &wf(0.0), p, sub).unwrap();
            let s = path_loop(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, p, sub).unwrap();
            for j in 0..p {
                assert!((d.w[j] - s.w[j]).abs() < 1e-12);
                for q in 0..7 {
                    assert!((d.jac[j][q] - s.jac[j][q]).abs() < 1e-11);
                }
            }
        }
        // d w / d lambda against central differences (as jacobian_matches_central_differences).
        let run = |l: f64| {
            path_loop_distorted(1.4, 0.7, 0.25, 1.8, 0.1, 0.15, 0.9, &wf(l), p, sub).unwrap()
        };
        let base = run(1.0);
        let step = 1e-5;
        let (up, dn) = (run(1.0 + step), run(1.0 - step));
        for j in 0..p {
            let fd = (up.w[j] - dn.w[j]) / (2.0 * step);
            let err = (fd - base.jac[j][PD_DISTORT]).abs() / (1.0 + fd.abs());
            assert!(
                err < 1e-6,
                "sample {j}: {fd} vs {}",
                base.jac[j][PD_DISTORT]
            );
        }
        // Too strong a distortion (extra reversals) is a named refusal, not a wrong loop.
        let strong = [0.0, 0.0, 0.5, 0.0];
        let bad = Waveform {
            lambda: 1.0,
            harmonics: &strong,
        };
        let r = path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 0.0, 0.0, &bad, p, sub);
        assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
    }
}

//! The nodes of one cycle of the path: the P samples and the two reversals of x, ordered from the
//! top, with the play output at each and its derivatives `d/d(A, phi, b, lambda)`; a segment runs
//! from one node to the next.

use super::waveform::Waveform;
use crate::bouc_wen::sgn;
use crate::error::{CoreError, Result};
use std::f64::consts::PI;

/// One segment of the path: from one node to the next.
#[derive(Clone, Copy)]
pub(super) struct Segment {
    /// `xp_end - xp_start`.
    pub(super) dx: f64,
    /// `d dx / d(A, phi, b, lambda)`.
    pub(super) ddx: [f64; 4],
    /// Direction of xp on the segment (`-1` descending half, `+1` ascending).
    pub(super) s: f64,
    /// The sample the segment ends on, or [`REVERSAL`].
    pub(super) end: usize,
}

/// Marks a segment that ends on a reversal of x rather than on a sample.
pub(super) const REVERSAL: usize = usize::MAX;

/// Play output of the sine and its derivatives `d/d(A, phi, b)` at cycle phase `zeta`
/// (`zeta = 0` at the top of x, descending on `[0, pi]`): `x = a cos(zeta)`,
/// `dx/dA = sgn(A) cos(zeta)`, `dx/dphi = a sin(zeta)`.
pub(super) fn play_node(a: f64, sa: f64, b: f64, zeta: f64, descending: bool) -> (f64, [f64; 3]) {
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
pub(super) fn segments(amplitude: f64, phi: f64, b: f64, p: usize) -> Vec<Segment> {
    let a = amplitude.abs();
    let sa = sgn(amplitude);
    // Cycle phase of sample j, as a fraction of the period: u_j = frac(j/P - phi'/(2 pi)), with
    // phi' = phi (+ pi when A < 0, whose top is at theta - phi = pi).
    let shift = if amplitude < 0.0 { 0.5 } else { 0.0 };
    let r = (phi / (2.0 * PI) + shift).rem_euclid(1.0);
    // No lambda here: its derivative is 0 at every node.
    let top = (a - b, [sa, 0.0, -1.0, 0.0]);
    let bottom = (-a + b, [-sa, 0.0, 1.0, 0.0]);
    walk(p, r, 0.5, top, bottom, |_, u, descending| {
        let (xp, d) = play_node(a, sa, b, 2.0 * PI * u, descending);
        (xp, [d[0], d[1], d[2], 0.0])
    })
}

/// A node of the cycle: the play output there and its derivatives `d/d(A, phi, b, lambda)`.
type Node = (f64, [f64; 4]);

/// The P + 2 segments of one cycle, from the top around to the top: the samples in cycle order
/// from the one closest after the top (sample j at the cycle phase `u_j = frac(j/P - r)`, a
/// fraction of the period, descending while `u_j <= ub`), with the bottom between the last
/// descending and the first ascending sample; `node(j, u_j, descending)` is sample j's node.
fn walk(
    p: usize,
    r: f64,
    ub: f64,
    top: Node,
    bottom: Node,
    node: impl Fn(usize, f64, bool) -> Node,
) -> Vec<Segment> {
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
    let mut prev = top;
    let mut push = |prev: &mut Node, node: Node, s: f64, end: usize| {
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
        let u = frac(j);
        let descending = u <= ub;
        if !descending && !passed_bottom {
            push(&mut prev, bottom, -1.0, REVERSAL);
            passed_bottom = true;
        }
        push(
            &mut prev,
            node(j, u, descending),
            if descending { -1.0 } else { 1.0 },
            j,
        );
    }
    if !passed_bottom {
        push(&mut prev, bottom, -1.0, REVERSAL);
    }
    push(&mut prev, top, 1.0, REVERSAL);
    segs
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
pub(super) fn distorted_segments(
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
    let segs = walk(p, r, ub, top, bottom, |j, _, descending| {
        let zeta = 2.0 * PI * j as f64 / p as f64 - phi;
        let ev = wf.eval(zeta);
        let x = amplitude * ev[0];
        let dx = [sa * ev[0], -amplitude * ev[1], amplitude * ev[3]];
        if descending {
            if x < xt - 2.0 * b {
                (x + b, [dx[0], dx[1], 1.0, dx[2]])
            } else {
                top
            }
        } else if x > xb + 2.0 * b {
            (x - b, [dx[0], dx[1], -1.0, dx[2]])
        } else {
            bottom
        }
    });
    Ok((segs, half))
}

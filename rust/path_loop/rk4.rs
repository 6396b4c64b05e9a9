//! The segment maps: RK4 in sigma along each segment with the forward sensitivities summed in
//! reverse, for K pieces of the cycle side by side (cheap passes, and full passes that record every
//! sample's value and partials).

use super::nodes::{Segment, REVERSAL};
use super::rate::{rate, Rate, Shape};
use super::{N_PD, PD_AMPLITUDE, PD_BETA, PD_DELTA, PD_DISTORT, PD_GAMMA, PD_MU, PD_PHI};
use super::{PD_PINCH, PD_PLAY};
use crate::loop_kernel::{rk4_combine, rk4_reverse_weights};

/// Pieces of the cycle integrated side by side: piece i is `segs[start[i]..end[i]]`. With
/// `K > 1` the K chains are independent until the pieces are joined, so their `ln`/`exp`
/// latencies overlap (multiple shooting); `K = 1` is plain single shooting.
#[derive(Clone, Copy)]
pub(super) struct Pieces<const K: usize> {
    pub(super) start: [usize; K],
    pub(super) end: [usize; K],
}

impl<const K: usize> Pieces<K> {
    /// K contiguous pieces of `n` segments, as equal as they come.
    pub(super) fn split(n: usize) -> Self {
        Self {
            start: std::array::from_fn(|i| i * n / K),
            end: std::array::from_fn(|i| (i + 1) * n / K),
        }
    }

    pub(super) fn longest(&self) -> usize {
        (0..K)
            .map(|i| self.end[i] - self.start[i])
            .max()
            .unwrap_or(0)
    }

    /// Segment `m` of every piece (a dwell `dx = 0` past a piece's end).
    #[inline(always)]
    pub(super) fn row(&self, segs: &[Segment], m: usize) -> [Segment; K] {
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
pub(super) const NQ: usize = 6;

/// One RK4 step of length `hs` in sigma of `dw/dsigma = dx h(w, s)` for K chains side by side
/// (stage by stage, so that the chains' `ln`/`exp` overlap). Returns the new `w`, the step's
/// derivative `R = dw_new/dw` and (`FULL`) its derivatives at fixed `w` to `[dx, beta, gamma,
/// mu, delta]`.
///
/// The derivatives are those of the augmented RK4 (forward sensitivities riding along), summed
/// in reverse ([`rk4_reverse_weights`]): with `k_i = dx h(w_i)`, `a_i = dx dh/dw(w_i)` and
/// `b_i = d k_i/dq` at fixed `w_i`, `R = 1 + sum l_i a_i` and `dw_new/dq = sum l_i b_i`: the
/// same numbers with five multiplications per parameter instead of a 7-component RK4 state.
#[inline(always)]
pub(super) fn rk4_step<const K: usize, const FULL: bool>(
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
        wn[i] = rk4_combine(w[i], hs, [k1[i], k2[i], k3[i], k4]);
        let rs = [&r1[i], &r2[i], &r3[i], &r4[i]];
        let a = rs.map(|r| dx * r.hw);
        let l;
        (l, rr[i]) = rk4_reverse_weights(hs, a);
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
pub(super) fn shoot_pass<const K: usize>(
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
pub(super) fn full_pass<const K: usize>(
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
pub(super) struct Record<'a> {
    pub(super) w: &'a mut [f64],
    pub(super) jac: &'a mut [[f64; N_PD]],
    pub(super) phis: &'a mut [f64],
}
